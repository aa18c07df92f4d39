// The irid preview: its GLSL ES shaders (the environment, its prefiltered
// map, the object, the chart) around the export's sampler, and compiling
// them with the export's uniform arrays bound.
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
    TORUS_MAJOR, TORUS_MINOR, TORUS_TILT,
  } = P;

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

  Object.assign(P, { ALBEDO_NODES, FULLSCREEN_VS, BACKGROUND_FS, OBJECT_VS, ENVIRONMENT_MAP_FS, PREFILTER_FS, DEPTH_FS, OBJECT_FS, CHART_FS, link, samplerBody, bindFilm, bindRough });
})((window.IridWeb = window.IridWeb || {}));
