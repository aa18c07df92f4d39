"""docs/blender.md as a reader uses it: every Python snippet that uses bpy
imports it, the layering section's export command and snippet run as
written, and the add-on installs from a zip of blender/irid_blender the
way the page says (Install from Disk, here its operator) and adds File >
Import > irid film. No rendering.

Runs with Blender as a Python module, as tools/ci/blender.sh installs it:

    python blender/tests/test_docs.py --irid target/release/irid

Prints "N passed, N failed" last and exits non-zero on any failure.
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))
from cycles_scene import Irid  # noqa: E402


class Results:
    def __init__(self):
        self.passed = self.failed = 0

    def check(self, name, ok, detail=""):
        print(f"{'ok  ' if ok else 'FAIL'}  {name} {detail}")
        if ok:
            self.passed += 1
        else:
            self.failed += 1


def test_docs_snippets(results):
    """Every Python snippet of docs/blender.md that uses bpy imports it."""
    text = (REPO / "docs" / "blender.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    missing = [b.splitlines()[0] for b in blocks if "bpy." in b and "import bpy" not in b]
    results.check("docs/blender.md: each snippet using bpy imports it", blocks and not missing,
                  f"({len(blocks)} snippets; without the import: {missing})")


def test_layering_snippet(results, irid, workdir):
    """docs/blender.md's layering section works as written: its export
    command (irid replaced by the binary under test, run where the
    repository's tests/ folder is visible) and then its Python snippet, in
    that folder, give a material with the film's group over the Principled
    BSDF."""
    text = (REPO / "docs" / "blender.md").read_text()
    section = text.split("## Layering", 1)[1].split("\n## ", 1)[0]
    commands = [line for block in re.findall(r"```sh\n(.*?)```", section, re.S)
                for line in block.splitlines() if line.startswith("irid ")]
    snippets = re.findall(r"```python\n(.*?)```", section, re.S)
    folder = workdir / "docs-layering"
    folder.mkdir(exist_ok=True)
    if not (folder / "tests").exists():
        (folder / "tests").symlink_to(REPO / "tests")
    here = os.getcwd()
    try:
        os.chdir(folder)
        for command in commands:
            irid.run(*command.split()[1:])
        scope = {}
        for snippet in snippets:
            exec(compile(snippet, "docs/blender.md (layering)", "exec"), scope)
        material = scope.get("mat")
        groups = [n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup"]
        ok, detail = bool(commands and snippets and groups), f"({len(commands)} commands)"
    except Exception as e:  # what a reader following the page would see
        ok, detail = False, f"({type(e).__name__}: {e})"
    finally:
        os.chdir(here)
    results.check("docs/blender.md: the layering section's commands and snippet run as written",
                  ok, detail)


# Run in a fresh Blender whose user folders are a scratch directory, so
# that installing does not touch the user's own add-ons.
INSTALL = """
import sys, bpy
done = bpy.ops.preferences.addon_install(filepath=sys.argv[1])
enabled = bpy.ops.preferences.addon_enable(module="irid_blender")
import irid_blender
print(done, enabled, hasattr(bpy.ops.import_scene, "irid_film"), irid_blender.__file__)
"""


def test_addon_zip(results, workdir):
    """A zip of the package folder installs and enables as an add-on, and
    the import operator is there, loaded from the installed copy."""
    archive = workdir / "irid_blender.zip"
    package = HERE.parent / "irid_blender"
    with zipfile.ZipFile(archive, "w") as z:
        for path in sorted(package.glob("*.py")):
            z.write(path, f"irid_blender/{path.name}")
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(workdir / "user"), HOME=str(workdir))
    done = subprocess.run([sys.executable, "-c", INSTALL, str(archive)], capture_output=True,
                          text=True, env=env, cwd=workdir, check=False)
    last = done.stdout.strip().splitlines()[-1:] or [done.stderr.strip()[-300:]]
    installed = str(workdir / "user")
    ok = done.returncode == 0 and last[0].startswith("{'FINISHED'} {'FINISHED'} True " + installed)
    results.check("the add-on installs from a zip of blender/irid_blender and adds File > Import",
                  ok, f"({last[0]})")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--irid", default=os.environ.get("IRID_BIN", REPO / "target/release/irid"))
    args = parser.parse_args()
    results = Results()
    with tempfile.TemporaryDirectory(prefix="irid-blender-docs-") as tmp:
        test_docs_snippets(results)
        # The snippet runs in a folder of its own: the binary by its full path.
        irid = Irid(os.path.abspath(args.irid), tmp)
        test_layering_snippet(results, irid, Path(tmp))
        test_addon_zip(results, Path(tmp))
    print(f"{results.passed} passed, {results.failed} failed")
    return 1 if results.failed else 0


if __name__ == "__main__":
    sys.exit(main())
