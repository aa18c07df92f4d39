"""The examples of docs/python.md run as written (each in a fresh folder
holding the repository's luts/)."""

import os
import re
from pathlib import Path

import pytest

# Not imported from conftest: that name is ambiguous when pytest collects
# python/tests_mitsuba in the same run.
REPO = Path(__file__).resolve().parents[2]

DOC = REPO / "docs" / "python.md"


def blocks():
    if not DOC.exists():
        return []
    return re.findall(r"```python\n(.*?)```", DOC.read_text(), re.S)


def test_the_page_has_examples():
    assert len(blocks()) >= 3


@pytest.mark.parametrize("index", range(len(blocks())))
def test_example_runs(index, tmp_path, monkeypatch, luts, capsys):
    os.symlink(luts, tmp_path / "luts")
    monkeypatch.chdir(tmp_path)
    code = blocks()[index]
    exec(compile(code, f"{DOC.name} example {index + 1}", "exec"), {"__name__": "__docs__"})
    printed = capsys.readouterr().out
    # Each example prints what its comment says it prints.
    for line, comment in re.findall(r"^(print\(.*\))\s*#\s*(.*)$", code, re.M):
        expected = comment.split(":")[0].strip()
        assert expected in printed, (line, expected, printed)
