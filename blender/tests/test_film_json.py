"""The add-on's film.json reader against the one rule (docs/gpu.md,
"Reading film.json: the one rule"): every file of the shared fixture
tests/film-json/ (cases.json lists them) is accepted when good and, when
bad, refused with one line naming the file and the field cases.json
gives; and the add-on's own further checks in the same form: a film.json
without `white` or without `stack`, and one of another white than
Blender's, each refused through Export with one line naming the field.
No rendering.

Runs with Blender as a Python module, as tools/ci/blender.sh installs it:

    python blender/tests/test_film_json.py

Prints "N passed, N failed" last and exits non-zero on any failure.
"""

import json
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
FIXTURE = REPO / "tests" / "film-json"
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))
import irid_blender  # noqa: E402
from colour_exr import write_linear_band  # noqa: E402


def refusal(read, path):
    """The one-line message `read(path)` raises, or None when it accepts."""
    try:
        read(path)
    except irid_blender.ExportError as e:
        return str(e)
    return None


def fixture_checks():
    """(name, ok, detail) for every file of the shared fixture."""
    cases = json.loads((FIXTURE / "cases.json").read_text())
    if not cases["good"] or not cases["bad"]:
        yield "tests/film-json/cases.json lists good and bad files", False, ""
    for name in cases["good"]:
        message = refusal(irid_blender.read_film, FIXTURE / name)
        yield f"fixture {name} is accepted", message is None, f"({message})" if message else ""
    for name, field in cases["bad"].items():
        path = FIXTURE / name
        message = refusal(irid_blender.read_film, path)
        ok = (message is not None and "\n" not in message and str(path) in message
              and field in message)
        yield f"fixture {name} is refused naming {field}", ok, f"({message})"


def export_checks(workdir):
    """(name, ok, detail) for a synthetic export missing a field the rule
    and the add-on need, read as make_material reads it (Export)."""
    for field, needle in (("white", "white"), ("stack", "stack")):
        directory = workdir / f"no-{field}"
        write_linear_band(directory, (3, 3))
        film = json.loads((directory / "film.json").read_text())
        del film[field]
        (directory / "film.json").write_text(json.dumps(film))
        message = refusal(irid_blender.Export, directory)
        ok = message is not None and "\n" not in message and f"{needle} " in message
        yield f"a film.json without {field} is refused naming it", ok, f"({message})"
    directory = workdir / "d65"
    write_linear_band(directory, (3, 3))
    film = json.loads((directory / "film.json").read_text())
    film["white"] = "d65"
    (directory / "film.json").write_text(json.dumps(film))
    message = refusal(irid_blender.Export, directory)
    yield ("a film.json for white d65 passes the rule and is refused by the add-on, naming "
           "--white e", message is not None and "--white e" in message, f"({message})")


def main():
    passed = failed = 0
    with tempfile.TemporaryDirectory(prefix="irid-film-json-") as tmp:
        for name, ok, detail in [*fixture_checks(), *export_checks(Path(tmp))]:
            print(f"{'ok  ' if ok else 'FAIL'}  {name} {detail}")
            passed, failed = passed + bool(ok), failed + (not ok)
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
