"""The examples of docs/mitsuba.md run as written, each in a fresh empty
folder (no repository files at hand, as for a user who installed the
package with pip), and print what their comments say; the text says what
its figures depend on."""

import re

from mitsuba_setup import REPO

DOC = REPO / "docs" / "mitsuba.md"


def _examples():
    return re.findall(r"```python\n(.*?)```", DOC.read_text(), re.S)


def _run(block, name, folder, monkeypatch, capsys):
    monkeypatch.chdir(folder)
    exec(compile(block, name, "exec"), {"__name__": "__docs__"})
    printed = capsys.readouterr().out
    for _, comment in re.findall(r"^(print\(.*\))\s*#\s*(.*)$", block, re.M):
        assert comment.strip() in printed, (comment, printed)


def test_the_scene_example_runs_from_any_folder(jit, tmp_path, monkeypatch, capsys):
    _run(_examples()[0], "docs/mitsuba.md scene example", tmp_path, monkeypatch, capsys)


def test_the_inverse_rendering_example_converges(jit, tmp_path, monkeypatch, capsys):
    """It prints the recovered texture's error against the truth, which its
    comment states (so a run that does not converge fails here)."""
    block = _examples()[1]
    assert "mi.ad.Adam" in block and "thickness_nm.data" in block
    _run(block, "docs/mitsuba.md inverse rendering example", tmp_path, monkeypatch, capsys)


def test_the_text_names_the_sampler_and_where_bake_comes_from():
    text = DOC.read_text()
    tests = text[text.index("## Tests") :]
    colours = tests[tests.index("**Colours at known angles.**") : tests.index("**Rough albedo.**")]
    assert "`stratified`" in colours, "the ΔE00 figures of the sphere depend on the sampler: name it"
    setup = text[text.index("## Set-up") : text.index("## Parameters")]
    assert "`irid.bake`" in setup and "command line is not" in setup
