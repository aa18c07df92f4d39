// The irid preview: where exports come from, `window.IRID_EXPORTS`
// (embedded by `irid preview` in exports.js, which lets the page open from
// file://) or `?export=DIR/` parameters (fetched; needs the page to be
// served over http).
//
// One of the preview's classic scripts (web/preview/*.js, loaded by
// index.html in a fixed order: sources, export, meshes, matrices, shaders,
// ggx, page); each adds what it offers to IridWeb.preview and takes what
// it needs from the scripts before it. Classic scripts, not modules, so
// that the page also opens from file://.
(function (ns) {
  'use strict';

  const P = (ns.preview = ns.preview || {});

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

  Object.assign(P, { exportSources });
})((window.IridWeb = window.IridWeb || {}));
