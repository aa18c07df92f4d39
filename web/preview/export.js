// The irid preview: reading one export, film.json (by the one reader rule,
// web/film-json.js, and the fields the page reads beyond it), its GLSL ES
// sampler, its textures and its rough table.
//
// One of the preview's classic scripts (web/preview/*.js, loaded by
// index.html in a fixed order: sources, export, meshes, matrices, shaders,
// ggx, page); each adds what it offers to IridWeb.preview and takes what
// it needs from the scripts before it. Classic scripts, not modules, so
// that the page also opens from file://.
(function (ns) {
  'use strict';

  const P = (ns.preview = ns.preview || {});

  function isNumber(x) { return typeof x === 'number' && Number.isFinite(x); }

  // film.json by the one reader rule (web/film-json.js), then the fields
  // the page reads beyond it, in the same one-line form.
  function checkFilm(film, file) {
    ns.checkFilmJson(film, file);
    const fail = (why) => { throw new Error(`${file}: ${why}`); };
    const u = film.uniform_f32;
    if (!Array.isArray(u) || u.length === 0 || u.length % 4 !== 0 || !u.every(isNumber)) {
      fail('uniform_f32 must be an array of numbers, whole vec4s');
    }
    if (!film.charts.every((c) => c && c.params && Object.values(c.params).every(isNumber))) {
      fail('charts must each have numeric params');
    }
    const charts = (side) => side && Array.isArray(side.charts) && side.charts.length > 0
      && side.charts.every((k) => Number.isInteger(k) && k >= 0 && k < film.charts.length);
    if (!charts(film.sides.front) || !(film.sides.back === null || charts(film.sides.back))) {
      fail('sides.front must list its charts, sides.back its charts or be null');
    }
    if (!film.opaque && !(film.refraction && isNumber(film.refraction.substrate_over_ambient)
      && film.refraction.substrate_over_ambient > 0)) {
      fail('refraction.substrate_over_ambient must be a positive number for a film that is not opaque');
    }
  }

  /** The text of a film.json (`file`, for errors), read and checked as the page reads it. */
  function readPreviewFilm(text, file) {
    const film = ns.readFilmJson(text, file);
    checkFilm(film, file);
    return film;
  }

  /**
   * RGBA Float32Array of one texture: from the half-float EXR, which holds
   * the values as the GPU samples them (negative ones, for colours outside
   * the sRGB gamut, included); from the 16-bit PNG only when film.json
   * lists no EXR (PNGs clamp at 0).
   */
  async function loadTexture(source, film, which) {
    const { width, height } = film.texture;
    const png = film.texture.png;
    const exr = film.texture.files && film.texture.files[which];
    let image;
    let data;
    let kind;
    if (!exr && png && png[which]) {
      const file = png[which];
      const scale = png.scale;
      if (!isNumber(scale) || scale <= 0) throw new Error(`${source.name}film.json: texture.png.scale must be a positive number`);
      image = await ns.decodePng16(await source.bytes(file), `${source.name}${file}`);
      data = new Float32Array(image.data.length);
      // texel = PNG value / 65535 × scale, in RGB; A is 1.
      for (let i = 0; i < data.length; i++) data[i] = (i & 3) === 3 ? 1 : (image.data[i] / 65535) * scale;
      kind = `PNG16 (${file})`;
    } else {
      const file = exr;
      if (typeof file !== 'string') throw new Error(`${source.name}film.json: texture.files.${which} is missing`);
      image = await ns.decodeExr(await source.bytes(file), `${source.name}${file}`);
      data = image.data;
      kind = `EXR half (${file})`;
    }
    if (image.width !== width || image.height !== height) {
      throw new Error(`${source.name}${which}: ${image.width}×${image.height} pixels, film.json says ${width}×${height}`);
    }
    for (let i = 0; i < data.length; i++) {
      if (!Number.isFinite(data[i])) throw new Error(`${source.name}${which}: non-finite value at texel ${i >> 2}`);
    }
    return { data, kind };
  }

  async function loadExport(source) {
    const film = readPreviewFilm(await source.text('film.json'), `${source.name}film.json`);
    const sampler = await source.text('irid_film_es.glsl');
    if (!/irid_film\s*\(/.test(sampler)) throw new Error(`${source.name}irid_film_es.glsl: defines no irid_film()`);
    const reflectance = await loadTexture(source, film, 'reflectance');
    const transmittance = await loadTexture(source, film, 'transmittance');
    const rough = await loadRough(source, film);
    return { name: source.name, label: source.label, film, sampler, reflectance, transmittance, rough };
  }

  /**
   * The rough table of an export made with `irid export --rough` (film.json's
   * "rough": F_eff(thickness, cos θ, roughness) for light from the ambient,
   * docs/rough.md): its GLSL ES sampler, texture and uniform array, read by
   * the names and lengths film.json gives. null when the export has none.
   */
  async function loadRough(source, film) {
    const r = film.rough;
    if (r === undefined || r === null) return null;
    const fail = (why) => { throw new Error(`${source.name}film.json: rough.${why}`); };
    if (typeof r !== 'object') fail(' must be an object or null');
    const tex = r.texture;
    if (!tex || typeof tex.file !== 'string' || !Number.isInteger(tex.width) || !Number.isInteger(tex.height)
      || tex.width < 1 || tex.height < 1) {
      fail('texture must name its file and give a positive integer width and height');
    }
    if (tex.file === '' || /[/\\]/.test(tex.file) || tex.file === '..') fail(`texture.file ${JSON.stringify(tex.file)} is not a plain file name`);
    const u = r.uniform_f32;
    if (!Array.isArray(u) || u.length === 0 || u.length % 4 !== 0 || !u.every(isNumber)) {
      fail('uniform_f32 must be an array of numbers, whole vec4s');
    }
    const shaderFile = (Array.isArray(r.shaders) && r.shaders.find((f) => typeof f === 'string' && /_es\.glsl$/.test(f)))
      || 'irid_film_rough_es.glsl';
    const sampler = await source.text(shaderFile);
    if (!/irid_film_rough\s*\(/.test(sampler)) throw new Error(`${source.name}${shaderFile}: defines no irid_film_rough()`);
    const image = await ns.decodeExr(await source.bytes(tex.file), `${source.name}${tex.file}`);
    if (image.width !== tex.width || image.height !== tex.height) {
      throw new Error(`${source.name}${tex.file}: ${image.width}×${image.height} pixels, film.json says ${tex.width}×${tex.height}`);
    }
    for (let i = 0; i < image.data.length; i++) {
      if (!Number.isFinite(image.data[i])) throw new Error(`${source.name}${tex.file}: non-finite value at texel ${i >> 2}`);
    }
    return { sampler, shaderFile, file: tex.file, width: tex.width, height: tex.height, data: image.data, uniform: u, error: r.error ?? null };
  }

  Object.assign(P, { isNumber, loadExport, readPreviewFilm });
})((window.IridWeb = window.IridWeb || {}));
