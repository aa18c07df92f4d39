// The irid preview: an exported film (film.json, its two textures and its
// GLSL ES sampler irid_film_es.glsl) on a sphere or torus under a procedural
// environment, and the film's colour chart, in plain WebGL2.
//
// Exports come from `window.IRID_EXPORTS` (embedded by `irid preview` in
// exports.js, which lets the page open from file://) or from `?export=DIR/`
// parameters (fetched; needs the page to be served over http).
//
// A classic script (not a module) so that the page also opens from file://.
(function (ns) {
  'use strict';

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

  // ---------------------------------------------------------------- sources

  function base64ToBytes(text) {
    const bin = atob(text);
    const out = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
    return out;
  }

  /** An export read over http from a folder URL. */
  function fetchedSource(dir) {
    const base = dir.endsWith('/') ? dir : `${dir}/`;
    const get = async (file) => {
      let response;
      try {
        response = await fetch(new URL(base + file, location.href));
      } catch (e) {
        const hint = location.protocol === 'file:'
          ? ' (a page opened from file:// cannot read other files: serve the folder, e.g. `python3 -m http.server`)'
          : '';
        throw new Error(`${base}${file}: cannot be read${hint}`);
      }
      if (!response.ok) throw new Error(`${base}${file}: ${response.status === 404 ? 'not found' : `HTTP ${response.status}`}`);
      return response;
    };
    return {
      name: base,
      label: base.replace(/\/$/, '').split('/').pop() || base,
      async text(file) { return (await get(file)).text(); },
      async bytes(file) { return new Uint8Array(await (await get(file)).arrayBuffer()); },
    };
  }

  /** An export embedded in exports.js: {name, files: {file: {text} | {base64}}}. */
  function embeddedSource(entry) {
    const file = (f) => {
      const item = entry.files && entry.files[f];
      if (!item) throw new Error(`${entry.name}/${f}: not in the embedded export`);
      return item;
    };
    return {
      name: `${entry.name}/`,
      label: entry.name,
      async text(f) {
        const item = file(f);
        return item.text !== undefined ? item.text : new TextDecoder().decode(base64ToBytes(item.base64));
      },
      async bytes(f) {
        const item = file(f);
        return item.base64 !== undefined ? base64ToBytes(item.base64) : new TextEncoder().encode(item.text);
      },
    };
  }

  function exportSources() {
    const params = new URLSearchParams(location.search);
    const dirs = params.getAll('export').filter((d) => d !== '');
    if (dirs.length) return dirs.map(fetchedSource);
    if (Array.isArray(window.IRID_EXPORTS) && window.IRID_EXPORTS.length) {
      return window.IRID_EXPORTS.map(embeddedSource);
    }
    return [];
  }

  // ---------------------------------------------------------------- export

  function isNumber(x) { return typeof x === 'number' && Number.isFinite(x); }

  // film.json by the one reader rule (web/film-json.js), then the fields
  // the page reads beyond it, in the same one-line form.
  function checkFilm(film, where) {
    const file = `${where}film.json`;
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
    const film = ns.readFilmJson(await source.text('film.json'), `${source.name}film.json`);
    checkFilm(film, source.name);
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

  // ---------------------------------------------------------------- shaders

  const HEADER = `#version 300 es
precision highp float;
precision highp int;
precision highp sampler2D;
`;

  const COMMON = `
vec3 irid_encode_srgb(vec3 linear) {
  vec3 c = clamp(linear, 0.0, 1.0);
  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

// A procedural environment: a sky with a sun over a ground plane, a dark
// studio with two soft boxes, or uniform white (where a film shows R + T).
uniform int u_environment;
vec3 irid_environment(vec3 d) {
  if (u_environment == 2) return vec3(1.0);
  if (u_environment == 1) {
    vec3 c = vec3(0.02);
    float box1 = smoothstep(0.08, 0.0, abs(d.x - 0.55)) * smoothstep(0.5, 0.3, abs(d.y - 0.2));
    float box2 = smoothstep(0.05, 0.0, abs(d.z + 0.6)) * smoothstep(0.6, 0.4, abs(d.y - 0.1));
    float top = smoothstep(0.85, 0.95, d.y);
    return c + vec3(4.0) * box1 + vec3(2.5, 2.6, 3.0) * box2 + vec3(0.8) * top;
  }
  vec3 sun = normalize(vec3(0.45, 0.55, 0.7));
  float s = max(dot(d, sun), 0.0);
  vec3 c;
  if (d.y >= 0.0) {
    c = mix(vec3(0.75, 0.85, 1.0), vec3(0.15, 0.35, 0.85), pow(d.y, 0.45));
  } else {
    float checker = mod(floor(d.x / max(-d.y, 0.02) * 2.0) + floor(d.z / max(-d.y, 0.02) * 2.0), 2.0);
    // The checker fades towards the horizon, where it would alias.
    checker = mix(0.5, checker, smoothstep(0.0, -0.12, d.y));
    c = mix(vec3(0.10, 0.09, 0.08), vec3(0.22, 0.20, 0.17), checker) * (0.6 + 0.4 * smoothstep(0.0, -0.4, d.y));
  }
  return c + vec3(1.0, 0.95, 0.85) * (pow(s, 900.0) * 60.0 + pow(s, 16.0) * 0.25);
}
`;

  const FULLSCREEN_VS = `#version 300 es
out vec2 v_ndc;
void main() {
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2)) * 2.0 - 1.0;
  v_ndc = p;
  gl_Position = vec4(p, 0.0, 1.0);
}`;

  const BACKGROUND_FS = `${HEADER}${COMMON}
uniform mat4 u_inverse_view_proj;
uniform vec3 u_eye;
uniform float u_exposure;
in vec2 v_ndc;
out vec4 o_color;
void main() {
  vec4 p = u_inverse_view_proj * vec4(v_ndc, 1.0, 1.0);
  vec3 d = normalize(p.xyz / p.w - u_eye);
  o_color = vec4(irid_encode_srgb(irid_environment(d) * exp2(u_exposure)), 1.0);
}`;

  const OBJECT_VS = `#version 300 es
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_view_proj;
out vec3 v_position;
out vec3 v_normal;
void main() {
  v_position = a_position;
  v_normal = a_normal;
  gl_Position = u_view_proj * vec4(a_position, 1.0);
}`;

  // Classic gradient noise (Perlin 2002: quintic fade, 12 edge gradients),
  // hashed with integer arithmetic so it does not depend on sin() precision.
  const NOISE = `
uint irid_hash(uvec3 p) {
  uint h = p.x * 0x8da6b343u ^ p.y * 0xd8163841u ^ p.z * 0xcb1ab31fu;
  h ^= h >> 16; h *= 0x7feb352du; h ^= h >> 15; h *= 0x846ca68bu; h ^= h >> 16;
  return h;
}
float irid_grad(ivec3 cell, vec3 f) {
  uint h = irid_hash(uvec3(cell)) & 15u;
  float u = h < 8u ? f.x : f.y;
  float v = h < 4u ? f.y : (h == 12u || h == 14u ? f.x : f.z);
  return ((h & 1u) == 0u ? u : -u) + ((h & 2u) == 0u ? v : -v);
}
float irid_perlin(vec3 p) {
  ivec3 i = ivec3(floor(p));
  vec3 f = fract(p);
  vec3 w = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
  float x00 = mix(irid_grad(i, f), irid_grad(i + ivec3(1, 0, 0), f - vec3(1, 0, 0)), w.x);
  float x10 = mix(irid_grad(i + ivec3(0, 1, 0), f - vec3(0, 1, 0)), irid_grad(i + ivec3(1, 1, 0), f - vec3(1, 1, 0)), w.x);
  float x01 = mix(irid_grad(i + ivec3(0, 0, 1), f - vec3(0, 0, 1)), irid_grad(i + ivec3(1, 0, 1), f - vec3(1, 0, 1)), w.x);
  float x11 = mix(irid_grad(i + ivec3(0, 1, 1), f - vec3(0, 1, 1)), irid_grad(i + ivec3(1, 1, 1), f - vec3(1, 1, 1)), w.x);
  return mix(mix(x00, x10, w.y), mix(x01, x11, w.y), w.z);
}
`;

  // Directions and their place on an equirectangular map: u the azimuth
  // (atan(x, -z), seam at +z), v the polar angle from +y (v = 0 up).
  const EQUIRECT = `
const float IRID_PI = 3.14159265358979;
vec2 irid_equirect(vec3 d) {
  return vec2(atan(d.x, -d.z) / (2.0 * IRID_PI) + 0.5, acos(clamp(d.y, -1.0, 1.0)) / IRID_PI);
}
vec3 irid_equirect_dir(vec2 uv) {
  float phi = (uv.x - 0.5) * 2.0 * IRID_PI;
  float theta = uv.y * IRID_PI;
  return vec3(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
}
`;

  // The environment drawn into an equirectangular map (the prefilter's
  // source; mipmapped after).
  const ENVIRONMENT_MAP_FS = `${HEADER}${COMMON}${EQUIRECT}
uniform vec2 u_resolution;
out vec4 o_color;
void main() {
  o_color = vec4(irid_environment(irid_equirect_dir(gl_FragCoord.xy / u_resolution)), 1.0);
}`;

  // The environment prefiltered for a GGX lobe of roughness r (α = r²), the
  // split sum's first factor (Karis 2013): for each direction R, with the
  // normal and the view both R, the mean of the radiance over light
  // directions l drawn from D(h) cos θ_h, weighted by n·l. Each sample reads
  // the source's mip level whose texel covers the sample's share of the
  // lobe's solid angle, plus half a level (filtered importance sampling,
  // Křivánek and Colbert 2008), so few samples give a smooth map: the half
  // level removes the sampling pattern from the sun's highlight for a few
  // per cent there (tools/web/test_web.mjs measures it).
  const PREFILTER_SAMPLES = 256;
  const PREFILTER_FS = `${HEADER}${EQUIRECT}
uniform sampler2D u_source;
uniform vec2 u_source_size;
uniform vec2 u_resolution;
uniform float u_alpha;
out vec4 o_color;
const int SAMPLES = ${PREFILTER_SAMPLES};
float irid_radical_inverse(uint i) {
  i = (i << 16u) | (i >> 16u);
  i = ((i & 0x55555555u) << 1u) | ((i & 0xAAAAAAAAu) >> 1u);
  i = ((i & 0x33333333u) << 2u) | ((i & 0xCCCCCCCCu) >> 2u);
  i = ((i & 0x0F0F0F0Fu) << 4u) | ((i & 0xF0F0F0F0u) >> 4u);
  i = ((i & 0x00FF00FFu) << 8u) | ((i & 0xFF00FF00u) >> 8u);
  return float(i) * 2.3283064365386963e-10;
}
void main() {
  vec3 n = irid_equirect_dir(gl_FragCoord.xy / u_resolution);
  vec3 up = abs(n.y) < 0.999 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
  vec3 tx = normalize(cross(up, n));
  vec3 ty = cross(n, tx);
  float a2 = u_alpha * u_alpha;
  vec3 sum = vec3(0.0);
  float weight = 0.0;
  for (int i = 0; i < SAMPLES; i++) {
    vec2 xi = vec2((float(i) + 0.5) / float(SAMPLES), irid_radical_inverse(uint(i)));
    float cos2 = (1.0 - xi.x) / (1.0 + (a2 - 1.0) * xi.x);
    float cos_h = sqrt(cos2);
    float sin_h = sqrt(max(1.0 - cos2, 0.0));
    float phi = 2.0 * IRID_PI * xi.y;
    vec3 h = tx * (sin_h * cos(phi)) + ty * (sin_h * sin(phi)) + n * cos_h;
    vec3 l = 2.0 * dot(n, h) * h - n;
    float nl = dot(n, l);
    if (nl <= 0.0) continue;
    // pdf of l with v = n: D(h) cos θ_h / (4 v·h) = D / 4.
    float q = 1.0 + (a2 - 1.0) * cos2;
    float pdf = a2 / (IRID_PI * q * q) / 4.0;
    float sample_solid_angle = 1.0 / (float(SAMPLES) * pdf);
    float sin_l = sqrt(max(1.0 - l.y * l.y, 1e-4));
    float texel_solid_angle = 2.0 * IRID_PI * IRID_PI * sin_l / (u_source_size.x * u_source_size.y);
    float lod = max(0.5 * log2(sample_solid_angle / texel_solid_angle) + 0.5, 0.0);
    sum += textureLod(u_source, irid_equirect(l), lod).rgb * nl;
    weight += nl;
  }
  o_color = vec4(sum / weight, 1.0);
}`;

  // The depth pass: the object's nearest face, no colour.
  const DEPTH_FS = `#version 300 es
precision highp float;
out vec4 o_color;
void main() { o_color = vec4(0.0); }`;

  // The frame-time baseline's stand-in for the export's sampler: the same
  // shading with constant R and T, no texture fetch.
  const BASELINE_SAMPLER = `
struct IridFilm { vec3 reflectance; vec3 transmittance; };
IridFilm irid_film(float thickness_nm, float cos_theta, int side) {
  return IridFilm(vec3(0.04) * (1.0 + 1e-9 * thickness_nm), vec3(0.96));
}
`;

  // What the rough program adds: the roughness, the prefiltered environment
  // (equirectangular, texture unit 3) and the white GGX lobe's directional
  // albedo at ALBEDO_NODES + 1 values of cos θ evenly over [0, 1], computed
  // by the page (lobeAlbedo) for the current roughness.
  const ALBEDO_NODES = 64;
  const ROUGH_UNIFORMS = `
uniform float u_roughness;
uniform sampler2D u_prefiltered;
uniform float u_lobe_albedo[${ALBEDO_NODES + 1}];
float irid_lobe_albedo(float c) {
  float x = clamp(c, 0.0, 1.0) * ${ALBEDO_NODES}.0;
  int i = min(int(x), ${ALBEDO_NODES - 1});
  return mix(u_lobe_albedo[i], u_lobe_albedo[i + 1], x - float(i));
}
`;

  // The object (its mesh's normals point out, into the ambient) is shaded on
  // the side the eye sees (gl_FrontFacing: 0, light from the ambient; 1,
  // from the substrate). A film that lets light through has the substrate
  // inside: the transmitted ray refracts in by the ratio of the indices and
  // is followed to INNER_HITS inner surface hits (after two, a ray not
  // totally reflected keeps R1 R2 of the light: 0.2 % through glass at
  // normal incidence), each shaded from the
  // substrate side (the export's back side: total internal reflection past
  // the critical angle), where it refracts out weighted by T and reflects on
  // weighted by R; what is left after the last hit leaves along its ray.
  //
  // With the export's rough sampler (rough, the program the page uses at a
  // roughness above 0), the film seen from the ambient is a GGX lobe of that
  // roughness, lit by the environment alone (the page has no analytic
  // light): the prefiltered radiance about the mirror direction × the white
  // lobe's directional albedo at n·v × F_eff(t, n·v, r) from
  // irid_film_rough (docs/rough.md). The rough table holds light from the
  // ambient only: the transmitted light and the inner faces stay smooth.
  const OBJECT_FS = (sampler, baseline, kind, rough = null) => `${HEADER}${baseline ? BASELINE_SAMPLER : sampler}
${rough ?? ''}
${COMMON}${NOISE}${EQUIRECT}
#define IRID_OBJECT ${kind}
#define IRID_ROUGH ${rough ? 1 : 0}
${rough ? ROUGH_UNIFORMS : ''}
uniform vec3 u_eye;
uniform float u_exposure;
uniform int u_thickness_mode;      // 0 uniform, 1 noise
uniform float u_thickness_nm;
uniform vec2 u_thickness_range_nm; // noise: [min, max]
uniform float u_noise_scale;
uniform bool u_opaque;
uniform float u_index_ratio;       // substrate over ambient
in vec3 v_position;
in vec3 v_normal;
out vec4 o_color;

const int INNER_HITS = 2;
const float TORUS_MAJOR = ${TORUS_MAJOR.toFixed(6)};
const float TORUS_MINOR = ${TORUS_MINOR.toFixed(6)};
const float TORUS_TILT = ${TORUS_TILT.toFixed(6)};

float irid_thickness(vec3 p) {
  if (u_thickness_mode == 0) return u_thickness_nm;
  float k = clamp(0.5 + 0.75 * irid_perlin(p * u_noise_scale), 0.0, 1.0);
  return mix(u_thickness_range_nm.x, u_thickness_range_nm.y, k);
}

// The torus's own frame: the page tilts it about x.
vec3 irid_untilt(vec3 p) {
  float c = cos(TORUS_TILT), s = sin(TORUS_TILT);
  return vec3(p.x, p.y * c + p.z * s, -p.y * s + p.z * c);
}

// The object as a signed distance, negative inside.
float irid_sdf(vec3 p) {
#if IRID_OBJECT == 0
  return length(p) - 1.0;
#else
  vec3 q = irid_untilt(p);
  return length(vec2(length(q.xz) - TORUS_MAJOR, q.y)) - TORUS_MINOR;
#endif
}

vec3 irid_outward(vec3 p) {
#if IRID_OBJECT == 0
  return normalize(p);
#else
  vec2 e = vec2(1e-4, 0.0);
  return normalize(vec3(irid_sdf(p + e.xyy) - irid_sdf(p - e.xyy),
    irid_sdf(p + e.yxy) - irid_sdf(p - e.yxy), irid_sdf(p + e.yyx) - irid_sdf(p - e.yyx)));
#endif
}

// Where a ray inside the object leaves it: in closed form for the sphere,
// by stepping the distance for the torus.
vec3 irid_exit(vec3 p, vec3 d) {
#if IRID_OBJECT == 0
  float b = dot(p, d);
  return p + d * (-b + sqrt(max(b * b - dot(p, p) + 1.0, 0.0)));
#else
  float s = 2e-3;
  for (int i = 0; i < 64; i++) {
    float e = irid_sdf(p + s * d);
    if (e > -1e-4) break;
    s += max(-e, 1e-4);
  }
  return p + s * d;
#endif
}

// The light leaving the object's inside along a ray that entered at p with
// direction d (into the substrate).
vec3 irid_inside(vec3 p, vec3 d) {
  vec3 weight = vec3(1.0);
  vec3 c = vec3(0.0);
  for (int k = 0; k < INNER_HITS; k++) {
    p = irid_exit(p, d);
    vec3 m = irid_outward(p);
    IridFilm film = irid_film(irid_thickness(p), clamp(dot(d, m), 0.0, 1.0), 1);
    vec3 out_dir = refract(d, -m, u_index_ratio);
    if (dot(out_dir, out_dir) > 0.0) c += weight * film.transmittance * irid_environment(out_dir);
    weight *= film.reflectance;
    d = reflect(d, m);
  }
  return c + weight * irid_environment(d);
}

void main() {
  vec3 n = normalize(v_normal);
  int side = gl_FrontFacing ? 0 : 1;
  if (!gl_FrontFacing) n = -n; // the normal on the eye's side
  vec3 v = normalize(u_eye - v_position);
  float cos_theta = clamp(dot(n, v), 0.0, 1.0);
  IridFilm film = irid_film(irid_thickness(v_position), cos_theta, side);
  // Seen from outside, the reflection comes from the ambient and what comes
  // through from the inside; seen from inside (the eye in the substrate),
  // the other way round, the transmitted ray bent out of the substrate.
  vec3 mirrored = reflect(-v, n);
#if IRID_ROUGH
  vec3 c = gl_FrontFacing
    ? irid_lobe_albedo(cos_theta) * irid_film_rough(irid_thickness(v_position), cos_theta, u_roughness)
      * texture(u_prefiltered, irid_equirect(mirrored)).rgb
    : film.reflectance * (u_opaque ? irid_environment(mirrored) : irid_inside(v_position, mirrored));
#else
  vec3 c = film.reflectance * (gl_FrontFacing || u_opaque ? irid_environment(mirrored) : irid_inside(v_position, mirrored));
#endif
  if (!u_opaque) {
    vec3 d = refract(-v, n, gl_FrontFacing ? 1.0 / u_index_ratio : u_index_ratio);
    if (dot(d, d) > 0.0) {
      c += film.transmittance * (gl_FrontFacing ? irid_inside(v_position, d) : irid_environment(d));
    }
  }
  o_color = vec4(irid_encode_srgb(c * exp2(u_exposure)), 1.0);
}`;

  // The chart of one side: thickness along x (left to right, domain min to
  // max), angle along y (bottom to top, acos(cos_max) to acos(cos_min)),
  // each pixel's centre sampled. Output: the linear colour clamped to [0, 1], sRGB-encoded.
  // u_quantity 2 (with the rough sampler): F_eff at u_roughness.
  const CHART_FS = (sampler, rough = null) => `${HEADER}${sampler}
${rough ?? ''}
${COMMON}
#define IRID_ROUGH ${rough ? 1 : 0}
uniform float u_roughness;
uniform vec2 u_resolution;
uniform vec2 u_chart_thickness_nm;
uniform vec2 u_chart_angle_rad;
uniform int u_quantity;
uniform int u_side;
out vec4 o_color;
void main() {
  vec2 p = gl_FragCoord.xy / u_resolution;
  float t = mix(u_chart_thickness_nm.x, u_chart_thickness_nm.y, p.x);
  float theta = mix(u_chart_angle_rad.x, u_chart_angle_rad.y, p.y);
  IridFilm film = irid_film(t, cos(theta), u_side);
  vec3 c = u_quantity == 0 ? film.reflectance : film.transmittance;
#if IRID_ROUGH
  if (u_quantity == 2) c = irid_film_rough(t, cos(theta), u_roughness);
#endif
  o_color = vec4(irid_encode_srgb(c), 1.0);
}`;

  function compile(gl, type, source, what) {
    const shader = gl.createShader(type);
    gl.shaderSource(shader, source);
    gl.compileShader(shader);
    if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS) && !gl.isContextLost()) {
      const log = gl.getShaderInfoLog(shader);
      gl.deleteShader(shader);
      throw new Error(`${what}: does not compile:\n${log}`);
    }
    return shader;
  }

  function link(gl, vs, fs, what) {
    const program = gl.createProgram();
    gl.attachShader(program, compile(gl, gl.VERTEX_SHADER, vs, what));
    gl.attachShader(program, compile(gl, gl.FRAGMENT_SHADER, fs, what));
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS) && !gl.isContextLost()) {
      throw new Error(`${what}: does not link:\n${gl.getProgramInfoLog(program)}`);
    }
    const locations = new Map();
    program.uniform = (name) => {
      if (!locations.has(name)) locations.set(name, gl.getUniformLocation(program, name));
      return locations.get(name);
    };
    return program;
  }

  /** The sampler's own text, ready to paste after the page's #version line. */
  function samplerBody(text) {
    return text.replace(/^\s*#version[^\n]*\n/m, '').replace(/^\s*precision\s+[^\n]*;\s*$/gm, '');
  }

  // The export's uniform array (film.json's uniform_f32, as it is) into the
  // sampler's uniform block, at binding 0 here. Texture units 0 and 1 hold
  // R and T.
  function bindFilm(gl, program, exp, what) {
    gl.useProgram(program);
    const values = new Float32Array(exp.film.uniform_f32);
    const blockIndex = gl.getUniformBlockIndex(program, 'IridParamsBlock');
    if (blockIndex === gl.INVALID_INDEX) throw new Error(`${what}: declares no uniform block IridParamsBlock`);
    const size = gl.getActiveUniformBlockParameter(program, blockIndex, gl.UNIFORM_BLOCK_DATA_SIZE);
    if (size !== values.byteLength) {
      throw new Error(`${what}: its uniform block takes ${size} bytes, film.json's uniform_f32 holds ${values.byteLength}`);
    }
    const buffer = gl.createBuffer();
    gl.bindBuffer(gl.UNIFORM_BUFFER, buffer);
    gl.bufferData(gl.UNIFORM_BUFFER, values, gl.STATIC_DRAW);
    gl.uniformBlockBinding(program, blockIndex, 0);
    program.iridParams = buffer;
    const r = program.uniform('irid_reflectance');
    const t = program.uniform('irid_transmittance');
    if (r === null && t === null) throw new Error(`${what}: declares no sampler irid_reflectance or irid_transmittance`);
    if (r !== null) gl.uniform1i(r, 0);
    if (t !== null) gl.uniform1i(t, 1);
  }

  // The rough table's uniform array (film.json's rough.uniform_f32, as it
  // is) into the rough sampler's block, at binding 1; texture unit 2 holds
  // the rough texture, unit 3 the prefiltered environment.
  function bindRough(gl, program, exp, what) {
    gl.useProgram(program);
    const values = new Float32Array(exp.rough.uniform);
    const blockIndex = gl.getUniformBlockIndex(program, 'IridRoughParamsBlock');
    if (blockIndex === gl.INVALID_INDEX) throw new Error(`${what}: declares no uniform block IridRoughParamsBlock`);
    const size = gl.getActiveUniformBlockParameter(program, blockIndex, gl.UNIFORM_BLOCK_DATA_SIZE);
    if (size !== values.byteLength) {
      throw new Error(`${what}: its uniform block takes ${size} bytes, film.json's rough.uniform_f32 holds ${values.byteLength}`);
    }
    const buffer = gl.createBuffer();
    gl.bindBuffer(gl.UNIFORM_BUFFER, buffer);
    gl.bufferData(gl.UNIFORM_BUFFER, values, gl.STATIC_DRAW);
    gl.uniformBlockBinding(program, blockIndex, 1);
    program.iridRoughParams = buffer;
    const r = program.uniform('irid_rough');
    if (r === null) throw new Error(`${what}: declares no sampler irid_rough`);
    gl.uniform1i(r, 2);
    const env = program.uniform('u_prefiltered');
    if (env !== null) gl.uniform1i(env, 3);
  }

  // ---------------------------------------------------------------- GGX

  /** Gauss–Legendre nodes and weights on [0, 1], n points. */
  function gaussLegendre(n) {
    const x = [];
    const w = [];
    for (let i = 1; i <= n; i++) {
      let z = Math.cos((Math.PI * (i - 0.25)) / (n + 0.5));
      let dp = 1;
      for (let it = 0; it < 100; it++) {
        let p1 = 1;
        let p2 = 0;
        for (let j = 1; j <= n; j++) {
          const p3 = p2;
          p2 = p1;
          p1 = ((2 * j - 1) * z * p2 - (j - 1) * p3) / j;
        }
        dp = (n * (z * p1 - p2)) / (z * z - 1);
        const previous = z;
        z = previous - p1 / dp;
        if (Math.abs(z - previous) < 1e-15) break;
      }
      x.push((1 - z) / 2);
      w.push(1 / ((1 - z * z) * dp * dp));
    }
    return { x, w };
  }
  const GAUSS_48 = gaussLegendre(48);

  /**
   * The directional albedo of a white GGX lobe (α = roughness², height-
   * correlated Smith G2, single scattering; docs/rough.md), irid's
   * lobe_albedo: ∫ D G2 / (4 n·v) dl. Over the microfacet normal h drawn
   * from D(h) cos θ_h (u in [0, 1], tan²θ_h = α² u / (1 − u)) it is
   * ∫ du ∫ dφ/2π G2 (v·h) / (n·v n·h) over the h whose l = 2(v·h)h − v is
   * above the surface: for each u an interval cos φ > K(u) (symmetric about
   * the plane of incidence), so the φ rule runs over that interval alone and
   * the u rule is cut where the interval starts or stops being whole or
   * empty (K = −1, K = 1). Gauss–Legendre, 48 points each way: within 4e-4
   * of irid's at 0–80°, 1.3e-3 at 85° (tools/web/test_web.mjs checks 0–80°).
   */
  function lobeAlbedo(cosV, roughness) {
    const alpha = roughness * roughness;
    if (alpha === 0) return 1;
    const c = Math.min(1 - 1e-9, Math.max(cosV, 1e-4));
    const s = Math.sqrt(1 - c * c);
    const a2 = alpha * alpha;
    const lambda = (cw) => (Math.sqrt(1 + (a2 * Math.max(1 - cw * cw, 0)) / (cw * cw)) - 1) / 2;
    const lambdaV = lambda(c);
    const halfway = (u) => {
      const cos2 = (1 - u) / (1 + (a2 - 1) * u);
      return [Math.sqrt(cos2), Math.sqrt(Math.max(1 - cos2, 0))];
    };
    const bound = (u) => {
      const [ch, sh] = halfway(u);
      return (c * (1 / (2 * ch) - ch)) / (s * sh);
    };
    const cuts = [0, 1];
    for (const target of [-1, 1]) {
      let lo = 1e-12;
      let hi = 1 - 1e-12;
      if ((bound(lo) - target) * (bound(hi) - target) > 0) continue;
      for (let it = 0; it < 60; it++) {
        const mid = (lo + hi) / 2;
        if ((bound(lo) - target) * (bound(mid) - target) <= 0) hi = mid;
        else lo = mid;
      }
      cuts.push((lo + hi) / 2);
    }
    cuts.sort((p, q) => p - q);
    const { x, w } = GAUSS_48;
    let sum = 0;
    for (let p = 0; p + 1 < cuts.length; p++) {
      const [u0, u1] = [cuts[p], cuts[p + 1]];
      for (let i = 0; i < x.length; i++) {
        const u = u0 + (u1 - u0) * x[i];
        const [ch, sh] = halfway(u);
        const k = bound(u);
        if (!(k < 1)) continue;
        const phiMax = k <= -1 ? Math.PI : Math.acos(k);
        let inner = 0;
        for (let j = 0; j < x.length; j++) {
          const vh = s * sh * Math.cos(phiMax * x[j]) + c * ch;
          const nl = 2 * vh * ch - c;
          if (nl <= 0 || vh <= 0) continue;
          inner += (w[j] * (vh / (c * ch))) / (1 + lambdaV + lambda(nl));
        }
        sum += ((u1 - u0) * w[i] * inner * phiMax) / Math.PI;
      }
    }
    return sum;
  }

  /** lobeAlbedo at ALBEDO_NODES + 1 values of cos θ evenly over [0, 1]. */
  function lobeAlbedoTable(roughness) {
    return Float32Array.from({ length: ALBEDO_NODES + 1 }, (_, i) => lobeAlbedo(i / ALBEDO_NODES, roughness));
  }

  /**
   * An RGBA16F texture to render into (equirectangular: repeat in u, clamp
   * in v), with a mip chain when `mipmapped`. Bound on texture unit 4, the
   * page's scratch unit.
   */
  function renderTarget(gl, width, height, mipmapped) {
    const texture = gl.createTexture();
    gl.activeTexture(gl.TEXTURE4);
    gl.bindTexture(gl.TEXTURE_2D, texture);
    const levels = mipmapped ? Math.floor(Math.log2(Math.max(width, height))) + 1 : 1;
    gl.texStorage2D(gl.TEXTURE_2D, levels, gl.RGBA16F, width, height);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, mipmapped ? gl.LINEAR_MIPMAP_LINEAR : gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.REPEAT);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    return texture;
  }

  /** Runs `draw` with `texture` (level 0) as the colour target, then restores the canvas. */
  function drawInto(gl, texture, width, height, draw) {
    const fb = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, texture, 0);
    const status = gl.checkFramebufferStatus(gl.FRAMEBUFFER);
    if (status !== gl.FRAMEBUFFER_COMPLETE) {
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      gl.deleteFramebuffer(fb);
      throw new Error(`cannot render the environment map into an RGBA16F texture (framebuffer status 0x${status.toString(16)})`);
    }
    gl.viewport(0, 0, width, height);
    gl.disable(gl.DEPTH_TEST);
    gl.disable(gl.CULL_FACE);
    draw();
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.deleteFramebuffer(fb);
    gl.viewport(0, 0, gl.canvas.width, gl.canvas.height);
  }

  function makeTexture(gl, width, height, data) {
    const texture = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, texture);
    gl.pixelStorei(gl.UNPACK_FLIP_Y_WEBGL, false);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    // Row 0 of the file is v near 0: uploaded as is, it lands at t = 0.
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA16F, width, height, 0, gl.RGBA, gl.FLOAT, data);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    return texture;
  }

  // ---------------------------------------------------------------- meshes

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

  // ---------------------------------------------------------------- matrices (column-major)

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

  // ---------------------------------------------------------------- page

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
  ns.loadExport = loadExport;
})((window.IridWeb = window.IridWeb || {}));
