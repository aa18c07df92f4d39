// An irid export on a three.js material, through onBeforeCompile: the
// recipe docs/web.md describes, run by tools/web/test_web.mjs. three.js
// built-in materials take no uniform blocks, so the sampler's block becomes a
// struct uniform; the film's R then weights the material's specular light.

const BLOCK = /layout\s*\(\s*std140\s*\)\s*uniform\s+\w+\s*\{\s*IridParams\s+irid_params\s*;\s*\}\s*;/;

/** A decoded texture ({width, height, data: RGBA Float32Array, rows in file order}) as RGBA16F. */
export function filmTexture(THREE, { width, height, data }) {
  const texture = new THREE.DataTexture(data, width, height, THREE.RGBAFormat, THREE.FloatType);
  texture.internalFormat = 'RGBA16F'; // filterable in every WebGL2
  texture.minFilter = THREE.LinearFilter;
  texture.magFilter = THREE.LinearFilter;
  texture.wrapS = THREE.ClampToEdgeWrapping;
  texture.wrapT = THREE.ClampToEdgeWrapping;
  texture.generateMipmaps = false;
  texture.flipY = false; // row 0 of the file at v = 0
  texture.colorSpace = THREE.NoColorSpace; // linear data
  texture.needsUpdate = true;
  return texture;
}

/**
 * Patches a MeshStandardMaterial or MeshPhysicalMaterial so that its
 * specular light is weighted by the film's reflectance R(t, cos θ). For R
 * alone, make the material a white mirror: color white, metalness 1 (its
 * own Fresnel is then 1 at every angle). Returns the uniforms; set
 * `uniforms.irid_thickness_nm.value` to change the thickness.
 */
export function addIridFilm(THREE, material, { film, sampler, reflectance, transmittance }) {
  if (!BLOCK.test(sampler)) throw new Error('irid_film_es.glsl: no IridParams uniform block found');
  const code = sampler
    .replace(/^\s*precision\s+[^\n]*;\s*$/gm, '') // three.js declares precision itself
    .replace(BLOCK, 'uniform IridParams irid_params;');
  const [tMin, tMax] = film.domain.thickness_nm;
  const uniforms = {
    irid_reflectance: { value: filmTexture(THREE, reflectance) },
    irid_transmittance: { value: filmTexture(THREE, transmittance) },
    irid_params: { value: { v: film.uniform_f32 } }, // a struct uniform: its vec4 array, flat
    irid_thickness_nm: { value: (tMin + tMax) / 2 },
  };
  material.onBeforeCompile = (shader) => {
    Object.assign(shader.uniforms, uniforms);
    const replace = (text, chunk, replacement) => {
      if (!text.includes(chunk)) throw new Error(`three.js shader has no ${chunk}`);
      return text.replace(chunk, replacement);
    };
    let fs = replace(shader.fragmentShader, '#include <common>', `#include <common>\n${code}\nuniform float irid_thickness_nm;`);
    fs = replace(fs, '#include <lights_fragment_end>', `#include <lights_fragment_end>
	{
		// normal and vViewPosition are in view space: their dot is cos θ.
		float irid_cos = saturate(dot(normal, normalize(vViewPosition)));
		IridFilm irid = irid_film(irid_thickness_nm, irid_cos, 0); // light from the ambient
		reflectedLight.directSpecular *= irid.reflectance;
		reflectedLight.indirectSpecular *= irid.reflectance;
	}`);
    shader.fragmentShader = fs;
  };
  material.customProgramCacheKey = () => 'irid-film';
  return uniforms;
}
