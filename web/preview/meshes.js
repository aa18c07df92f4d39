// The irid preview: the sphere and the torus, as vertex arrays.
//
// One of the preview's classic scripts (web/preview/*.js, loaded by
// index.html in a fixed order: sources, export, meshes, matrices, shaders,
// ggx, page); each adds what it offers to IridWeb.preview and takes what
// it needs from the scripts before it. Classic scripts, not modules, so
// that the page also opens from file://.
(function (ns) {
  'use strict';

  const P = (ns.preview = ns.preview || {});

  function sphereMesh(stacks, slices) {
    const positions = [];
    const indices = [];
    for (let i = 0; i <= stacks; i++) {
      const phi = (Math.PI * i) / stacks;
      for (let j = 0; j <= slices; j++) {
        const theta = (2 * Math.PI * j) / slices;
        positions.push(Math.sin(phi) * Math.cos(theta), Math.cos(phi), Math.sin(phi) * Math.sin(theta));
      }
    }
    for (let i = 0; i < stacks; i++) {
      for (let j = 0; j < slices; j++) {
        const a = i * (slices + 1) + j;
        const b = a + slices + 1;
        indices.push(a, a + 1, b, b, a + 1, b + 1);
      }
    }
    return { positions, normals: positions.slice(), indices };
  }

  const TORUS_TILT = 1.0; // radians
  const TORUS_MAJOR = 0.72;
  const TORUS_MINOR = 0.34;

  function torusMesh(major, minor, rings, sides) {
    const positions = [];
    const normals = [];
    const indices = [];
    for (let i = 0; i <= rings; i++) {
      const u = (2 * Math.PI * i) / rings;
      for (let j = 0; j <= sides; j++) {
        const v = (2 * Math.PI * j) / sides;
        const n = [Math.cos(v) * Math.cos(u), Math.sin(v), Math.cos(v) * Math.sin(u)];
        const p = [major * Math.cos(u) + minor * n[0], minor * n[1], major * Math.sin(u) + minor * n[2]];
        // Tilted about x so that a camera near the horizon sees the hole.
        const tilt = (w) => [w[0], w[1] * Math.cos(TORUS_TILT) - w[2] * Math.sin(TORUS_TILT), w[1] * Math.sin(TORUS_TILT) + w[2] * Math.cos(TORUS_TILT)];
        normals.push(...tilt(n));
        positions.push(...tilt(p));
      }
    }
    for (let i = 0; i < rings; i++) {
      for (let j = 0; j < sides; j++) {
        const a = i * (sides + 1) + j;
        const b = a + sides + 1;
        indices.push(a, a + 1, b, b, a + 1, b + 1); // counter-clockwise seen from outside
      }
    }
    return { positions, normals, indices };
  }

  function uploadMesh(gl, mesh) {
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    const attribute = (location, values) => {
      const buffer = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
      gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(values), gl.STATIC_DRAW);
      gl.enableVertexAttribArray(location);
      gl.vertexAttribPointer(location, 3, gl.FLOAT, false, 0, 0);
    };
    attribute(0, mesh.positions);
    attribute(1, mesh.normals);
    const indexBuffer = gl.createBuffer();
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, indexBuffer);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, new Uint32Array(mesh.indices), gl.STATIC_DRAW);
    gl.bindVertexArray(null);
    return { vao, count: mesh.indices.length };
  }

  Object.assign(P, { TORUS_TILT, TORUS_MAJOR, TORUS_MINOR, sphereMesh, torusMesh, uploadMesh });
})((window.IridWeb = window.IridWeb || {}));
