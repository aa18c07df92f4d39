"""The film.json reader rule (docs/gpu.md, "Reading film.json: the one
rule"), the one every host applies the same way (tests/film-json/ holds
the shared fixture), and the field checks the rest of the add-on builds
on. No bpy here: the rule is plain JSON.

The rule: a JSON object with `format` "irid-film" and `version` 3 (an
integer); `texture` with positive whole `width` and `height` and a
`row_check` object; `domain` with `thickness_nm` [min, max], finite,
0 ≤ min ≤ max, and `cos_theta` [min, max], 0 ≤ min ≤ max ≤ 1; `charts`, a
non-empty list; `sides` with a `front` object (`back` an object or null);
`opaque`, true or false; `white`, "d65" or "e"; `stack`, an object;
`rough`, null (or absent) or an object. Anything else is refused with one
line naming the file and the field.
"""

import json
import math
import os

FILM_FORMAT = "irid-film"
# Version 3: an atlas of charts in optical thickness, several per side,
# chosen per lookup. Earlier versions are refused: export the film again.
FILM_VERSION = 3
WHITES = ("d65", "e")


class ExportError(ValueError):
    """An export directory that cannot be turned into a material."""


def read_film(film_path):
    """film.json at `film_path`, parsed and checked by the reader rule;
    ExportError (one line naming the file and the field) otherwise."""
    try:
        with open(film_path, encoding="utf-8") as f:
            film = json.load(f)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ExportError(f"irid export {film_path}: not readable JSON ({e})") from None
    check_film(film, f"irid export {film_path}")
    return film


def check_film(film, where):
    """The reader rule on a parsed film.json; `where` starts each message."""
    if not isinstance(film, dict):
        raise ExportError(f"{where}: expected a JSON object")
    if film.get("format") != FILM_FORMAT:
        found = "is missing" if "format" not in film else f"{film['format']!r}"
        raise ExportError(f"{where}: format {found}, expected {FILM_FORMAT!r}")
    version = film.get("version")
    if not is_whole(version) or version != FILM_VERSION:
        found = "is missing" if "version" not in film else f"{version!r}"
        raise ExportError(
            f"{where}: version {found}; this add-on reads version {FILM_VERSION} only: "
            "export the film again with this irid"
        )
    texture = require_object(film, "texture", where)
    for key in ("width", "height"):
        if not is_whole(texture.get(key)) or texture[key] < 1:
            raise ExportError(f"{where}: texture.{key} {texture.get(key)!r} is not a positive whole number")
    require_object(texture, "row_check", where, "texture.")
    domain = require_object(film, "domain", where)
    require_range(domain, "thickness_nm", where, "domain.", upper=math.inf)
    require_range(domain, "cos_theta", where, "domain.", upper=1.0)
    charts = film.get("charts")
    if not isinstance(charts, list) or not charts:
        raise ExportError(f"{where}: charts is missing or not a non-empty list")
    sides = require_object(film, "sides", where)
    require_object(sides, "front", where, "sides.")
    if sides.get("back") is not None and not isinstance(sides["back"], dict):
        raise ExportError(f"{where}: sides.back is neither null nor an object")
    if not isinstance(film.get("opaque"), bool):
        raise ExportError(f"{where}: opaque {film.get('opaque')!r}, expected true or false")
    if film.get("white") not in WHITES:
        found = "is missing" if "white" not in film else f"{film['white']!r}"
        raise ExportError(f"{where}: white {found}, expected 'd65' or 'e'")
    require_object(film, "stack", where)
    if film.get("rough") is not None and not isinstance(film["rough"], dict):
        raise ExportError(f"{where}: rough is neither null nor an object")


def is_whole(value):
    return isinstance(value, int) and not isinstance(value, bool)


def require_object(parent, key, where, prefix=""):
    """parent[key], a JSON object; ExportError naming prefix + key otherwise."""
    value = parent.get(key)
    if not isinstance(value, dict):
        raise ExportError(f"{where}: {prefix}{key} is missing or not an object")
    return value


def require_range(parent, key, where, prefix, upper):
    """parent[key], [min, max] of finite numbers with 0 ≤ min ≤ max ≤
    upper, as floats."""
    value = parent.get(key)
    if (not isinstance(value, list) or len(value) != 2
            or not all(is_number(v) for v in value) or not 0.0 <= value[0] <= value[1] <= upper):
        bound = "" if upper == math.inf else f" ≤ {upper:g}"
        raise ExportError(
            f"{where}: {prefix}{key} {value!r} must be [min, max] with 0 ≤ min ≤ max{bound}"
        )
    return float(value[0]), float(value[1])


def is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def require_number(parent, key, where):
    value = parent.get(key)
    if not is_number(value):
        raise ExportError(f"irid export {where}.{key}: expected a finite number, got {value!r}")
    return float(value)


def thickness_range(parent, where):
    """parent["thickness_nm"], [min, max] nm with 0 ≤ min ≤ max, as floats
    (a rough atlas's range may be a single thickness)."""
    value = parent.get("thickness_nm")
    if (not isinstance(value, list) or len(value) != 2
            or not all(is_number(v) for v in value) or not 0.0 <= value[0] <= value[1]):
        raise ExportError(f"irid export {where} is not a thickness range in nm")
    return float(value[0]), float(value[1])


def file_in(directory, name, where):
    """The path of the export's file `name` (a bare file name) in
    `directory`, which must exist."""
    if not isinstance(name, str) or not name or os.path.basename(name) != name:
        raise ExportError(f"irid export {where} is not a file name")
    path = os.path.join(directory, name)
    if not os.path.isfile(path):
        raise ExportError(f"irid export {directory}: {name} is missing")
    return path
