// What the browser tests share: a static file server on 127.0.0.1, headless
// Chromium through playwright-core, and stack files with one layer's
// thickness set for `irid color`.

import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

export const HERE = path.dirname(fileURLToPath(import.meta.url));
export const REPO = path.resolve(HERE, '../..');
export const IRID = process.env.IRID_BIN || path.join(REPO, 'target/release/irid');
const CHROMIUM = process.env.CHROMIUM || '/usr/bin/chromium';

/** IRID_STACKS (NAME=STACK.toml,...) as a Map of NAME to an absolute path. */
export function stacksFromEnv() {
  return new Map((process.env.IRID_STACKS || '').split(',').filter(Boolean).map((pair) => {
    const at = pair.indexOf('=');
    return [pair.slice(0, at), path.resolve(pair.slice(at + 1))];
  }));
}

const MIME = {
  '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.css': 'text/css', '.json': 'application/json',
  '.png': 'image/png', '.exr': 'image/x-exr', '.glsl': 'text/plain',
};

/**
 * A server of the folders in `mounts` ([[url prefix, folder], ...], the
 * first matching prefix wins) on a free port of 127.0.0.1; resolves to
 * {server, baseUrl}.
 */
export async function serve(mounts) {
  const server = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://127.0.0.1');
    const pathname = decodeURIComponent(url.pathname);
    const mount = mounts.find(([prefix]) => pathname.startsWith(prefix));
    const dir = mount && path.resolve(mount[1]);
    const file = mount && path.join(dir, pathname.slice(mount[0].length));
    if (!file || !file.startsWith(dir + path.sep) || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
      res.writeHead(404).end('not found');
      return;
    }
    res.writeHead(200, { 'content-type': MIME[path.extname(file)] || 'application/octet-stream' });
    fs.createReadStream(file).pipe(res);
  });
  await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
  return { server, baseUrl: `http://127.0.0.1:${server.address().port}` };
}

/** Headless Chromium with WebGL2 on SwiftShader (no GPU needed). */
export function launchChromium() {
  return chromium.launch({
    executablePath: CHROMIUM,
    headless: true,
    args: ['--no-sandbox', '--no-first-run', '--disable-background-networking', '--disable-component-update',
      '--disable-sync', '--disable-quic', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  });
}

/** The stack file `text` with layer `layer`'s thickness set, in a file under `dir`. */
export function stackWithThickness(text, layer, thickness, dir) {
  let seen = 0;
  const out = text.replace(/^(\s*thickness_nm\s*=\s*)[^#\n]+/gm, (m, lead) => {
    seen++;
    return seen === layer ? `${lead}${thickness}` : m;
  });
  if (seen < layer) throw new Error(`the stack file has no layer ${layer}`);
  const file = path.join(dir, `stack-${thickness}.toml`);
  fs.writeFileSync(file, out);
  return file;
}

/**
 * `irid color STACK --json` at `angles` (degrees): one {reflectance_rgb,
 * transmittance_rgb, ...} per angle; with `roughness`, `--roughness R`: F_eff
 * as reflectance_rgb and the white lobe's lobe_albedo (docs/rough.md).
 */
export function iridColor(stackFile, angles, roughness = null) {
  const rough = roughness === null ? [] : ['--roughness', String(roughness)];
  const out = execFileSync(IRID, ['color', stackFile, '--json', ...rough, '--angles', angles.map((a) => a.toPrecision(17)).join(',')],
    { encoding: 'utf8', maxBuffer: 1 << 28 });
  const colours = JSON.parse(out);
  if (colours.length !== angles.length) throw new Error(`irid color gave ${colours.length} colours for ${angles.length} angles`);
  return colours;
}

/**
 * The stack of film.json seen from its substrate (reversed), as a stack file
 * in `dir`: for stacks of constant indices, which every back-side export of
 * the test has.
 */
export function reversedStack(film, dir) {
  const index = (m) => {
    const c = m.dispersion && m.dispersion.constant;
    if (!c) throw new Error(`${m.name}: the test writes constant indices only`);
    return `[${c.n}, ${c.k}]`;
  };
  const lines = [`ambient = { n = ${index(film.stack.substrate)} }`, `substrate = { n = ${index(film.stack.ambient)} }`];
  for (const layer of [...film.stack.layers].reverse()) {
    lines.push('[[layers]]', `n = ${index(layer.material)}`, `thickness_nm = ${layer.thickness_nm}`);
  }
  const file = path.join(dir, 'reversed.toml');
  fs.writeFileSync(file, `${lines.join('\n')}\n`);
  return file;
}
