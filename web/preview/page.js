// The irid preview: an exported film (film.json, its two textures and its
// GLSL ES sampler irid_film_es.glsl) on a sphere or torus under a procedural
// environment, and the film's colour chart, in plain WebGL2: the page, its
// controls and the renderer.
//
// One of the preview's classic scripts (web/preview/*.js, loaded by
// index.html in a fixed order: sources, export, meshes, matrices, shaders,
// ggx, page); each adds what it offers to IridWeb.preview and takes what
// it needs from the scripts before it. Classic scripts, not modules, so
// that the page also opens from file://.
(function (ns) {
  'use strict';

  const P = (ns.preview = ns.preview || {});
  const {
    exportSources, isNumber, loadExport, TORUS_MAJOR, TORUS_MINOR, sphereMesh, torusMesh,
    uploadMesh, perspective, lookAt, multiply, invert, FULLSCREEN_VS, BACKGROUND_FS, OBJECT_VS,
    ENVIRONMENT_MAP_FS, PREFILTER_FS, DEPTH_FS, OBJECT_FS, CHART_FS, link, samplerBody, bindFilm,
    bindRough, lobeAlbedo, lobeAlbedoTable, renderTarget, drawInto, makeTexture,
  } = P;

  const ENVIRONMENTS = { sky: 0, studio: 1, white: 2 };
  // A chart view: the quantity (0 R, 1 T) and the side (0 light from the
  // ambient, 1 from the substrate).
  const CHART_VIEW = {
    'chart-r': [0, 0], 'chart-t': [1, 0], 'chart-r-back': [0, 1], 'chart-t-back': [1, 1],
    'chart-r-rough': [2, 0], // F_eff at the roughness control's value (the rough table)
  };
  // The environment maps: the source (mipmapped) and the prefiltered map
  // the rough program reads, equirectangular, RGBA16F.
  const SOURCE_MAP_SIZE = [1024, 512];
  const PREFILTERED_SIZE = [512, 256];
  // The objects: each has its own compiled shader (a software renderer runs
  // an untaken branch's loop too), and the radius of a sphere about the
  // origin that holds it (outside it, no back face can be seen).
  const OBJECTS = { sphere: { kind: 0, radius: 1.0 }, torus: { kind: 1, radius: 1.06 } };

  const $ = (id) => document.getElementById(id);

  function showMessage(text) {
    const box = $('message');
    box.textContent = text;
    box.hidden = false;
    document.body.dataset.state = 'error';
  }

  function hideMessage() {
    $('message').hidden = true;
  }

  function formatList(values, digits) {
    return Array.isArray(values) ? values.map((x) => (isNumber(x) ? x.toFixed(digits) : String(x))).join(' / ') : '—';
  }

  function describe(exp) {
    const f = exp.film;
    const deg = (c) => (Math.acos(Math.min(1, Math.max(-1, c))) * 180) / Math.PI;
    const kinds = (side) => {
      const list = side.charts.map((k) => f.charts[k].kind);
      const bands = list.filter((k) => k === 'band').length;
      return `${bands} band${bands === 1 ? '' : 's'}${list.includes('corner') ? ' and a grazing corner' : ''}`;
    };
    const rows = [
      ['export', exp.label],
      ['white', f.white],
      ['layer', `${f.layer ?? '—'} of ${f.stack && Array.isArray(f.stack.layers) ? f.stack.layers.length : '?'}`],
      ['thickness', `${f.domain.thickness_nm[0]} – ${f.domain.thickness_nm[1]} nm`],
      ['angle', `${deg(f.domain.cos_theta[1]).toFixed(1)}° – ${deg(f.domain.cos_theta[0]).toFixed(1)}°`],
      ['front charts', kinds(f.sides.front)],
      ['texture', `${f.texture.width} × ${f.texture.height}, ${exp.reflectance.kind}`],
      ['sides', f.sides.back === null ? 'front only (no light arrives from the substrate)'
        : f.sides.back.charts[0] === f.sides.front.charts[0] ? 'front and back, the same charts (the stack reads the same)'
          : `front and back (reversed stack: ${kinds(f.sides.back)})`],
      ['opaque', f.opaque ? 'yes (no transmission drawn)' : `no (refraction index ratio ${f.refraction.substrate_over_ambient.toFixed(3)})`],
    ];
    for (const side of ['front', 'back']) {
      const e = f.error && f.error[side];
      if (!e) continue;
      rows.push([`${side}: max ΔE00 R / T`, formatList(e.max_delta_e00, 3)]);
      rows.push([`${side}: mean ΔE00 R / T`, formatList(e.mean_delta_e00, 4)]);
      rows.push([`${side}: max |error| R`, formatList(Array.isArray(e.max_abs) ? e.max_abs.slice(0, 3) : null, 5)]);
      rows.push([`${side}: max |error| T`, formatList(Array.isArray(e.max_abs) ? e.max_abs.slice(3, 6) : null, 5)]);
      if (isNumber(e.points)) rows.push([`${side}: checked at`, `${e.points} points`]);
    }
    if (exp.rough) {
      const e = exp.rough.error;
      const slices = f.rough.slices;
      const charts = Array.isArray(f.rough.charts) ? f.rough.charts.length : null;
      rows.push(['rough table', `${exp.rough.file}, ${exp.rough.width} × ${exp.rough.height}${isNumber(slices) ? `, ${slices} roughness slices` : ''}${isNumber(charts) ? ` of ${charts} charts` : ''}`]);
      if (e) {
        rows.push(['rough: max |error|', formatList(e.max_abs, 5)]);
        rows.push(['rough: max / mean ΔE00', `${isNumber(e.max_delta_e00) ? e.max_delta_e00.toFixed(3) : '—'} / ${isNumber(e.mean_delta_e00) ? e.mean_delta_e00.toFixed(4) : '—'}`]);
        if (e.grazing && isNumber(e.grazing_below_cos)) {
          rows.push([`rough: max |error| below cos θ ${e.grazing_below_cos}`, formatList(e.grazing.max_abs, 5)]);
        }
      }
    } else {
      rows.push(['rough table', 'none (export with --rough)']);
    }
    const info = $('info');
    info.replaceChildren();
    for (const [k, v] of rows) {
      const dt = document.createElement('dt');
      dt.textContent = k;
      const dd = document.createElement('dd');
      dd.textContent = v;
      info.append(dt, dd);
    }
  }

  class Preview {
    constructor(gl) {
      this.gl = gl;
      this.exports = [];
      this.current = null;
      this.yaw = 0.6;
      this.pitch = 0.12;
      this.distance = 4.2;
      this.frames = 0;
      this.pending = false;
      this.meshes = { sphere: uploadMesh(gl, sphereMesh(64, 128)), torus: uploadMesh(gl, torusMesh(TORUS_MAJOR, TORUS_MINOR, 128, 64)) };
      this.empty = gl.createVertexArray();
      this.background = link(gl, FULLSCREEN_VS, BACKGROUND_FS, 'background shader');
      this.depth = link(gl, OBJECT_VS, DEPTH_FS, 'depth shader');
      // Rough films: the environment maps are float render targets.
      this.floatTargets = gl.getExtension('EXT_color_buffer_float') !== null;
      this.environmentProgram = link(gl, FULLSCREEN_VS, ENVIRONMENT_MAP_FS, 'environment map shader');
      this.prefilterProgram = link(gl, FULLSCREEN_VS, PREFILTER_FS, 'prefilter shader');
      this.sourceMaps = {};
      this.prefilter = null;
    }

    /** Compiles the export's programs and uploads its textures once. */
    prepare(exp) {
      if (exp.gpu) return;
      const gl = this.gl;
      const body = samplerBody(exp.sampler);
      const what = `${exp.name}irid_film_es.glsl`;
      const object = {};
      const baseline = {};
      for (const [name, { kind }] of Object.entries(OBJECTS)) {
        object[name] = link(gl, OBJECT_VS, OBJECT_FS(body, false, kind), what);
        baseline[name] = link(gl, OBJECT_VS, OBJECT_FS(body, true, kind), 'baseline shader');
        bindFilm(gl, object[name], exp, what);
      }
      const roughBody = exp.rough ? samplerBody(exp.rough.sampler) : null;
      const roughWhat = exp.rough ? `${exp.name}${exp.rough.shaderFile}` : null;
      const chart = link(gl, FULLSCREEN_VS, CHART_FS(body, roughBody), exp.rough ? `${what} with ${roughWhat}` : what);
      bindFilm(gl, chart, exp, what);
      // The rough programs: compiled only for an export with the rough table;
      // at roughness 0 the page draws with the smooth ones above.
      let objectRough = null;
      if (exp.rough) {
        bindRough(gl, chart, exp, roughWhat);
        objectRough = {};
        for (const [name, { kind }] of Object.entries(OBJECTS)) {
          objectRough[name] = link(gl, OBJECT_VS, OBJECT_FS(body, false, kind, roughBody), `${what} with ${roughWhat}`);
          bindFilm(gl, objectRough[name], exp, what);
          bindRough(gl, objectRough[name], exp, roughWhat);
        }
      }
      const { width, height } = exp.film.texture;
      exp.gpu = {
        object, chart, baseline, objectRough,
        reflectance: makeTexture(gl, width, height, exp.reflectance.data),
        transmittance: makeTexture(gl, width, height, exp.transmittance.data),
        rough: exp.rough ? makeTexture(gl, exp.rough.width, exp.rough.height, exp.rough.data) : null,
      };
    }

    /**
     * Why the roughness control cannot be used with `exp`, or null when it
     * can: an export without the rough table, or a browser that cannot
     * render the float environment maps.
     */
    roughUnavailable(exp) {
      if (!exp.rough) {
        return 'This export has no rough table (film.json "rough" is null): the roughness stays 0. '
          + 'Export it with `irid export STACK --rough` to preview a rough film.';
      }
      if (!this.floatTargets) {
        return 'This browser cannot render to float textures (EXT_color_buffer_float), which the prefiltered environment needs: the roughness stays 0.';
      }
      return null;
    }

    /** The environment `name` as a mipmapped equirectangular map, drawn once. */
    environmentMap(name) {
      if (this.sourceMaps[name]) return this.sourceMaps[name];
      const gl = this.gl;
      const [w, h] = SOURCE_MAP_SIZE;
      const texture = renderTarget(gl, w, h, true);
      drawInto(gl, texture, w, h, () => {
        gl.useProgram(this.environmentProgram);
        gl.uniform2f(this.environmentProgram.uniform('u_resolution'), w, h);
        gl.uniform1i(this.environmentProgram.uniform('u_environment'), ENVIRONMENTS[name]);
        gl.bindVertexArray(this.empty);
        gl.drawArrays(gl.TRIANGLES, 0, 3);
      });
      gl.activeTexture(gl.TEXTURE4);
      gl.bindTexture(gl.TEXTURE_2D, texture);
      gl.generateMipmap(gl.TEXTURE_2D);
      this.sourceMaps[name] = texture;
      return texture;
    }

    /**
     * The environment prefiltered for roughness r (kept for the last
     * environment and roughness asked), with the white lobe's albedo table.
     */
    prefiltered(name, roughness) {
      const p = this.prefilter;
      if (p && p.name === name && p.roughness === roughness) return p;
      const gl = this.gl;
      const source = this.environmentMap(name);
      const [w, h] = PREFILTERED_SIZE;
      const texture = p ? p.texture : renderTarget(gl, w, h, false);
      drawInto(gl, texture, w, h, () => {
        const program = this.prefilterProgram;
        gl.useProgram(program);
        gl.activeTexture(gl.TEXTURE4);
        gl.bindTexture(gl.TEXTURE_2D, source);
        gl.uniform1i(program.uniform('u_source'), 4);
        gl.uniform2f(program.uniform('u_source_size'), SOURCE_MAP_SIZE[0], SOURCE_MAP_SIZE[1]);
        gl.uniform2f(program.uniform('u_resolution'), w, h);
        gl.uniform1f(program.uniform('u_alpha'), roughness * roughness);
        gl.bindVertexArray(this.empty);
        gl.drawArrays(gl.TRIANGLES, 0, 3);
      });
      const albedo = p && p.roughness === roughness ? p.albedo : lobeAlbedoTable(roughness);
      this.prefilter = { name, roughness, texture, albedo };
      return this.prefilter;
    }

    /** Linear RGB of the prefiltered map at direction d (bilinear, as the shader reads it), for tests. */
    prefilteredAt(name, roughness, d) {
      const gl = this.gl;
      const p = this.prefiltered(name, roughness);
      const [w, h] = PREFILTERED_SIZE;
      if (!p.pixels) {
        const fb = gl.createFramebuffer();
        gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
        gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, p.texture, 0);
        p.pixels = new Float32Array(w * h * 4);
        gl.readPixels(0, 0, w, h, gl.RGBA, gl.FLOAT, p.pixels);
        gl.bindFramebuffer(gl.FRAMEBUFFER, null);
        gl.deleteFramebuffer(fb);
      }
      const len = Math.hypot(...d);
      const u = Math.atan2(d[0] / len, -d[2] / len) / (2 * Math.PI) + 0.5;
      const v = Math.acos(Math.max(-1, Math.min(1, d[1] / len))) / Math.PI;
      const x = u * w - 0.5;
      const y = v * h - 0.5;
      const x0 = Math.floor(x);
      const y0 = Math.floor(y);
      const at = (i, j, ch) => p.pixels[((Math.max(0, Math.min(h - 1, j)) * w) + (((i % w) + w) % w)) * 4 + ch];
      return [0, 1, 2].map((ch) => {
        const fx = x - x0;
        const fy = y - y0;
        return (at(x0, y0, ch) * (1 - fx) + at(x0 + 1, y0, ch) * fx) * (1 - fy)
          + (at(x0, y0 + 1, ch) * (1 - fx) + at(x0 + 1, y0 + 1, ch) * fx) * fy;
      });
    }

    controls() {
      return {
        mode: $('mode').value,
        object: $('object').value,
        environment: $('environment').value,
        thicknessMode: $('thickness-mode').value,
        thickness: Number($('thickness').value),
        thicknessMin: Number($('thickness-min').value),
        thicknessMax: Number($('thickness-max').value),
        noiseScale: Number($('noise-scale').value),
        exposure: Number($('exposure').value),
        roughness: $('roughness').disabled ? 0 : Number($('roughness').value),
      };
    }

    camera(aspect) {
      const eye = [
        this.distance * Math.cos(this.pitch) * Math.sin(this.yaw),
        this.distance * Math.sin(this.pitch),
        this.distance * Math.cos(this.pitch) * Math.cos(this.yaw),
      ];
      const viewProj = multiply(perspective((35 * Math.PI) / 180, aspect, 0.1, 100), lookAt(eye, [0, 0, 0], [0, 1, 0]));
      return { eye, viewProj, inverse: invert(viewProj) };
    }

    /** The chart's (thickness, angle) ranges, each pixel centre mapped linearly. */
    chartRanges(exp) {
      const d = exp.film.domain;
      return { thickness: d.thickness_nm, angle: [Math.acos(d.cos_theta[1]), Math.acos(d.cos_theta[0])] };
    }

    /** Draws one frame now, with the current controls. */
    draw(options = {}) {
      const gl = this.gl;
      const exp = this.current;
      if (!exp) return;
      const c = this.controls();
      const canvas = gl.canvas;
      gl.viewport(0, 0, canvas.width, canvas.height);
      gl.activeTexture(gl.TEXTURE0);
      gl.bindTexture(gl.TEXTURE_2D, exp.gpu.reflectance);
      gl.activeTexture(gl.TEXTURE1);
      gl.bindTexture(gl.TEXTURE_2D, exp.gpu.transmittance);
      if (exp.gpu.rough) {
        gl.activeTexture(gl.TEXTURE2);
        gl.bindTexture(gl.TEXTURE_2D, exp.gpu.rough);
      }
      if (c.mode in CHART_VIEW) {
        this.drawChart(exp, c);
      } else {
        this.drawObject(exp, c, options);
      }
      this.frames++;
      document.body.dataset.frames = String(this.frames);
    }

    drawChart(exp, c) {
      const gl = this.gl;
      const canvas = gl.canvas;
      const program = exp.gpu.chart;
      const ranges = this.chartRanges(exp);
      gl.useProgram(program);
      if (program.iridParams) gl.bindBufferBase(gl.UNIFORM_BUFFER, 0, program.iridParams);
      if (program.iridRoughParams) gl.bindBufferBase(gl.UNIFORM_BUFFER, 1, program.iridRoughParams);
      gl.disable(gl.DEPTH_TEST);
      gl.uniform1f(program.uniform('u_roughness'), c.roughness);
      gl.uniform2f(program.uniform('u_resolution'), canvas.width, canvas.height);
      gl.uniform2f(program.uniform('u_chart_thickness_nm'), ranges.thickness[0], ranges.thickness[1]);
      gl.uniform2f(program.uniform('u_chart_angle_rad'), ranges.angle[0], ranges.angle[1]);
      gl.uniform1i(program.uniform('u_quantity'), CHART_VIEW[c.mode][0]);
      gl.uniform1i(program.uniform('u_side'), CHART_VIEW[c.mode][1]);
      gl.bindVertexArray(this.empty);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
    }

    /**
     * The environment, then the object (unless options.objectHidden, a test's
     * reference). From inside the object both faces are drawn (a back face
     * is the film seen from the substrate), after a depth pass so that only
     * the nearest is shaded; from outside, front faces only.
     */
    drawObject(exp, c, options) {
      const gl = this.gl;
      const canvas = gl.canvas;
      const cam = this.camera(canvas.width / canvas.height);
      const env = ENVIRONMENTS[c.environment];
      // A rough film (roughness above 0, never at 0: there the smooth
      // program draws what it always did) reads the prefiltered environment.
      const rough = c.roughness > 0 && !options.baseline && exp.gpu.objectRough;
      const prefilter = rough ? this.prefiltered(c.environment, c.roughness) : null;
      gl.viewport(0, 0, canvas.width, canvas.height);
      gl.disable(gl.DEPTH_TEST);
      gl.useProgram(this.background);
      gl.uniformMatrix4fv(this.background.uniform('u_inverse_view_proj'), false, cam.inverse);
      gl.uniform3fv(this.background.uniform('u_eye'), cam.eye);
      gl.uniform1f(this.background.uniform('u_exposure'), c.exposure);
      gl.uniform1i(this.background.uniform('u_environment'), env);
      gl.bindVertexArray(this.empty);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
      if (options.objectHidden) return;

      const mesh = this.meshes[c.object];
      gl.enable(gl.DEPTH_TEST);
      gl.clear(gl.DEPTH_BUFFER_BIT);
      gl.bindVertexArray(mesh.vao);
      if (this.distance > OBJECTS[c.object].radius) {
        gl.enable(gl.CULL_FACE); // outside: no back face can be seen
      } else {
        gl.disable(gl.CULL_FACE);
        gl.useProgram(this.depth);
        gl.uniformMatrix4fv(this.depth.uniform('u_view_proj'), false, cam.viewProj);
        gl.colorMask(false, false, false, false);
        gl.drawElements(gl.TRIANGLES, mesh.count, gl.UNSIGNED_INT, 0);
        gl.colorMask(true, true, true, true);
        gl.depthFunc(gl.LEQUAL);
      }

      const program = (options.baseline ? exp.gpu.baseline : rough ? exp.gpu.objectRough : exp.gpu.object)[c.object];
      gl.useProgram(program);
      if (program.iridParams) gl.bindBufferBase(gl.UNIFORM_BUFFER, 0, program.iridParams);
      if (rough) {
        gl.bindBufferBase(gl.UNIFORM_BUFFER, 1, program.iridRoughParams);
        gl.activeTexture(gl.TEXTURE3);
        gl.bindTexture(gl.TEXTURE_2D, prefilter.texture);
        gl.uniform1f(program.uniform('u_roughness'), c.roughness);
        gl.uniform1fv(program.uniform('u_lobe_albedo[0]'), prefilter.albedo);
      }
      gl.uniformMatrix4fv(program.uniform('u_view_proj'), false, cam.viewProj);
      gl.uniform3fv(program.uniform('u_eye'), cam.eye);
      gl.uniform1f(program.uniform('u_exposure'), c.exposure);
      gl.uniform1i(program.uniform('u_environment'), env);
      gl.uniform1i(program.uniform('u_thickness_mode'), c.thicknessMode === 'noise' ? 1 : 0);
      gl.uniform1f(program.uniform('u_thickness_nm'), c.thickness);
      gl.uniform2f(program.uniform('u_thickness_range_nm'), Math.min(c.thicknessMin, c.thicknessMax), Math.max(c.thicknessMin, c.thicknessMax));
      gl.uniform1f(program.uniform('u_noise_scale'), c.noiseScale);
      gl.uniform1i(program.uniform('u_opaque'), exp.film.opaque ? 1 : 0);
      gl.uniform1f(program.uniform('u_index_ratio'), exp.film.opaque ? 1 : exp.film.refraction.substrate_over_ambient);
      gl.drawElements(gl.TRIANGLES, mesh.count, gl.UNSIGNED_INT, 0);
      gl.bindVertexArray(null);
      gl.depthFunc(gl.LESS);
    }

    request() {
      if (this.pending) return;
      this.pending = true;
      requestAnimationFrame(() => {
        this.pending = false;
        try {
          this.draw();
        } catch (e) {
          showMessage(e.message);
        }
      });
    }

    select(exp) {
      this.prepare(exp);
      this.current = exp;
      const [tMin, tMax] = exp.film.domain.thickness_nm;
      for (const id of ['thickness', 'thickness-min', 'thickness-max']) {
        const input = $(id);
        input.min = String(tMin);
        input.max = String(tMax);
        input.disabled = tMin === tMax;
      }
      // Without a back side (an opaque film) its charts would show the front's.
      const back = exp.film.sides.back !== null;
      for (const option of $('mode').options) {
        if (option.value.endsWith('-back')) option.disabled = !back;
      }
      if (!back && $('mode').value.endsWith('-back')) $('mode').value = 'object';
      // Roughness: only with the export's rough table, never the smooth film
      // in its place.
      const unavailable = this.roughUnavailable(exp);
      const roughness = $('roughness');
      roughness.disabled = unavailable !== null;
      if (unavailable !== null) roughness.value = '0';
      $('mode').querySelector('option[value="chart-r-rough"]').disabled = unavailable !== null;
      if (unavailable !== null && $('mode').value === 'chart-r-rough') $('mode').value = 'object';
      const note = $('roughness-note');
      note.classList.toggle('unavailable', unavailable !== null);
      note.textContent = unavailable ?? `GGX, α = roughness². Environment light: the prefiltered environment × the white lobe's albedo × F_eff from ${exp.rough.file} `
        + '(irid_film_rough at n·v). The rough table holds light from the ambient: the transmitted light and the view from inside stay smooth.';
      $('thickness').value = String((tMin + tMax) / 2);
      $('thickness-min').value = String(tMin + 0.25 * (tMax - tMin));
      $('thickness-max').value = String(tMin + 0.75 * (tMax - tMin));
      const [cMin, cMax] = exp.film.domain.cos_theta;
      const deg = (x) => ((Math.acos(x) * 180) / Math.PI).toFixed(1);
      $('chart-x').textContent = `x: thickness ${tMin} → ${tMax} nm`;
      $('chart-y').textContent = `y: angle ${deg(cMax)}° (bottom) → ${deg(cMin)}° (top)`;
      describe(exp);
      updateOutputs();
      this.request();
    }
  }

  function updateOutputs() {
    $('thickness-out').value = `${Number($('thickness').value).toFixed(1)} nm`;
    $('thickness-min-out').value = `${Number($('thickness-min').value).toFixed(1)} nm`;
    $('thickness-max-out').value = `${Number($('thickness-max').value).toFixed(1)} nm`;
    $('noise-scale-out').value = Number($('noise-scale').value).toFixed(2);
    $('exposure-out').value = `${Number($('exposure').value).toFixed(2)} EV`;
    $('roughness-out').value = $('roughness').disabled ? 'no table' : Number($('roughness').value).toFixed(3);
    const noise = $('thickness-mode').value === 'noise';
    $('row-thickness').hidden = noise;
    $('row-min').hidden = !noise;
    $('row-max').hidden = !noise;
    $('row-scale').hidden = !noise;
    $('chart-axes').hidden = !($('mode').value in CHART_VIEW);
  }

  function attachOrbit(canvas, preview) {
    let drag = null;
    canvas.addEventListener('pointerdown', (e) => {
      drag = { x: e.clientX, y: e.clientY };
      canvas.setPointerCapture(e.pointerId);
    });
    canvas.addEventListener('pointermove', (e) => {
      if (!drag) return;
      preview.yaw -= (e.clientX - drag.x) * 0.01;
      preview.pitch = Math.max(-1.5, Math.min(1.5, preview.pitch + (e.clientY - drag.y) * 0.01));
      drag = { x: e.clientX, y: e.clientY };
      preview.request();
    });
    const end = () => { drag = null; };
    canvas.addEventListener('pointerup', end);
    canvas.addEventListener('pointercancel', end);
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      // Down to 0.5: inside the sphere, whose inner face is the film seen from the substrate.
      preview.distance = Math.max(0.5, Math.min(12, preview.distance * Math.exp(e.deltaY * 0.001)));
      preview.request();
    }, { passive: false });
  }

  /** Renders `frames` frames, each waited for, and returns milliseconds per frame. */
  function timeFrames(preview, frames, baseline) {
    const gl = preview.gl;
    const pixel = new Uint8Array(4);
    preview.draw({ baseline });
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel); // warm-up, synchronised
    const start = performance.now();
    for (let i = 0; i < frames; i++) {
      preview.yaw += 0.01;
      preview.draw({ baseline });
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    }
    return (performance.now() - start) / frames;
  }

  async function start() {
    document.body.dataset.state = 'loading';
    const canvas = $('canvas');
    const dpr = window.devicePixelRatio || 1;
    canvas.width = Math.round(640 * dpr);
    canvas.height = Math.round(480 * dpr);
    const gl = canvas.getContext('webgl2', { antialias: true, preserveDrawingBuffer: true });
    if (!gl) {
      showMessage('This browser does not offer WebGL2, which the preview needs.\n'
        + 'Try a current Firefox, Chrome, Edge or Safari, with hardware acceleration enabled.');
      return;
    }
    canvas.addEventListener('webglcontextlost', (e) => {
      e.preventDefault();
      showMessage('The WebGL2 context was lost (the GPU was reset or ran out of memory). Reload the page.');
    });
    const preview = new Preview(gl);
    const sources = exportSources();
    if (!sources.length) {
      showMessage('No export to show.\nWrite a preview with `irid preview EXPORT_DIR -o OUT_DIR` and open OUT_DIR/index.html, '
        + 'or serve this folder and add ?export=path/to/export/ to the address.');
      return;
    }
    const loaded = [];
    const failures = [];
    for (const source of sources) {
      try {
        const exp = await loadExport(source);
        preview.prepare(exp);
        loaded.push(exp);
      } catch (e) {
        failures.push(e.message);
      }
    }
    if (!loaded.length) {
      showMessage(`The export cannot be shown:\n${failures.join('\n')}`);
      return;
    }
    preview.exports = loaded;
    const select = $('export');
    for (const [i, exp] of loaded.entries()) {
      const option = document.createElement('option');
      option.value = String(i);
      option.textContent = exp.label;
      select.append(option);
    }
    select.addEventListener('change', () => preview.select(loaded[Number(select.value)]));
    for (const id of ['mode', 'object', 'environment', 'thickness-mode', 'thickness', 'thickness-min', 'thickness-max', 'noise-scale', 'exposure', 'roughness']) {
      $(id).addEventListener('input', () => { updateOutputs(); preview.request(); });
    }
    attachOrbit(canvas, preview);
    preview.select(loaded[0]);
    if (failures.length) {
      showMessage(`Some exports cannot be shown:\n${failures.join('\n')}`);
      $('message').addEventListener('click', hideMessage);
    } else {
      hideMessage();
      document.body.dataset.state = 'ready';
    }

    // For tests and the console: draw now and read the canvas back.
    window.irid = {
      preview,
      draw(options) { preview.draw(options); },
      // options: draw()'s ({ objectHidden: true }: the environment alone).
      pixels(options) {
        preview.draw(options);
        const data = new Uint8Array(canvas.width * canvas.height * 4);
        gl.readPixels(0, 0, canvas.width, canvas.height, gl.RGBA, gl.UNSIGNED_BYTE, data);
        // Rows bottom to top (readPixels order), RGBA8, base64: compact to hand over.
        let text = '';
        for (let i = 0; i < data.length; i += 0x8000) text += String.fromCharCode(...data.subarray(i, i + 0x8000));
        return { width: canvas.width, height: canvas.height, base64: btoa(text) };
      },
      chartRanges() { return preview.chartRanges(preview.current); },
      timeFrames(frames, baseline) { return timeFrames(preview, frames, baseline); },
      // Rough films: the white GGX lobe's albedo as the page computes it, and
      // the prefiltered environment at a direction (linear RGB).
      lobeAlbedo(cos, roughness) { return lobeAlbedo(cos, roughness); },
      lobeAlbedoTable(roughness) { return Array.from(lobeAlbedoTable(roughness)); },
      prefilteredAt(environment, roughness, d) { return preview.prefilteredAt(environment, roughness, d); },
    };
  }

  ns.start = () => start().catch((e) => showMessage(`The preview failed: ${e.message}`));

  ns.start = () => start().catch((e) => showMessage(`The preview failed: ${e.message}`));
  ns.loadExport = loadExport;
})((window.IridWeb = window.IridWeb || {}));
