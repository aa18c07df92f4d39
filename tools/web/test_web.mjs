// The WebGL2 preview in a real browser: Debian's chromium, headless, driven
// by playwright-core, the page served from 127.0.0.1.
//
// Environment:
//   IRID_PREVIEW     a folder written by `irid preview` (required)
//   IRID_STACKS      NAME=STACK.toml,... : the stack file each export NAME of
//                    the preview was made from (required for at least one:
//                    the reference colours come from `irid color` on it)
//   IRID_BIN         irid (default: target/release/irid of this repository)
//   IRID_SCREENSHOT  where to write a screenshot of the page (optional)
//   CHROMIUM         the browser (default /usr/bin/chromium)
//
// Run: node --test tools/web/test_web.mjs

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { srgb8ToLinear, linearSrgbToLab, deltaE00 } from './colour.mjs';
import { REPO, iridColor, launchChromium, reversedStack, serve, stacksFromEnv, stackWithThickness } from './harness.mjs';

const PREVIEW = process.env.IRID_PREVIEW;
const STACKS = stacksFromEnv();
if (!PREVIEW || STACKS.size === 0) {
  throw new Error('set IRID_PREVIEW (a folder written by `irid preview`) and IRID_STACKS (NAME=STACK.toml,...)');
}

let root;
let server;
let baseUrl;
let browser;

/** The first export named in IRID_STACKS, as a folder under `root`. */
function firstExportDir() {
  const name = [...STACKS.keys()][0];
  const dir = path.join('preview', 'exports', name);
  assert.ok(fs.existsSync(path.join(root, dir, 'film.json')), `the preview holds no export ${name}`);
  return dir;
}

before(async () => {
  root = fs.mkdtempSync(path.join(os.tmpdir(), 'irid-web-'));
  fs.cpSync(PREVIEW, path.join(root, 'preview'), { recursive: true });
  ({ server, baseUrl } = await serve([['/', root]]));
  browser = await launchChromium();
});

after(async () => {
  await browser?.close();
  server?.close();
  if (root) fs.rmSync(root, { recursive: true, force: true });
});

async function open(query = '', init, url = `${baseUrl}/preview/index.html`) {
  const page = await browser.newPage({ viewport: { width: 1100, height: 760 }, deviceScaleFactor: 1 });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  if (init) await page.addInitScript(init);
  await page.goto(`${url}${query}`);
  await page.waitForFunction(() => document.body.dataset.state && document.body.dataset.state !== 'loading', null, { timeout: 60000 });
  page.errors = errors;
  return page;
}

async function ready(query = '', url = undefined) {
  const page = await open(query, undefined, url);
  const state = await page.evaluate(() => document.body.dataset.state);
  const message = await page.textContent('#message');
  assert.equal(state, 'ready', `the page reports: ${message}`);
  await page.waitForFunction(() => Number(document.body.dataset.frames) >= 1);
  assert.deepEqual(page.errors, []);
  return page;
}

async function setControl(page, id, value) {
  await page.$eval(`#${id}`, (el, v) => {
    el.value = v;
    el.dispatchEvent(new Event('input', { bubbles: true }));
  }, String(value));
}

/** The canvas as {width, height, data: RGBA8 rows bottom to top}. */
async function pixels(page, options) {
  const { width, height, base64 } = await page.evaluate((o) => window.irid.pixels(o), options);
  return { width, height, data: new Uint8Array(Buffer.from(base64, 'base64')) };
}

/**
 * The page's chart pixels of one side ('front', or 'back': light from the
 * substrate) against `irid color` at the same (thickness, angle) on the
 * stack as seen from that side.
 */
async function compareChart(page, film, quantity, stackFile, side = 'front', roughness = null) {
  const back = side === 'back' ? '-back' : '';
  const rough = roughness === null ? '' : '-rough';
  await page.selectOption('#mode', (quantity === 'reflectance' ? 'chart-r' : 'chart-t') + back + rough);
  const layer = side === 'back' ? film.sides.back.layer : film.layer;
  const image = await pixels(page);
  const { width, height, data } = image;
  // The chart's mapping, restated from the page's contract: pixel centres,
  // thickness linear in x, angle linear in y from acos(cos_max) at the bottom.
  const [t0, t1] = film.domain.thickness_nm;
  const angleLo = Math.acos(film.domain.cos_theta[1]);
  const angleHi = Math.acos(film.domain.cos_theta[0]);
  const columns = 24;
  const rows = 10;
  const text = fs.readFileSync(stackFile, 'utf8');
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'irid-web-stack-'));
  const differences = [];
  try {
    for (let i = 0; i < columns; i++) {
      const px = Math.floor(((i + 0.5) / columns) * width);
      const thickness = t0 + ((px + 0.5) / width) * (t1 - t0);
      const pys = [];
      const angles = [];
      for (let j = 0; j < rows; j++) {
        const py = Math.floor(((j + 0.5) / rows) * height);
        const theta = angleLo + ((py + 0.5) / height) * (angleHi - angleLo);
        const deg = (theta * 180) / Math.PI;
        if (deg >= 90) continue;
        pys.push(py);
        angles.push(deg);
      }
      const colours = iridColor(stackWithThickness(text, layer, thickness, tmp), angles, roughness);
      colours.forEach((c, k) => {
        const o = (pys[k] * width + px) * 4; // readPixels rows run bottom to top
        const shown = [0, 1, 2].map((ch) => srgb8ToLinear(data[o + ch]));
        // The page can only show [0, 1]: the reference is clamped likewise.
        const exact = c[`${quantity}_rgb`].map((v) => Math.min(1, Math.max(0, v)));
        differences.push(deltaE00(linearSrgbToLab(exact), linearSrgbToLab(shown)));
      });
    }
  } finally {
    fs.rmSync(tmp, { recursive: true, force: true });
  }
  const mean = differences.reduce((s, d) => s + d, 0) / differences.length;
  const max = Math.max(...differences);
  return { mean, max, points: differences.length };
}

function readFilm(dir) {
  return JSON.parse(fs.readFileSync(path.join(root, dir, 'film.json'), 'utf8'));
}

test('CIEDE2000 reproduces Sharma, Wu and Dalal (2005)', () => {
  const pairs = [
    [[50, 2.6772, -79.7751], [50, 0, -82.7485], 2.0425],
    [[50, 0, 0], [50, -1, 2], 2.3669],
    [[50, 2.5, 0], [73, 25, -18], 27.1492],
    [[60.2574, -34.0099, 36.2677], [60.4626, -34.1751, 39.4387], 1.2644],
    [[22.7233, 20.0904, -46.694], [23.0331, 14.973, -42.5619], 2.0373],
  ];
  for (const [a, b, expected] of pairs) assert.ok(Math.abs(deltaE00(a, b) - expected) < 5e-5, `${a} ${b}`);
  assert.ok(Math.abs(srgb8ToLinear(255) - 1) < 1e-12 && srgb8ToLinear(0) === 0);
});

test('the page opens, draws, and its charts match irid color (ΔE00 after 8-bit sRGB encoding)', async () => {
  const page = await ready();
  const labels = await page.evaluate(() => window.irid.preview.exports.map((e) => e.label));
  for (const [name, stackFile] of STACKS) {
    const index = labels.indexOf(name);
    assert.ok(index >= 0, `the page offers no export ${name} (it offers ${labels.join(', ')})`);
    await page.selectOption('#export', String(index));
    const film = readFilm(path.join('preview', 'exports', name));
    if (film.white !== 'd65') {
      throw new Error(`${name}: the reference (irid color) is D65 linear sRGB; this export's white is ${film.white}`);
    }
    for (const quantity of ['reflectance', 'transmittance']) {
      const r = await compareChart(page, film, quantity, stackFile);
      console.log(`${name} chart ${quantity}: ΔE00 mean ${r.mean.toFixed(3)}, max ${r.max.toFixed(3)} over ${r.points} points`);
      assert.ok(r.mean <= 0.5, `${name} ${quantity}: mean ΔE00 ${r.mean}`);
    }
  }
  await page.close();
});

test('the charts from the substrate side match the reversed stack, past the critical angle too', async () => {
  const page = await ready();
  const labels = await page.evaluate(() => window.irid.preview.exports.map((e) => e.label));
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'irid-web-back-'));
  let checked = 0;
  try {
    for (const name of STACKS.keys()) {
      const film = readFilm(path.join('preview', 'exports', name));
      if (film.sides.back === null || film.sides.back.charts[0] === film.sides.front.charts[0]) continue;
      await page.selectOption('#export', String(labels.indexOf(name)));
      const stack = reversedStack(film, tmp);
      for (const quantity of ['reflectance', 'transmittance']) {
        const r = await compareChart(page, film, quantity, stack, 'back');
        console.log(`${name} chart ${quantity} from the substrate: ΔE00 mean ${r.mean.toFixed(3)}, max ${r.max.toFixed(3)} over ${r.points} points`);
        assert.ok(r.mean <= 0.5, `${name} ${quantity} (back): mean ΔE00 ${r.mean}`);
      }
      checked++;
    }
  } finally {
    fs.rmSync(tmp, { recursive: true, force: true });
  }
  assert.ok(checked >= 1, 'no export with a back chart of its own');
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a film over an absorbing substrate (copper) is opaque: the sphere shows R alone', async () => {
  const name = 'film-on-copper';
  assert.ok(STACKS.has(name), `IRID_STACKS names no ${name}`);
  const film = readFilm(path.join('preview', 'exports', name));
  assert.equal(film.opaque, true);
  assert.equal(film.sides.back, null);
  const page = await ready();
  const labels = await page.evaluate(() => window.irid.preview.exports.map((e) => e.label));
  await page.selectOption('#export', String(labels.indexOf(name)));
  assert.match(await page.textContent('#info'), /opaque\s*yes/);
  await page.selectOption('#mode', 'object');
  await page.selectOption('#environment', 'white');
  const image = await pixels(page);
  // The centre sees the sphere at normal incidence, at the thickness
  // control's default (the middle of the range): R there, as irid color has
  // it, and not R + T, which is white for a film that absorbs nothing.
  const [t0, t1] = film.domain.thickness_nm;
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'irid-web-copper-'));
  try {
    const stack = stackWithThickness(fs.readFileSync(STACKS.get(name), 'utf8'), film.layer, (t0 + t1) / 2, tmp);
    const exact = iridColor(stack, [0])[0];
    const o = ((image.height >> 1) * image.width + (image.width >> 1)) * 4;
    const shown = [0, 1, 2].map((ch) => srgb8ToLinear(image.data[o + ch]));
    const want = exact.reflectance_rgb.map((v) => Math.min(1, Math.max(0, v)));
    const de = deltaE00(linearSrgbToLab(want), linearSrgbToLab(shown));
    console.log(`film on copper, sphere centre in the white environment: ${shown.map((x) => x.toFixed(3))} against R ${want.map((x) => x.toFixed(3))}: ΔE00 ${de.toFixed(3)}`);
    assert.ok(de <= 1, `ΔE00 ${de}`);
  } finally {
    fs.rmSync(tmp, { recursive: true, force: true });
  }
  await page.close();
});

test('inside a coated glass sphere the view is the film from the glass: white in a white world, past the critical angle too', async () => {
  const name = 'film-on-glass';
  assert.ok(STACKS.has(name), `IRID_STACKS names no ${name}`);
  const page = await ready();
  const labels = await page.evaluate(() => window.irid.preview.exports.map((e) => e.label));
  await page.selectOption('#export', String(labels.indexOf(name)));
  await page.selectOption('#mode', 'object');
  // The eye 0.9 from the centre of the unit sphere: its rays meet the inner
  // face at up to 64°, past the glass side's critical angle (41.8°).
  await page.evaluate(() => { window.irid.preview.distance = 0.9; });
  await page.selectOption('#environment', 'sky');
  const inside = await pixels(page);
  const alone = await pixels(page, { objectHidden: true });
  let changed = 0;
  for (let i = 0; i < inside.data.length; i += 4) {
    if ([0, 1, 2].some((ch) => Math.abs(inside.data[i + ch] - alone.data[i + ch]) > 2)) changed++;
  }
  await page.selectOption('#environment', 'white');
  const white = await pixels(page);
  let dark = 0;
  for (let i = 0; i < white.data.length; i += 4) {
    if (Math.min(white.data[i], white.data[i + 1], white.data[i + 2]) < 250) dark++;
  }
  const n = white.data.length / 4;
  console.log(`inside the coated glass sphere: ${(100 * changed / n).toFixed(1)} % of the pixels differ from the sky alone; `
    + `in the white world ${dark} of ${n} pixels below 250 of 255`);
  // The inner face is drawn (the back faces, side 1)...
  assert.ok(changed > 0.5 * n, `only ${changed} pixels show the sphere from inside`);
  // ...and keeps the light: R + T = 1 from the glass, R = 1 past the critical angle.
  assert.ok(dark <= 0.001 * n, `${dark} pixels darker than white`);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('the 16-bit PNGs, read when film.json lists no EXR, give the chart too', async () => {
  const dir = firstExportDir();
  const film = readFilm(dir);
  if (!film.texture.png) return; // exported without --png: nothing to read
  const pngOnly = path.join(root, 'png-only');
  fs.cpSync(path.join(root, dir), pngOnly, { recursive: true });
  fs.writeFileSync(path.join(pngOnly, 'film.json'), JSON.stringify({ ...film, texture: { ...film.texture, files: null } }));
  for (const f of Object.values(film.texture.files)) fs.rmSync(path.join(pngOnly, f), { force: true });
  const page = await ready('?export=../png-only/');
  assert.match(await page.textContent('#info'), /PNG16/);
  const r = await compareChart(page, film, 'reflectance', STACKS.get(path.basename(dir)));
  console.log(`${path.basename(dir)} chart reflectance from the PNGs: ΔE00 mean ${r.mean.toFixed(3)}, max ${r.max.toFixed(3)} over ${r.points} points`);
  assert.ok(r.mean <= 0.5, `mean ΔE00 ${r.mean}`);
  await page.close();
});

test('the preview opens from file:// (embedded exports) and draws what the page draws from fetched files', async () => {
  const local = await ready('', `file://${path.join(root, 'preview', 'index.html')}`);
  const name = await local.evaluate(() => window.irid.preview.current.label);
  await local.selectOption('#mode', 'chart-r');
  const fromFile = await pixels(local);
  await local.close();
  const served = await ready(`?export=exports/${name}/`);
  assert.equal(await served.evaluate(() => window.irid.preview.current.name), `exports/${name}/`);
  await served.selectOption('#mode', 'chart-r');
  const fromServer = await pixels(served);
  await served.close();
  assert.equal(Buffer.compare(Buffer.from(fromServer.data), Buffer.from(fromFile.data)), 0);
});

/** Mean absolute difference of two RGBA8 images over a centred box. */
function boxDifference(a, b, size) {
  let sum = 0;
  let n = 0;
  const x0 = (a.width - size) >> 1;
  const y0 = (a.height - size) >> 1;
  for (let y = y0; y < y0 + size; y++) {
    for (let x = x0; x < x0 + size; x++) {
      for (let ch = 0; ch < 3; ch++) {
        const o = (y * a.width + x) * 4 + ch;
        sum += Math.abs(a.data[o] - b.data[o]);
        n++;
      }
    }
  }
  return sum / n;
}

test('the sphere is drawn, and the thickness control changes it', async () => {
  const page = await ready();
  await page.selectOption('#mode', 'object');
  const first = await pixels(page);
  // Not blank: the centre shows many colours, not the background alone.
  const colours = new Set();
  let lit = 0;
  const size = 160;
  for (let y = (first.height - size) >> 1, i = 0; i < size; y++, i++) {
    for (let x = (first.width - size) >> 1, j = 0; j < size; x++, j++) {
      const o = (y * first.width + x) * 4;
      colours.add((first.data[o] << 16) | (first.data[o + 1] << 8) | first.data[o + 2]);
      if (first.data[o] + first.data[o + 1] + first.data[o + 2] > 30) lit++;
    }
  }
  assert.ok(colours.size > 200, `only ${colours.size} colours at the centre`);
  assert.ok(lit > 0.5 * size * size, `only ${lit} lit pixels at the centre`);

  // Rendering is deterministic: the same controls give the same pixels, so
  // any difference below comes from the control changed.
  const [tMin, tMax] = await page.evaluate(() => window.irid.preview.current.film.domain.thickness_nm);
  await setControl(page, 'thickness', tMin + 0.2 * (tMax - tMin));
  const thin = await pixels(page);
  assert.equal(boxDifference(thin, await pixels(page), size), 0, 'two draws of the same scene differ');
  await setControl(page, 'thickness', tMin + 0.8 * (tMax - tMin));
  const thick = await pixels(page);
  const change = boxDifference(thin, thick, size);
  console.log(`thickness at 20 % → 80 % of the range: mean |Δ| ${change.toFixed(2)} of 255 over the centre's RGB`);
  assert.ok(change > 1, `moving the thickness changes the centre by ${change} only`);

  await page.selectOption('#thickness-mode', 'noise');
  const noise = await pixels(page);
  assert.ok(boxDifference(thick, noise, size) > 1, 'noise thickness looks like the uniform one');
  await page.selectOption('#object', 'torus');
  const torus = await pixels(page);
  assert.ok(boxDifference(noise, torus, size) > 1, 'the torus looks like the sphere');
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('frame time: the film shader against the same scene with constant R and T', async () => {
  const page = await ready();
  await page.selectOption('#mode', 'object');
  const film = [];
  const plain = [];
  // Alternating rounds, so that both see the same load on a shared machine.
  for (let round = 0; round < 9; round++) {
    film.push(await page.evaluate(() => window.irid.timeFrames(10, false)));
    plain.push(await page.evaluate(() => window.irid.timeFrames(10, true)));
  }
  const median = (xs) => [...xs].sort((a, b) => a - b)[xs.length >> 1];
  const renderer = await page.evaluate(() => {
    const gl = document.getElementById('canvas').getContext('webgl2');
    const e = gl.getExtension('WEBGL_debug_renderer_info');
    return gl.getParameter(e ? e.UNMASKED_RENDERER_WEBGL : gl.RENDERER);
  });
  const size = await page.evaluate(() => [window.irid.preview.gl.canvas.width, window.irid.preview.gl.canvas.height]);
  console.log(`frame time ${size[0]}×${size[1]} (${renderer}): film ${median(film).toFixed(1)} ms, `
    + `constant R/T ${median(plain).toFixed(1)} ms, ratio ${(median(film) / median(plain)).toFixed(2)} (medians of 9 alternating rounds of 10 frames)`);
  // A bound for software rendering, not a goal: a frame within 2 s.
  assert.ok(median(film) < 2000, `${median(film)} ms per frame`);
  await page.close();
});

test('screenshot', async (t) => {
  const out = process.env.IRID_SCREENSHOT;
  if (!out) {
    t.skip('IRID_SCREENSHOT not set');
    return;
  }
  const page = await ready();
  await page.selectOption('#mode', 'object');
  await page.selectOption('#thickness-mode', 'noise');
  await page.evaluate(() => window.irid.draw());
  fs.mkdirSync(path.dirname(out), { recursive: true });
  await page.screenshot({ path: out, clip: { x: 0, y: 0, width: 1100, height: 560 } });
  await page.close();
});

test('film.json: every file of tests/film-json by the one reader rule (docs/gpu.md)', async () => {
  fs.cpSync(path.join(REPO, 'tests/film-json'), path.join(root, 'film-json'), { recursive: true });
  const page = await ready();
  const read = (name) => page.evaluate(async (url) => {
    try {
      window.IridWeb.preview.readPreviewFilm(await (await fetch(url)).text(), url);
      return null;
    } catch (e) {
      return e.message;
    }
  }, `/film-json/${name}`);
  const cases = JSON.parse(fs.readFileSync(path.join(REPO, 'tests/film-json/cases.json'), 'utf8'));
  for (const name of cases.good) assert.equal(await read(name), null, name);
  for (const [name, field] of Object.entries(cases.bad)) {
    const message = await read(name);
    assert.ok(message !== null, `${name}: accepted`);
    assert.ok(message.startsWith(`/film-json/${name}: `) && message.includes(field) && !message.includes('\n'), `${name}: ${message}`);
  }
  await page.close();
});

test('a missing export, damaged ones, and no WebGL2 each show a message', async () => {
  const dir = firstExportDir();
  const film = readFilm(dir);

  let page = await open('?export=../no-such-export/');
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'error');
  assert.match(await page.textContent('#message'), /no-such-export\/film\.json: not found/);
  await page.close();

  const badJson = path.join(root, 'bad-json');
  fs.cpSync(path.join(root, dir), badJson, { recursive: true });
  fs.writeFileSync(path.join(badJson, 'film.json'), '{"format": "irid-film", "version": 1,');
  page = await open('?export=../bad-json/');
  assert.match(await page.textContent('#message'), /film\.json: not JSON/);
  await page.close();

  const truncated = path.join(root, 'truncated');
  fs.cpSync(path.join(root, dir), truncated, { recursive: true });
  const texture = film.texture.files.reflectance;
  const bytes = fs.readFileSync(path.join(truncated, texture));
  fs.writeFileSync(path.join(truncated, texture), bytes.subarray(0, bytes.length >> 1));
  page = await open('?export=../truncated/');
  const message = await page.textContent('#message');
  assert.match(message, new RegExp(`${texture.replace('.', '\\.')}: .*(truncated|inflate|decompress)`));
  await page.close();

  const badShader = path.join(root, 'bad-shader');
  fs.cpSync(path.join(root, dir), badShader, { recursive: true });
  fs.writeFileSync(path.join(badShader, 'irid_film_es.glsl'), 'IridFilm irid_film(float t, float c) { return oops; }\n');
  page = await open('?export=../bad-shader/');
  assert.match(await page.textContent('#message'), /bad-shader\/irid_film_es\.glsl: does not compile/);
  await page.close();

  page = await open('', () => {
    const original = HTMLCanvasElement.prototype.getContext;
    HTMLCanvasElement.prototype.getContext = function (kind, ...rest) {
      return kind === 'webgl2' ? null : original.call(this, kind, ...rest);
    };
  });
  assert.match(await page.textContent('#message'), /does not offer WebGL2/);
  await page.close();
});

// ------------------------------------------------------------------ rough films

/** The export of IRID_STACKS made with `irid export --rough` (film.json "rough"), as [name, film]. */
function roughExport() {
  for (const name of STACKS.keys()) {
    const film = readFilm(path.join('preview', 'exports', name));
    if (film.rough) return [name, film];
  }
  throw new Error('no export of IRID_STACKS has the rough table: make one with `irid export STACK --rough`');
}

async function selectExport(page, name) {
  const labels = await page.evaluate(() => window.irid.preview.exports.map((e) => e.label));
  assert.ok(labels.includes(name), `the page offers no export ${name}`);
  await page.selectOption('#export', String(labels.indexOf(name)));
}

/**
 * The page's camera restated (yaw, pitch, distance, 35° field, looking at the
 * origin): for pixel (px, py) of a width × height canvas (py counted from
 * the bottom, as readPixels has it), the unit sphere's point it sees, or
 * null: {cos: n·v, mirrored: the reflected view direction}.
 */
function sphereAt(px, py, width, height, { yaw, pitch, distance }) {
  const eye = [distance * Math.cos(pitch) * Math.sin(yaw), distance * Math.sin(pitch), distance * Math.cos(pitch) * Math.cos(yaw)];
  const norm = (a) => { const l = Math.hypot(...a); return a.map((x) => x / l); };
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const z = norm(eye);
  const x = norm(cross([0, 1, 0], z));
  const y = cross(z, x);
  const f = Math.tan((35 * Math.PI) / 360);
  const sx = (((px + 0.5) / width) * 2 - 1) * f * (width / height);
  const sy = (((py + 0.5) / height) * 2 - 1) * f;
  const d = norm([0, 1, 2].map((k) => -z[k] + sx * x[k] + sy * y[k]));
  const b = dot(eye, d);
  const disc = b * b - dot(eye, eye) + 1;
  if (disc <= 0) return null;
  const s = -b - Math.sqrt(disc);
  const n = [0, 1, 2].map((k) => eye[k] + s * d[k]);
  const cos = -dot(n, d);
  return { cos, mirrored: [0, 1, 2].map((k) => d[k] + 2 * cos * n[k]) };
}

test('rough: the page\'s white GGX lobe albedo is irid\'s lobe_albedo', async () => {
  const [name, film] = roughExport();
  const page = await ready();
  await selectExport(page, name);
  const angles = [0, 15, 30, 45, 60, 70, 80];
  const stack = STACKS.get(name);
  let worst = 0;
  let worstTable = 0;
  for (const r of [0.1, 0.3, 0.5, 0.8, 1]) {
    const exact = iridColor(stack, angles, r);
    const table = await page.evaluate((rr) => window.irid.lobeAlbedoTable(rr), r);
    for (const [k, a] of angles.entries()) {
      const c = Math.cos((a * Math.PI) / 180);
      const direct = await page.evaluate(([cc, rr]) => window.irid.lobeAlbedo(cc, rr), [c, r]);
      // The shader's linear interpolation in the table (nodes i / (table.length − 1)).
      const x = c * (table.length - 1);
      const i = Math.min(Math.floor(x), table.length - 2);
      const interpolated = table[i] + (table[i + 1] - table[i]) * (x - i);
      worst = Math.max(worst, Math.abs(direct - exact[k].lobe_albedo));
      worstTable = Math.max(worstTable, Math.abs(interpolated - exact[k].lobe_albedo));
    }
  }
  console.log(`lobe albedo, roughness 0.1-1, 0-80°: page's quadrature within ${worst.toExponential(2)} of irid's, `
    + `the shader's table interpolation within ${worstTable.toExponential(2)}`);
  assert.ok(worst <= 1e-3, `lobe albedo off by ${worst}`);
  assert.ok(worstTable <= 2e-3, `interpolated lobe albedo off by ${worstTable}`);
  assert.ok(film.rough.uniform_f32.length % 4 === 0);
  await page.close();
});

test('rough: the rough R chart matches irid color --roughness (ΔE00 after 8-bit sRGB encoding)', async () => {
  const [name, film] = roughExport();
  const page = await ready();
  await selectExport(page, name);
  for (const r of [0.25, 0.5]) {
    await setControl(page, 'roughness', r);
    const res = await compareChart(page, film, 'reflectance', STACKS.get(name), 'front', r);
    console.log(`${name} rough R chart at roughness ${r}: ΔE00 mean ${res.mean.toFixed(3)}, max ${res.max.toFixed(3)} over ${res.points} points`);
    assert.ok(res.mean <= 0.5 && res.max <= 2, `roughness ${r}: ΔE00 mean ${res.mean}, max ${res.max}`);
  }
  assert.deepEqual(page.errors, []);
  await page.close();
});

/**
 * The sphere's pixels (every 16th in x and y, n·v ≥ 0.2) at roughness r in
 * `environment` against lobe_albedo × F_eff from `irid color --roughness r`
 * × the page's prefiltered environment about the mirror direction: ΔE00
 * and the largest difference in 8-bit codes.
 */
async function compareRoughSphere(page, name, film, r, environment) {
  await page.selectOption('#mode', 'object');
  await page.selectOption('#environment', environment);
  await setControl(page, 'roughness', r);
  const image = await pixels(page);
  const camera = await page.evaluate(() => ({ yaw: window.irid.preview.yaw, pitch: window.irid.preview.pitch, distance: window.irid.preview.distance }));
  const points = [];
  for (let py = 8; py < image.height; py += 16) {
    for (let px = 8; px < image.width; px += 16) {
      const hit = sphereAt(px, py, image.width, image.height, camera);
      if (hit && hit.cos >= 0.2) points.push({ px, py, ...hit });
    }
  }
  const [t0, t1] = film.domain.thickness_nm;
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'irid-web-rough-'));
  let exact;
  try {
    const stack = stackWithThickness(fs.readFileSync(STACKS.get(name), 'utf8'), film.layer, (t0 + t1) / 2, tmp);
    exact = iridColor(stack, points.map((p) => (Math.acos(Math.min(1, p.cos)) * 180) / Math.PI), r);
  } finally {
    fs.rmSync(tmp, { recursive: true, force: true });
  }
  const env = await page.evaluate(([e, rr, dirs]) => dirs.map((d) => window.irid.prefilteredAt(e, rr, d)),
    [environment, r, points.map((p) => p.mirrored)]);
  const differences = [];
  let codes = 0;
  points.forEach((p, k) => {
    const o = (p.py * image.width + p.px) * 4;
    const want = [0, 1, 2].map((ch) => Math.min(1, Math.max(0, exact[k].lobe_albedo * exact[k].reflectance_rgb[ch] * env[k][ch])));
    const shown = [0, 1, 2].map((ch) => srgb8ToLinear(image.data[o + ch]));
    differences.push(deltaE00(linearSrgbToLab(want), linearSrgbToLab(shown)));
    const encode = (c) => 255 * (c <= 0.0031308 ? 12.92 * c : 1.055 * c ** (1 / 2.4) - 0.055);
    codes = Math.max(codes, ...[0, 1, 2].map((ch) => Math.abs(encode(want[ch]) - image.data[o + ch])));
  });
  const mean = differences.reduce((s, d) => s + d, 0) / differences.length;
  return { mean, max: Math.max(...differences), codes, points: points.length, env };
}

test('rough: the sphere at roughness 0.5 is lobe albedo × F_eff × the prefiltered environment', async () => {
  const [name, film] = roughExport();
  assert.equal(film.opaque, true, `${name}: the test needs an opaque film (R alone on the sphere)`);
  const page = await ready();
  await selectExport(page, name);
  for (const [environment, r] of [['white', 0.5], ['white', 0.25], ['sky', 0.5], ['studio', 0.5]]) {
    const res = await compareRoughSphere(page, name, film, r, environment);
    console.log(`${name} sphere, roughness ${r}, ${environment} environment: ΔE00 mean ${res.mean.toFixed(3)}, `
      + `max ${res.max.toFixed(3)}, max ${res.codes.toFixed(2)} of 255 over ${res.points} pixels`);
    if (environment === 'white') {
      // A white world stays white when prefiltered.
      const off = Math.max(...res.env.flat().map((v) => Math.abs(v - 1)));
      assert.ok(off <= 1e-3, `the prefiltered white environment is off by ${off}`);
    }
    assert.ok(res.mean <= 0.5 && res.max <= 2 && res.codes <= 2,
      `${environment}, roughness ${r}: ΔE00 mean ${res.mean}, max ${res.max}, ${res.codes} of 255`);
  }
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('rough: at roughness 0 the page draws what it draws without the rough table', async () => {
  const [name, film] = roughExport();
  const dir = path.join(root, 'preview', 'exports', name);
  const smooth = path.join(root, 'smooth-only');
  fs.cpSync(dir, smooth, { recursive: true });
  fs.writeFileSync(path.join(smooth, 'film.json'), JSON.stringify({ ...film, rough: null }));
  const images = [];
  for (const query of [`?export=exports/${name}/`, '?export=../smooth-only/']) {
    const page = await ready(query);
    await page.selectOption('#mode', 'object');
    await setControl(page, 'roughness', 0.5);
    await setControl(page, 'roughness', 0);
    images.push(await pixels(page));
    await page.close();
  }
  assert.equal(Buffer.compare(Buffer.from(images[0].data), Buffer.from(images[1].data)), 0);
});

test('rough: without the rough table the control is disabled and says why', async () => {
  const page = await ready();
  const [name] = roughExport();
  const other = [...STACKS.keys()].find((n) => !readFilm(path.join('preview', 'exports', n)).rough);
  assert.ok(other, 'every export has the rough table: the test needs one without');
  await selectExport(page, name);
  assert.equal(await page.$eval('#roughness', (e) => e.disabled), false);
  await setControl(page, 'roughness', 0.5);
  await selectExport(page, other);
  assert.equal(await page.$eval('#roughness', (e) => e.disabled), true);
  assert.equal(await page.$eval('#roughness', (e) => Number(e.value)), 0);
  assert.equal(await page.$eval('option[value="chart-r-rough"]', (e) => e.disabled), true);
  const note = await page.textContent('#roughness-note');
  assert.match(note, /no rough table.*irid export STACK --rough/s);
  assert.ok(await page.isVisible('#roughness-note'), 'the reason is not visible');
  // Drawn at roughness 0 with the smooth film: the disabled control reads 0.
  assert.equal(await page.evaluate(() => window.irid.preview.controls().roughness), 0);
  const out = process.env.IRID_SCREENSHOT_ROUGH;
  if (out) {
    await page.screenshot({ path: out.replace(/\.png$/, '-no-table.png'), clip: { x: 0, y: 0, width: 1100, height: 560 }, timeout: 120000 });
    await selectExport(page, name);
    await setControl(page, 'roughness', 0.5);
    await page.evaluate(() => window.irid.draw());
    await page.screenshot({ path: out, clip: { x: 0, y: 0, width: 1100, height: 560 }, timeout: 120000 });
  }
  assert.deepEqual(page.errors, []);
  await page.close();
});

/** The page's sky (web/preview/shaders.js, irid_environment with u_environment 0), restated: linear RGB towards unit d. */
function sky(d) {
  const sun = (() => { const v = [0.45, 0.55, 0.7]; const l = Math.hypot(...v); return v.map((x) => x / l); })();
  const s = Math.max(d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2], 0);
  const mix = (a, b, t) => a.map((x, k) => x + (b[k] - x) * t);
  const smoothstep = (e0, e1, x) => { const t = Math.min(1, Math.max(0, (x - e0) / (e1 - e0))); return t * t * (3 - 2 * t); };
  let c;
  if (d[1] >= 0) {
    c = mix([0.75, 0.85, 1.0], [0.15, 0.35, 0.85], d[1] ** 0.45);
  } else {
    const k = Math.max(-d[1], 0.02);
    let checker = (((Math.floor((d[0] / k) * 2) + Math.floor((d[2] / k) * 2)) % 2) + 2) % 2;
    checker = 0.5 + (checker - 0.5) * smoothstep(0, -0.12, d[1]);
    c = mix([0.10, 0.09, 0.08], [0.22, 0.20, 0.17], checker).map((x) => x * (0.6 + 0.4 * smoothstep(0, -0.4, d[1])));
  }
  const glow = s ** 900 * 60 + s ** 16 * 0.25;
  return c.map((x, k) => x + [1, 0.95, 0.85][k] * glow);
}

/**
 * The prefiltered environment's definition evaluated densely: about R, with
 * the normal and the view both R, the mean of env(l) weighted by n·l over
 * h from D(h) cos θ_h (n × n stratified midpoints), no mip levels.
 */
function prefilterReference(env, R, roughness, n = 1024) {
  const a2 = roughness ** 4;
  const up = Math.abs(R[1]) < 0.999 ? [0, 1, 0] : [1, 0, 0];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const norm = (a) => { const l = Math.hypot(...a); return a.map((x) => x / l); };
  const tx = norm(cross(up, R));
  const ty = cross(R, tx);
  const sum = [0, 0, 0];
  let weight = 0;
  for (let i = 0; i < n; i++) {
    const u = (i + 0.5) / n;
    const cos2 = (1 - u) / (1 + (a2 - 1) * u);
    const ch = Math.sqrt(cos2);
    const sh = Math.sqrt(1 - cos2);
    for (let j = 0; j < n; j++) {
      const phi = (2 * Math.PI * (j + 0.5)) / n;
      const h = [0, 1, 2].map((k) => tx[k] * sh * Math.cos(phi) + ty[k] * sh * Math.sin(phi) + R[k] * ch);
      const nh = ch;
      const l = [0, 1, 2].map((k) => 2 * nh * h[k] - R[k]);
      const nl = 2 * nh * nh - 1;
      if (nl <= 0) continue;
      const L = env(l);
      for (let k = 0; k < 3; k++) sum[k] += L[k] * nl;
      weight += nl;
    }
  }
  return sum.map((x) => x / weight);
}

test('rough: the prefiltered sky against a dense evaluation of its definition', async () => {
  const [name] = roughExport();
  const page = await ready();
  await selectExport(page, name);
  const norm = (a) => { const l = Math.hypot(...a); return a.map((x) => x / l); };
  // Up, the sky at 30°, towards the sun, the horizon, the ground.
  const directions = [[0, 1, 0], norm([0.8, 0.5, -0.3]), norm([0.45, 0.55, 0.7]), norm([-0.6, 0.05, 0.8]), norm([0.2, -0.8, 0.4])];
  let worst = 0;
  for (const r of [0.25, 0.5]) {
    const shown = await page.evaluate(([rr, dirs]) => dirs.map((d) => window.irid.prefilteredAt('sky', rr, d)), [r, directions]);
    directions.forEach((d, i) => {
      const exact = prefilterReference(sky, d, r);
      const rel = Math.max(...[0, 1, 2].map((k) => Math.abs(shown[i][k] - exact[k]) / exact[k]));
      worst = Math.max(worst, rel);
      console.log(`prefiltered sky, roughness ${r}, direction ${d.map((x) => x.toFixed(2))}: page ${shown[i].map((x) => x.toFixed(4))}, `
        + `dense ${exact.map((x) => x.toFixed(4))}, largest relative difference ${(100 * rel).toFixed(2)} %`);
    });
  }
  assert.ok(worst <= 0.05, `the prefiltered sky is off by ${(100 * worst).toFixed(2)} %`);
  await page.close();
});
