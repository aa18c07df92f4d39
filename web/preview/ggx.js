// The irid preview: the white GGX lobe's directional albedo (the rough
// program's table) and the float render targets the prefiltered
// environment is drawn into.
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
    ALBEDO_NODES,
  } = P;

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

  Object.assign(P, { lobeAlbedo, lobeAlbedoTable, renderTarget, drawInto, makeTexture });
})((window.IridWeb = window.IridWeb || {}));
