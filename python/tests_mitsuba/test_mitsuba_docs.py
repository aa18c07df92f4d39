"""The example of docs/mitsuba.md runs as written (in a fresh folder
holding the repository's luts/) and prints what its comment says."""

import os
import re

from mitsuba_setup import LUTS, REPO

DOC = REPO / "docs" / "mitsuba.md"


def test_the_example_runs(tmp_path, monkeypatch, capsys):
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(), re.S)
    assert len(blocks) == 1
    os.symlink(LUTS, tmp_path / "luts")
    monkeypatch.chdir(tmp_path)
    exec(compile(blocks[0], "docs/mitsuba.md example", "exec"), {"__name__": "__docs__"})
    printed = capsys.readouterr().out
    for _, comment in re.findall(r"^(print\(.*\))\s*#\s*(.*)$", blocks[0], re.M):
        assert comment.strip() in printed, (comment, printed)
