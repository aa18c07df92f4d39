// An irid export (`irid export`) on a three.js material: the film's
// reflectance R(thickness, cos θ) weights the material's specular light.
//
// An ES module with no build step; it imports 'three' (and, for the default
// loader, 'three/addons/loaders/EXRLoader.js') through the page's import map,
// as three.js's own add-ons do, and film-json.js from beside it (the
// film.json reader rule). Documented in docs/web.md.
//
// With { rough: true } and an export holding the rough table, the film is on
// a rough surface: R at v·h for analytic lights, F_eff (irid_film_rough_es.glsl
// and rough.exr) for the environment light.
//
// The shading code is the export's own GLSL ES sampler (irid_film_es.glsl),
// pasted in as it is, so a change of the export's mapping reaches this module
// with the export. What the module adds:
//   - textures in file order whatever the loader did: film.json records, per
//     texture, a texel and its mirror image about the middle row
//     (`texture.row_check`); the loaded data is compared with both, and rows a
//     loader flipped (three.js's EXRLoader puts the file's first row last) are
//     put back;
//   - half or float data, as the loader gives it, uploaded as RGBA16F;
//   - cos θ from the view direction, (0, 0, 1) in view space under an
//     orthographic camera, not from the direction to the camera position;
//   - the sampler's uniform block turned into plain uniforms (three.js's
//     built-in materials take no uniform blocks), filled from film.json;
//   - the side of the film from the facing of the surface, whatever the
//     material's side (FrontSide, BackSide, DoubleSide);
//   - the film kept by material.clone().

import * as THREE from 'three';
// The one film.json reader rule (docs/gpu.md), shared with the browser
// preview: a classic script that adds readFilmJson and checkFilmJson to
// globalThis.IridWeb.
import './film-json.js';

const { readFilmJson, checkFilmJson } = globalThis.IridWeb;

/** The film.json version this module reads (docs/gpu.md: version 3, the atlas of bands and corners). */
export const FILM_VERSION = globalThis.IridWeb.FILM_VERSION;

const BLOCK = /layout\s*\(\s*std140\s*\)\s*uniform\s+(\w+)\s*\{([^}]*)\}\s*;/;
const SIGNATURE = /IridFilm\s+irid_film\s*\(([^)]*)\)/;

/** An Error naming where it comes from. */
function fail(where, why) {
  return new Error(`${where}: ${why}`);
}

/**
 * Checks a parsed film.json by the one reader rule (docs/gpu.md, "Reading
 * film.json: the one rule"); returns it. Errors name `where` and the field.
 */
export function checkFilm(film, where = 'film.json') {
  return checkFilmJson(film, where);
}

/** film.json's text, parsed and checked by the rule; errors name `where`. */
export function readFilm(text, where = 'film.json') {
  return readFilmJson(text, where);
}

// ---------------------------------------------------------------------------
// Textures

/** {width, height, data, half} of a loaded texture: a three.js DataTexture or {width, height, data}. */
function pixelsOf(loaded, where) {
  const image = loaded?.isTexture ? loaded.image : loaded;
  const { width, height, data } = image ?? {};
  if (!(width > 0 && height > 0) || !data) throw fail(where, 'not a decoded image ({width, height, data})');
  let half;
  if (data instanceof Float32Array) half = false;
  else if (data instanceof Uint16Array) half = true; // half floats, as EXRLoader's HalfFloatType gives them
  else throw fail(where, `texel data is a ${data.constructor.name}; expected Float32Array (float) or Uint16Array (half float)`);
  if (loaded?.isTexture) {
    const declared = loaded.type === THREE.HalfFloatType ? true : loaded.type === THREE.FloatType ? false : null;
    if (declared !== half) throw fail(where, `texture type ${loaded.type} does not match its ${data.constructor.name} data`);
    if (loaded.format !== undefined && loaded.format !== THREE.RGBAFormat) {
      throw fail(where, 'not RGBA (load EXRs with the loader\'s default RGBA output format)');
    }
  }
  if (data.length !== width * height * 4) throw fail(where, `${data.length} values for ${width} × ${height} RGBA texels`);
  return { width, height, data, half };
}

function rgbAt({ width, data, half }, x, y) {
  const o = (y * width + x) * 4;
  const value = (k) => (half ? THREE.DataUtils.fromHalfFloat(data[o + k]) : data[o + k]);
  return [value(0), value(1), value(2)];
}

const distance = (a, b) => Math.max(...a.map((v, k) => Math.abs(v - b[k])));

/**
 * Whether the loaded rows are in file order (false) or flipped (true), from
 * film.json's row check: the loaded texel at (x, y) equals the file's
 * value there, or its mirror's. Throws when it equals neither.
 */
export function rowsFlipped(pixels, check, where) {
  if (check === null) return false; // a single row
  const { x, y, value, mirrored } = check;
  const gap = distance(value, mirrored);
  if (gap === 0) return false; // symmetric: both orders are the same texture
  const found = rgbAt(pixels, x, y);
  // The loaded values are the file's f16 values (exact in half and float),
  // so the nearer candidate is at distance 0; a quarter of the gap leaves
  // room for a texture re-encoded at another precision.
  if (distance(found, value) <= gap / 4) return false;
  if (distance(found, mirrored) <= gap / 4) return true;
  throw fail(where, `texel (${x}, ${y}) holds ${found.map((v) => v.toPrecision(5)).join(', ')}, but film.json says `
    + `${value.join(', ')} (rows in file order) or ${mirrored.join(', ')} (flipped): not this export's texture`);
}

function flipRows({ width, height, data }) {
  const out = new data.constructor(data.length);
  const row = width * 4;
  for (let y = 0; y < height; y++) out.set(data.subarray(y * row, (y + 1) * row), (height - 1 - y) * row);
  return out;
}

/**
 * A loaded texture as the sampler needs it: a DataTexture with rows in file
 * order (row 0 at v = 0), RGBA16F, linear filtering, clamp to edge, no
 * mipmaps, no colour conversion. `loaded` is a three.js DataTexture (e.g.
 * from EXRLoader, half or float) or {width, height, data: Float32Array}
 * (e.g. IridWeb.decodeExr from web/exr.js). Returns {texture, flipped,
 * pixels} (pixels: the loaded data as given).
 */
export function filmTexture(film, quantity, loaded, where = film.texture.files?.[quantity] ?? quantity) {
  const pixels = pixelsOf(loaded, where);
  if (pixels.width !== film.texture.width || pixels.height !== film.texture.height) {
    throw fail(where, `${pixels.width} × ${pixels.height} texels, film.json says ${film.texture.width} × ${film.texture.height}`);
  }
  const flipped = rowsFlipped(pixels, film.texture.row_check[quantity], where);
  return { texture: dataTexture(pixels, flipped), flipped, pixels };
}

/** A DataTexture of `pixels` in file order (rows put back when `flipped`), RGBA16F, linear, clamp, no mipmaps. */
function dataTexture(pixels, flipped) {
  const data = flipped ? flipRows(pixels) : pixels.data;
  const type = pixels.half ? THREE.HalfFloatType : THREE.FloatType;
  const texture = new THREE.DataTexture(data, pixels.width, pixels.height, THREE.RGBAFormat, type);
  texture.internalFormat = 'RGBA16F'; // filterable in every WebGL2, from half or float data
  texture.minFilter = THREE.LinearFilter;
  texture.magFilter = THREE.LinearFilter;
  texture.wrapS = THREE.ClampToEdgeWrapping;
  texture.wrapT = THREE.ClampToEdgeWrapping;
  texture.generateMipmaps = false;
  texture.flipY = false;
  texture.colorSpace = THREE.NoColorSpace; // linear data
  texture.userData.iridFilm = true; // made here: addIridFilm binds it as it is
  texture.needsUpdate = true;
  return texture;
}

/**
 * Whether the loaded rough texture's rows are flipped, by film.json's
 * rough.texture.row_check (as the reflectance texture's own). An export
 * that gives none is read in the reflectance texture's row order, the same
 * loader on the same kind of file.
 */
function roughRowsFlipped(film, rough, reflectance, where) {
  const check = film.rough.texture.row_check;
  if (check !== undefined && check !== null) return rowsFlipped(rough, check, where);
  return reflectance.flipped;
}

/**
 * The rough texture as irid_film_rough needs it (a DataTexture, rows in file
 * order, as filmTexture makes). `reflectance` is {pixels, flipped} of the
 * export's reflectance texture loaded by the same route.
 */
export function roughTexture(film, loaded, reflectance, where = film.rough?.texture?.file ?? 'rough') {
  if (!film.rough) throw fail(where, 'film.json has no rough table (export the film with irid export --rough)');
  const pixels = pixelsOf(loaded, where);
  const { width, height } = film.rough.texture;
  if (pixels.width !== width || pixels.height !== height) {
    throw fail(where, `${pixels.width} × ${pixels.height} texels, film.json says ${width} × ${height}`);
  }
  const flipped = roughRowsFlipped(film, pixels, reflectance, where);
  return { texture: dataTexture(pixels, flipped), flipped };
}

// ---------------------------------------------------------------------------
// Loading an export folder

async function fetchOk(url) {
  let response;
  try {
    response = await fetch(url);
  } catch (e) {
    throw fail(url, `cannot be read (${e.message})`);
  }
  if (!response.ok) throw fail(url, `HTTP ${response.status}`);
  return response;
}

async function fetchText(url) {
  return (await fetchOk(url)).text();
}

/** A three.js EXRLoader (half float, its default), imported on first use. */
async function defaultLoader() {
  let module;
  try {
    module = await import('three/addons/loaders/EXRLoader.js');
  } catch (e) {
    throw new Error(`cannot import three/addons/loaders/EXRLoader.js (map "three/addons/" in the page's import map, or pass a loader or decode): ${e.message}`);
  }
  return new module.EXRLoader();
}

/**
 * The texture at `file`, through `decode` (bytes → {width, height, data})
 * or else the three.js loader `source`. A failure of either (a truncated
 * or damaged file: "unexpected EOF", "invalid distance") names the file.
 */
async function loadTextureFile(file, source, decode) {
  try {
    return decode
      ? await decode(new Uint8Array(await (await fetchOk(file)).arrayBuffer()), file)
      : await source.loadAsync(file);
  } catch (e) {
    const message = e instanceof Error ? e.message : String(e);
    throw message.startsWith(`${file}:`) ? e : fail(file, message);
  }
}

/**
 * Reads an export folder at `url` (ending in '/'): film.json, the GLSL ES
 * sampler and both EXR textures, and, when film.json has the rough table
 * (`irid export --rough`), irid_film_rough_es.glsl and rough.exr; returns
 * what `addIridFilm` takes ({film, sampler, reflectance, transmittance,
 * rough}, rough null without the table). Every error names the file.
 *
 * options.loader: a three.js loader with loadAsync (default: EXRLoader,
 *   half float); options.decode: instead, an async function (bytes, name) →
 *   {width, height, data}, e.g. IridWeb.decodeExr from web/exr.js.
 */
export async function loadIridFilm(url, { loader, decode } = {}) {
  const filmFile = `${url}film.json`;
  const film = readFilm(await fetchText(filmFile), filmFile);
  const sampler = await fetchText(`${url}irid_film_es.glsl`);
  const files = film.texture.files;
  if (!files) throw fail(filmFile, 'texture.files lists no EXR textures');
  const source = decode ? null : loader ?? (await defaultLoader());
  const load = async (quantity) => {
    if (typeof files[quantity] !== 'string') throw fail(filmFile, `texture.files.${quantity} must name a file`);
    const file = `${url}${files[quantity]}`;
    return filmTexture(film, quantity, await loadTextureFile(file, source, decode), file);
  };
  const [reflectance, transmittance] = await Promise.all([load('reflectance'), load('transmittance')]);
  let rough = null;
  if (film.rough) {
    // The rough table (irid export --rough): F_eff and its sampler.
    const shaders = film.rough.shaders ?? [];
    const shaderFile = shaders.find((f) => typeof f === 'string' && f.endsWith('_es.glsl')) ?? 'irid_film_rough_es.glsl';
    const roughSampler = await fetchText(`${url}${shaderFile}`);
    if (typeof film.rough.texture?.file !== 'string') throw fail(filmFile, 'rough.texture.file must name the rough table\'s texture');
    const file = `${url}${film.rough.texture.file}`;
    const loaded = await loadTextureFile(file, source, decode);
    rough = { sampler: roughSampler, ...roughTexture(film, loaded, reflectance, file) };
  }
  return { film, sampler, reflectance, transmittance, rough };
}

// ---------------------------------------------------------------------------
// The material

const DECLARATION = /(\w+)\s+(\w+)\s*(?:\[\s*(\d+)\s*\])?\s*;/g;

/** The declarations `type name[count];` in `text` as [{type, name, count}] (count null for no array). */
function declarations(text) {
  return [...text.matchAll(DECLARATION)].map(([, type, name, count]) => ({ type, name, count: count ? Number(count) : null }));
}

/** The struct types the sampler declares: name → their fields. */
function structs(code) {
  return new Map([...code.matchAll(/struct\s+(\w+)\s*\{([^}]*)\}/g)].map((m) => [m[1], declarations(m[2])]));
}

/**
 * The value three.js uploads for a uniform of `type` (an array of `count`
 * when count is not null) named `name`, from film.json: a float by name
 * from `params`, an array of vec4 from `uniform_f32` (the packed uniform
 * array as film.json gives it), a struct field by field.
 */
function uniformValue(values, types, { type, name, count }) {
  if (types.has(type) && count === null) {
    return Object.fromEntries(types.get(type).map((field) => [field.name, uniformValue(values, types, field)]));
  }
  if (type === 'float' && count === null) {
    const v = values.params?.[name];
    if (typeof v !== 'number') throw fail('film.json', `${values.prefix}params has no number "${name}", which the sampler reads`);
    return v;
  }
  if (type === 'vec4' && count !== null) {
    const packed = values.uniform_f32;
    if (!Array.isArray(packed) || packed.length !== 4 * count) {
      throw fail('film.json', `${values.prefix}uniform_f32 must hold ${4 * count} numbers for the sampler's vec4 ${name}[${count}]`);
    }
    return Array.from({ length: count }, (_, i) => new THREE.Vector4().fromArray(packed, 4 * i));
  }
  throw fail(values.file, `the uniform block holds ${type} ${name}${count === null ? '' : `[${count}]`}, which this module cannot fill`);
}

/**
 * The sampler with its uniform block replaced by plain uniforms (three.js's
 * built-in materials take no uniform blocks), and their values from
 * film.json: `values` is {uniform_f32, params, prefix, file}, film.json's
 * top level for irid_film (prefix '') or its "rough" for irid_film_rough
 * (prefix 'rough.'); the array's length is the sampler's own.
 */
function unblock(sampler, values) {
  const block = sampler.match(BLOCK);
  if (!block) throw fail(values.file, 'no std140 uniform block found');
  const types = structs(sampler);
  const members = declarations(block[2]);
  const uniforms = Object.fromEntries(members.map((m) => [m.name, { value: uniformValue(values, types, m) }]));
  const plain = members.map(({ type, name, count }) => `uniform ${type} ${name}${count === null ? '' : `[${count}]`};`);
  const code = sampler
    .replace(/^\s*precision\s+[^\n]*;\s*$/gm, '') // three.js declares precision itself
    .replace(BLOCK, plain.join('\n'));
  return { code, uniforms };
}

/** The literal of `value` in GLSL type `type` (a side index: float, int or uint). */
function literal(type, value) {
  if (type === 'float') return value.toFixed(1);
  if (type === 'int') return String(value);
  if (type === 'uint') return `${value}u`;
  throw fail('irid_film_es.glsl', `irid_film's side parameter is a ${type}; expected float, int or uint`);
}

/**
 * How the material's shader calls irid_film. A sampler that takes the side
 * of the film (0: light from the ambient, the front; 1: from the substrate)
 * gets it from IRID_FROM_AMBIENT (FACING, below): the film is seen from the
 * ambient on a geometric front face, from the substrate on a back face.
 */
function filmCall(sampler) {
  const m = sampler.match(SIGNATURE);
  if (!m) throw fail('irid_film_es.glsl', 'declares no IridFilm irid_film(...)');
  const types = m[1].split(',').map((p) => p.trim().split(/\s+/).slice(-2, -1)[0]);
  if (types.length === 2) return 'irid_film(irid_thickness_nm, irid_cos)';
  if (types.length === 3) {
    return `irid_film(irid_thickness_nm, irid_cos, IRID_FROM_AMBIENT ? ${literal(types[2], 0)} : ${literal(types[2], 1)})`;
  }
  throw fail('irid_film_es.glsl', `irid_film takes ${types.length} parameters; this module knows 2 (thickness, cos θ) and 3 (and the side)`);
}

// Whether the fragment is on a geometric front face (its mesh normal
// towards the eye), the film seen from the ambient. For side: BackSide
// three.js turns the GL front face round (gl.frontFace(CW), or back for a
// mirrored object), so gl_FrontFacing is true on the back faces it draws,
// and defines FLIP_SIDED; FrontSide and DoubleSide keep it, so there
// gl_FrontFacing is the geometric facing. three.js turns the shading
// normal towards the eye in all three.
const FACING = `
#ifdef FLIP_SIDED
#define IRID_FROM_AMBIENT ( ! gl_FrontFacing )
#else
#define IRID_FROM_AMBIENT gl_FrontFacing
#endif`;

/**
 * three.js's physical lighting with the film as the Fresnel term of
 * BRDF_GGX (the specular of every analytic light): the film's R at
 * cos = v·h, the microfacet's own angle, exact for that light and view
 * (docs/rough.md). `call` is irid_film's call at (irid_thickness_nm,
 * irid_cos); here the cosine is v·h.
 */
function roughLights(call) {
  const chunk = THREE.ShaderChunk.lights_physical_pars_fragment;
  const start = chunk.indexOf('vec3 BRDF_GGX(');
  const fresnel = 'vec3 F = F_Schlick( f0, f90, dotVH );';
  const at = chunk.indexOf(fresnel, start);
  if (start < 0 || at < 0) throw new Error('three.js\'s BRDF_GGX has no `F = F_Schlick( f0, f90, dotVH )`: this three.js is not one irid-three.mjs knows');
  const film = call.replace('irid_cos', 'dotVH');
  return `${chunk.slice(0, at)}vec3 F = F_Schlick( f0, f90, dotVH ) * ${film}.reflectance;${chunk.slice(at + fresnel.length)}`;
}

function hash(text) {
  let h = 0;
  for (let i = 0; i < text.length; i++) h = (Math.imul(h, 31) + text.charCodeAt(i)) | 0;
  return (h >>> 0).toString(16);
}

function replaceChunk(text, chunk, replacement) {
  if (!text.includes(chunk)) throw new Error(`three.js shader has no ${chunk}`);
  return text.replace(chunk, replacement);
}

// The materials that have a film, and what addIridFilm made for each:
// {uniforms, given, options}. Not in userData, which material.copy() and
// clone() copy as JSON: a copy has no film until addIridFilm gives it one.
const FILMS = new WeakMap();

/**
 * The texture to bind for `quantity`: filmTexture's own ({texture,
 * flipped}) as it is; a texture loaded any other way (a plain EXRLoader's
 * DataTexture, whose rows are upside down, or {width, height, data})
 * through filmTexture, which reads film.json's row check and puts flipped
 * rows back. Returns {texture, flipped}.
 */
function boundTexture(film, quantity, given) {
  if (given?.texture?.userData?.iridFilm) return given;
  if (given?.userData?.iridFilm) return { texture: given, flipped: false };
  return filmTexture(film, quantity, given);
}

/** The rough texture to bind, as boundTexture does for the film's own. */
function boundRoughTexture(film, given, reflectance) {
  if (given?.texture?.userData?.iridFilm) return given.texture;
  if (given?.userData?.iridFilm) return given;
  return roughTexture(film, given, reflectance).texture;
}

/** The rough sampler's code and uniforms (irid_film_rough and the material's roughness). */
function roughProgram(film, rough, reflectance, material) {
  const unblocked = unblock(rough.sampler, { ...film.rough, prefix: 'rough.', file: 'irid_film_rough_es.glsl' });
  if (!/vec3\s+irid_film_rough\s*\(/.test(unblocked.code)) throw fail('irid_film_rough_es.glsl', 'declares no vec3 irid_film_rough(...)');
  return {
    code: `${unblocked.code}\nuniform float irid_roughness;`,
    uniforms: {
      ...unblocked.uniforms,
      irid_rough: { value: boundRoughTexture(film, rough.texture, reflectance) },
      // F_eff's roughness is the material's own, read at every draw.
      irid_roughness: { get value() { return material.roughness; } },
    },
  };
}

/**
 * What goes after #include <lights_fragment_end>: the specular light
 * weighted by the film's R at the angle between the shading normal and the
 * direction to the eye (smooth); with the rough table, the environment
 * light by F_eff (the analytic lights took the film at v·h in BRDF_GGX). The
 * rough table holds light from the ambient; seen from the substrate the
 * environment light takes the smooth film's R at n·v.
 */
function filmLighting(call, useRough) {
  const weight = useRough
    ? `		reflectedLight.indirectSpecular *= IRID_FROM_AMBIENT
			? irid_film_rough( irid_thickness_nm, irid_cos, irid_roughness )
			: ${call}.reflectance;`
    : `		IridFilm irid = ${call};
		reflectedLight.directSpecular *= irid.reflectance;
		reflectedLight.indirectSpecular *= irid.reflectance;`;
  return `#include <lights_fragment_end>
	{
		// cos θ between the shading normal and the direction to the eye, in
		// view space: (0, 0, 1) under an orthographic camera, towards the
		// camera position under a perspective one.
		vec3 irid_view = isOrthographic ? vec3( 0.0, 0.0, 1.0 ) : normalize( vViewPosition );
		float irid_cos = saturate( dot( normal, irid_view ) );
${weight}
	}`;
}

/**
 * material.clone() as three.js makes it (a new material, copy()), with the
 * film added again: the same export and options, the thickness it has now.
 */
function keepFilmOnClone(material) {
  material.clone = function cloneWithFilm() {
    const copy = Object.getPrototypeOf(this).clone.call(this);
    const { given, options, uniforms } = FILMS.get(this);
    addIridFilm(copy, given, options).irid_thickness_nm.value = uniforms.irid_thickness_nm.value;
    return copy;
  };
}

/**
 * Puts a loaded export (from loadIridFilm, or {film, sampler, reflectance,
 * transmittance} with textures from filmTexture or from any loader, rows in
 * either order) on a MeshStandardMaterial or MeshPhysicalMaterial: after
 * the lights are summed, the specular light (direct and from the
 * environment) is multiplied by the film's R at the material's thickness
 * and the angle between the shading normal and the direction to the eye,
 * on the side of the film the eye sees (front faces: from the ambient; back
 * faces, of side: THREE.BackSide or DoubleSide: from the substrate). With a
 * white metal base (color 0xffffff, metalness 1) three.js's own Fresnel is
 * 1 and what the material reflects is R alone. Returns the uniforms (also
 * iridUniforms(material)); `irid_thickness_nm.value` is the thickness in nm
 * (starts at the middle of the export's range). material.clone() keeps the
 * film.
 *
 * options.rough (an export made with `irid export --rough`): the film on a
 * rough (GGX) surface of the material's roughness, as docs/rough.md says a
 * host should: each analytic light's specular takes the film's R at v·h as
 * its Fresnel term (inside three.js's BRDF_GGX), and the environment light
 * (three.js's prefiltered environment, its lobe albedo and multiple-
 * scattering term) is multiplied by F_eff = irid_film_rough(thickness, n·v,
 * material.roughness). An export without the rough table is refused, never
 * replaced by the smooth film.
 */
export function addIridFilm(material, given, options = {}) {
  const { film, sampler, transmittance, rough = null } = given;
  const useRough = options.rough ?? false;
  checkFilm(film);
  if (FILMS.has(material)) throw new Error('addIridFilm: this material has a film already; make a new material');
  if (useRough && !rough) {
    throw fail('film.json', 'has no rough table, which addIridFilm(..., { rough: true }) needs; export the film with `irid export STACK --rough`');
  }
  const { code, uniforms: params } = unblock(sampler, { ...film, prefix: '', file: 'irid_film_es.glsl' });
  const call = filmCall(sampler);
  const reflectance = boundTexture(film, 'reflectance', given.reflectance);
  const [tMin, tMax] = film.domain.thickness_nm;
  const uniforms = {
    ...params,
    irid_reflectance: { value: reflectance.texture },
    irid_transmittance: { value: boundTexture(film, 'transmittance', transmittance).texture },
    irid_thickness_nm: { value: (tMin + tMax) / 2 },
  };
  const roughPart = useRough ? roughProgram(film, rough, reflectance, material) : { code: '', uniforms: {} };
  Object.assign(uniforms, roughPart.uniforms);
  const before = material.onBeforeCompile;
  material.onBeforeCompile = (shader, renderer) => {
    before.call(material, shader, renderer);
    Object.assign(shader.uniforms, uniforms);
    let fs = replaceChunk(shader.fragmentShader, '#include <common>',
      `#include <common>\n${FACING}\n${code}\n${roughPart.code}\nuniform float irid_thickness_nm;`);
    if (useRough) fs = replaceChunk(fs, '#include <lights_physical_pars_fragment>', roughLights(call));
    shader.fragmentShader = replaceChunk(fs, '#include <lights_fragment_end>', filmLighting(call, useRough));
  };
  const key = material.customProgramCacheKey.bind(material);
  const own = `irid-film-${hash(code + roughPart.code)}`;
  material.customProgramCacheKey = () => `${key()}|${own}`;
  FILMS.set(material, { uniforms, given, options });
  keepFilmOnClone(material);
  material.needsUpdate = true;
  return uniforms;
}

/** The uniforms of the film on `material` (as addIridFilm returned them), or null when it has none. */
export function iridUniforms(material) {
  return FILMS.get(material)?.uniforms ?? null;
}
