// The one film.json reader rule (docs/gpu.md, "Reading film.json: the one
// rule"), for the browser preview (web/preview/) and the three.js module
// (web/irid-three.mjs, which imports this file for its side effect).
//
// A classic script, so that the preview opens from file://; as a module it
// runs the same way. It adds readFilmJson and checkFilmJson to
// globalThis.IridWeb. Every error is one line: the file, then the field.
(function (ns) {
  'use strict';

  const FILM_FORMAT = 'irid-film';
  // src/export/files.rs FILM_VERSION: the atlas of bands and corners.
  const FILM_VERSION = 3;
  const WHITES = ['d65', 'e'];

  const isObject = (x) => x !== null && typeof x === 'object' && !Array.isArray(x);
  const isSize = (x) => Number.isInteger(x) && x >= 1;

  /** Whether `pair` is [min, max] of finite numbers with lo ≤ min ≤ max ≤ hi. */
  function isRange(pair, lo, hi) {
    return Array.isArray(pair) && pair.length === 2
      && pair.every((v) => typeof v === 'number' && Number.isFinite(v))
      && lo <= pair[0] && pair[0] <= pair[1] && pair[1] <= hi;
  }

  // The integer fields, as paths of keys from the top: JSON.parse gives 3
  // for both `3` and `3.0`, which the rule tells apart (an integer is
  // written without a fraction or exponent, as Rust's and Python's readers
  // see it), so their text is read as well.
  const INTEGER_FIELDS = ['version', 'texture.width', 'texture.height'];
  const TOKEN = /"(?:[^"\\]|\\.)*"|-?\d+(?:\.\d+)?(?:[eE][+-]?\d+)?|[{}[\]:,]|true|false|null/g;

  /**
   * The number literals of INTEGER_FIELDS in `text`, a JSON text that
   * JSON.parse accepted, by field ("texture.width": "64.0"); the last one
   * where a key repeats, as JSON.parse keeps the last value.
   */
  function integerFieldText(text) {
    const found = {};
    const open = []; // per open container: whether it is an object, and its current key
    for (const [token] of text.matchAll(TOKEN)) {
      const top = open[open.length - 1];
      if (token === '{' || token === '[') {
        open.push({ object: token === '{', key: null });
      } else if (token === '}' || token === ']') {
        open.pop();
      } else if (token === ',') {
        if (top.object) top.key = null;
      } else if (token === ':') {
        // The key is set; the value follows.
      } else if (top && top.object && top.key === null) {
        top.key = JSON.parse(token);
      } else if (/^-?\d/.test(token) && open.every((c) => c.object)) {
        const field = open.map((c) => c.key).join('.');
        if (INTEGER_FIELDS.includes(field)) found[field] = token;
      }
    }
    return found;
  }

  /** Whether a field's number was written as an integer (or its text is unknown: a parsed object). */
  const writtenWhole = (text) => text === undefined || /^-?\d+$/.test(text);

  /**
   * The first way `film` breaks the rule, as "field: what", or null.
   * `written`: the text of its integer fields (integerFieldText), when it
   * was read from text.
   */
  function violation(film, written = {}) {
    if (!isObject(film)) return 'not a JSON object';
    if (film.format !== FILM_FORMAT) return `format is ${JSON.stringify(film.format)}, not "${FILM_FORMAT}"`;
    if (film.version !== FILM_VERSION || !writtenWhole(written.version)) {
      const shown = written.version ?? JSON.stringify(film.version);
      return `version ${shown}: readers take version ${FILM_VERSION} only; export the film again with this irid`;
    }
    const tex = film.texture;
    if (!isObject(tex)) return 'texture must be an object';
    if (!isSize(tex.width) || !writtenWhole(written['texture.width'])) return 'texture.width must be a positive integer';
    if (!isSize(tex.height) || !writtenWhole(written['texture.height'])) return 'texture.height must be a positive integer';
    if (!isObject(tex.row_check)) return 'texture.row_check must be an object (export the film again with this irid)';
    const d = film.domain;
    if (!isObject(d)) return 'domain must be an object';
    if (!isRange(d.thickness_nm, 0, Infinity)) return 'domain.thickness_nm must be [min, max] with 0 ≤ min ≤ max';
    if (!isRange(d.cos_theta, 0, 1)) return 'domain.cos_theta must be [min, max] with 0 ≤ min ≤ max ≤ 1';
    if (!Array.isArray(film.charts) || film.charts.length === 0) return 'charts must be a non-empty array';
    if (!isObject(film.sides)) return 'sides must be an object';
    if (!isObject(film.sides.front)) return 'sides.front must be an object';
    if (!(film.sides.back === undefined || film.sides.back === null || isObject(film.sides.back))) {
      return 'sides.back must be an object or null';
    }
    if (typeof film.opaque !== 'boolean') return 'opaque must be true or false';
    if (!WHITES.includes(film.white)) return `white is ${JSON.stringify(film.white)}, not "d65" or "e"`;
    if (!isObject(film.stack)) return 'stack must be an object';
    if (!(film.rough === undefined || film.rough === null || isObject(film.rough))) return 'rough must be an object or null';
    return null;
  }

  /**
   * Checks a parsed film.json by the rule; throws one line naming `where`
   * (the file) and the field. `written`: its integer fields' text, when
   * read from text (readFilmJson).
   */
  function checkFilmJson(film, where, written = {}) {
    const why = violation(film, written);
    if (why !== null) throw new Error(`${where}: ${why}`);
    return film;
  }

  /** film.json's text, parsed and checked; throws one line naming `where` and the fault. */
  function readFilmJson(text, where) {
    let film;
    try {
      film = JSON.parse(text);
    } catch (e) {
      throw new Error(`${where}: not JSON (${e.message})`);
    }
    return checkFilmJson(film, where, integerFieldText(text));
  }

  Object.assign(ns, { FILM_VERSION, checkFilmJson, readFilmJson });
}(globalThis.IridWeb = globalThis.IridWeb || {}));
