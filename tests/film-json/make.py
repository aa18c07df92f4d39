#!/usr/bin/env python3
"""Regenerates tests/film-json/: the shared film.json fixture every reader's
tests read (docs/gpu.md, "Reading film.json: the one rule").

    python3 tests/film-json/make.py [IRID]     # IRID: default target/release/irid

good/: the film.json of three real exports, small and fast to make: a soap
film (both sides, one set of charts), the same with the rough table
(--rough) and a film on gold at the export's default single thickness
(domain min = max, no back side).

bad/: one file per way of breaking the rule, each a good film.json changed
in one field (or not JSON, or not an object); cases.json maps each bad
file to the field its error must name (a reader's error line holds the
file's name and that text).
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

GOOD = {
    "soap-film": ["luts/soap-film.toml", "--thickness", "100:400"],
    "soap-film-rough": ["luts/soap-film.toml", "--thickness", "100:400", "--rough"],
    "two-layer-one-thickness": ["luts/two-layer.toml"],
}


def export_film(irid, args, work):
    out = os.path.join(work, "export")
    shutil.rmtree(out, ignore_errors=True)
    subprocess.run([irid, "export", *args, "-o", out, "--quiet"], cwd=ROOT, check=True)
    with open(os.path.join(out, "film.json"), encoding="utf-8") as f:
        return json.load(f)


def changed(film, path, value):
    """A copy of `film` with the field at `path` (keys) set to `value`, or
    removed when `value` is REMOVE."""
    out = json.loads(json.dumps(film))
    *parents, last = path
    node = out
    for key in parents:
        node = node[key]
    if value is REMOVE:
        del node[last]
    else:
        node[last] = value
    return out


REMOVE = object()

# name: (path of keys, new value or REMOVE, the field its error must name)
BAD = {
    "format-missing": (["format"], REMOVE, "format"),
    "format-wrong": (["format"], "irid-lut", "format"),
    "version-missing": (["version"], REMOVE, "version"),
    "version-2": (["version"], 2, "version"),
    "version-4": (["version"], 4, "version"),
    "version-string": (["version"], "3", "version"),
    "version-fraction": (["version"], 3.5, "version"),
    # JSON.parse reads 3.0 as 3; the rule's integer is written 3.
    "version-float": (["version"], 3.0, "version"),
    "texture-missing": (["texture"], REMOVE, "texture"),
    "texture-not-object": (["texture"], [64, 64], "texture"),
    "texture-width-zero": (["texture", "width"], 0, "texture.width"),
    "texture-width-missing": (["texture", "width"], REMOVE, "texture.width"),
    "texture-height-fraction": (["texture", "height"], 1.5, "texture.height"),
    "texture-width-float": (["texture", "width"], 64.0, "texture.width"),
    "texture-height-string": (["texture", "height"], "64", "texture.height"),
    "row-check-missing": (["texture", "row_check"], REMOVE, "texture.row_check"),
    "row-check-null": (["texture", "row_check"], None, "texture.row_check"),
    "domain-missing": (["domain"], REMOVE, "domain"),
    "domain-not-object": (["domain"], "100:400", "domain"),
    "thickness-missing": (["domain", "thickness_nm"], REMOVE, "domain.thickness_nm"),
    "thickness-reversed": (["domain", "thickness_nm"], [400, 100], "domain.thickness_nm"),
    "thickness-negative": (["domain", "thickness_nm"], [-10, 400], "domain.thickness_nm"),
    "thickness-one-number": (["domain", "thickness_nm"], [100], "domain.thickness_nm"),
    "thickness-string": (["domain", "thickness_nm"], ["100", 400], "domain.thickness_nm"),
    "cos-missing": (["domain", "cos_theta"], REMOVE, "domain.cos_theta"),
    "cos-above-one": (["domain", "cos_theta"], [0, 1.5], "domain.cos_theta"),
    "cos-negative": (["domain", "cos_theta"], [-0.5, 1], "domain.cos_theta"),
    "cos-reversed": (["domain", "cos_theta"], [1, 0], "domain.cos_theta"),
    "charts-missing": (["charts"], REMOVE, "charts"),
    "charts-empty": (["charts"], [], "charts"),
    "charts-not-array": (["charts"], {"0": {}}, "charts"),
    "sides-missing": (["sides"], REMOVE, "sides"),
    "sides-front-null": (["sides", "front"], None, "sides.front"),
    "sides-front-missing": (["sides", "front"], REMOVE, "sides.front"),
    "sides-back-number": (["sides", "back"], 1, "sides.back"),
    "opaque-missing": (["opaque"], REMOVE, "opaque"),
    "opaque-string": (["opaque"], "false", "opaque"),
    "white-missing": (["white"], REMOVE, "white"),
    "white-unknown": (["white"], "d50", "white"),
    "white-upper-case": (["white"], "D65", "white"),
    "stack-missing": (["stack"], REMOVE, "stack"),
    "stack-string": (["stack"], "luts/soap-film.toml", "stack"),
    "rough-number": (["rough"], 1, "rough"),
}


def main():
    irid = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 else os.path.join(ROOT, "target/release/irid")
    for sub in ("good", "bad"):
        shutil.rmtree(os.path.join(HERE, sub), ignore_errors=True)
        os.makedirs(os.path.join(HERE, sub))
    write = lambda path, text: open(os.path.join(HERE, path), "w", encoding="utf-8").write(text)
    with tempfile.TemporaryDirectory() as work:
        films = {name: export_film(irid, args, work) for name, args in GOOD.items()}
    for name, film in films.items():
        write(f"good/{name}.json", json.dumps(film, indent=1) + "\n")
    base = films["soap-film"]
    cases = {
        "bad/not-json.json": "JSON",
        "bad/not-object.json": "JSON",
        "bad/empty.json": "JSON",
    }
    write("bad/not-json.json", '{"format": "irid-film", "version": 3,')
    write("bad/not-object.json", json.dumps([base], separators=(",", ":")) + "\n")
    write("bad/empty.json", "")
    for name, (path, value, field) in BAD.items():
        write(f"bad/{name}.json", json.dumps(changed(base, path, value), separators=(",", ":")) + "\n")
        cases[f"bad/{name}.json"] = field
    write("cases.json", json.dumps(
        {"about": "each bad file and the field its error line must name (docs/gpu.md); "
                  "regenerate with python3 tests/film-json/make.py",
         "good": sorted(f"good/{n}.json" for n in films),
         "bad": cases}, indent=1) + "\n")


if __name__ == "__main__":
    main()
