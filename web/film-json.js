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

  /** The first way `film` breaks the rule, as "field: what", or null. */
  function violation(film) {
    if (!isObject(film)) return 'not a JSON object';
    if (film.format !== FILM_FORMAT) return `format is ${JSON.stringify(film.format)}, not "${FILM_FORMAT}"`;
    if (film.version !== FILM_VERSION) {
      return `version ${JSON.stringify(film.version)}: readers take version ${FILM_VERSION} only; export the film again with this irid`;
    }
    const tex = film.texture;
    if (!isObject(tex)) return 'texture must be an object';
    if (!isSize(tex.width)) return 'texture.width must be a positive integer';
    if (!isSize(tex.height)) return 'texture.height must be a positive integer';
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

  /** Checks a parsed film.json by the rule; throws one line naming `where` (the file) and the field. */
  function checkFilmJson(film, where) {
    const why = violation(film);
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
    return checkFilmJson(film, where);
  }

  Object.assign(ns, { FILM_VERSION, checkFilmJson, readFilmJson });
}(globalThis.IridWeb = globalThis.IridWeb || {}));
