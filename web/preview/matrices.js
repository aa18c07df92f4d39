// The irid preview: 4 × 4 matrices, column-major as WebGL takes them.
//
// One of the preview's classic scripts (web/preview/*.js, loaded by
// index.html in a fixed order: sources, export, meshes, matrices, shaders,
// ggx, page); each adds what it offers to IridWeb.preview and takes what
// it needs from the scripts before it. Classic scripts, not modules, so
// that the page also opens from file://.
(function (ns) {
  'use strict';

  const P = (ns.preview = ns.preview || {});

  function perspective(fovY, aspect, near, far) {
    const f = 1 / Math.tan(fovY / 2);
    return [f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) / (near - far), -1, 0, 0, (2 * far * near) / (near - far), 0];
  }

  function lookAt(eye, target, up) {
    const sub = (a, b) => a.map((x, i) => x - b[i]);
    const norm = (a) => { const l = Math.hypot(...a); return a.map((x) => x / l); };
    const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    const z = norm(sub(eye, target));
    const x = norm(cross(up, z));
    const y = cross(z, x);
    return [x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0, -dot(x, eye), -dot(y, eye), -dot(z, eye), 1];
  }

  function multiply(a, b) {
    const out = new Array(16).fill(0);
    for (let c = 0; c < 4; c++) {
      for (let r = 0; r < 4; r++) {
        for (let k = 0; k < 4; k++) out[c * 4 + r] += a[k * 4 + r] * b[c * 4 + k];
      }
    }
    return out;
  }

  function invert(m) {
    // Gauss-Jordan on a 4×8 block; the matrices here are well conditioned.
    const a = [];
    for (let r = 0; r < 4; r++) {
      a.push([0, 1, 2, 3].map((c) => m[c * 4 + r]).concat([0, 1, 2, 3].map((c) => (c === r ? 1 : 0))));
    }
    for (let c = 0; c < 4; c++) {
      let pivot = c;
      for (let r = c + 1; r < 4; r++) if (Math.abs(a[r][c]) > Math.abs(a[pivot][c])) pivot = r;
      [a[c], a[pivot]] = [a[pivot], a[c]];
      const p = a[c][c];
      for (let k = 0; k < 8; k++) a[c][k] /= p;
      for (let r = 0; r < 4; r++) {
        if (r === c) continue;
        const f = a[r][c];
        for (let k = 0; k < 8; k++) a[r][k] -= f * a[c][k];
      }
    }
    const out = new Array(16);
    for (let r = 0; r < 4; r++) for (let c = 0; c < 4; c++) out[c * 4 + r] = a[r][4 + c];
    return out;
  }

  Object.assign(P, { perspective, lookAt, multiply, invert });
})((window.IridWeb = window.IridWeb || {}));
