"""Bad input raises the documented exception with the CLI's one-line message,
never a crash (test_error_types.py holds the type of every entry point's
errors)."""

import math

import numpy as np
import pytest

import irid

INF = math.inf


def message_of_cli(run):
    """The CLI's message: its one stderr line without the `irid: ` prefix."""
    assert run.returncode == 2, (run.returncode, run.stderr)
    line = run.stderr.strip()
    assert "\n" not in line and line.startswith("irid: ")
    return line[len("irid: "):]


@pytest.mark.parametrize(
    "n, d, angles, wavelengths, needle",
    [
        ([1.0, 1.5, 1.0], [5.0, 100.0, INF], [0.0], [500.0], "must be inf (or 0)"),
        ([1.0, 1.5, 1.0], [INF, 100.0, -INF], [0.0], [500.0], "must be inf (or 0)"),
        ([1.0, 1.5, 1.0], [INF, 100.0, INF, INF], [0.0], [500.0], "d has 4 entries"),
        ([1.0, 1.5, 1.0], [INF, -1.0, INF], [0.0], [500.0], "d[1]"),
        ([1.0, 1.5, 1.0], [INF, math.nan, INF], [0.0], [500.0], "d[1]"),
        ([1.0 + 0.1j, 1.5, 1.0], [INF, 100.0, INF], [0.0], [500.0], "ambient must be lossless"),
        ([1.0, 1.5, 1.0 - 0.1j], [INF, 100.0, INF], [0.0], [500.0], "gain"),
        ([1.0, math.nan, 1.0], [INF, 100.0, INF], [0.0], [500.0], "n[0, 1]"),
        ([1.0, 0.0, 1.0], [INF, 100.0, INF], [0.0], [500.0], "n[0, 1]"),
        ([1.0, 1.5, 1.0], [INF, 100.0, INF], [91.0], [500.0], "angles"),
        ([1.0, 1.5, 1.0], [INF, 100.0, INF], [-1.0], [500.0], "angles"),
        ([1.0, 1.5, 1.0], [INF, 100.0, INF], [0.0], [-5.0], "wavelengths"),
        ([[1.0, 1.5, 1.0]] * 2, [INF, 100.0, INF], [0.0], [500.0], "shape"),
        ([1.0], [INF], [0.0], [500.0], "at least 2 media"),
        ("glass", [INF, 100.0, INF], [0.0], [500.0], "n"),
    ],
)
def test_coherent_rejects(n, d, angles, wavelengths, needle):
    with pytest.raises(ValueError) as e:
        irid.coherent(n, d, angles, wavelengths)
    assert needle in str(e.value)


def test_missing_stack_file_is_an_oserror_with_the_cli_message(tmp_path, irid_cli):
    path = tmp_path / "nope.toml"
    with pytest.raises(FileNotFoundError) as e:
        irid.Stack.load(path)
    assert isinstance(e.value, OSError)
    assert str(e.value) == message_of_cli(irid_cli("color", path))


@pytest.mark.parametrize(
    "text",
    [
        "ambient = { n = 1.0 }\n",  # no substrate
        "ambient = { n = 1.0 }\nsubstrate = { material = \"unobtainium\" }\n",
        "ambient = { n = [1.0, 0.1] }\nsubstrate = { n = 1.5 }\n",
        "ambient = { n = 1.0 }\nsubstrate = { n = [1.5, -0.1] }\n",
        "ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n[[layers]]\nn = 1.4\n",
        "ambient = { n = 1.0 }\nsubstrate = { n = 1.5, cauchy = [1.4, 0.01] }\n",
        "ambient = { n = 1.0 \n",
    ],
)
def test_bad_stack_file_raises_the_cli_message(tmp_path, irid_cli, text):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError) as e:
        irid.Stack.load(path)
    assert str(e.value) == message_of_cli(irid_cli("color", path))


@pytest.mark.parametrize(
    "kwargs, error, needle",
    [
        ({"ambient": (1.0, 0.2)}, ValueError, "ambient: must be lossless"),
        ({"substrate": (1.5, -0.1)}, ValueError, "substrate: gain"),
        ({"layers": [("unobtainium", 10)]}, ValueError, "layers[1].material: unknown material 'unobtainium'"),
        ({"layers": [(1.5, -3)]}, ValueError, "layers[1].thickness_nm"),
        ({"layers": [1.5]}, TypeError, "layers[1]: expected (material, thickness_nm)"),
        ({"layers": [{"n": 1.5}]}, ValueError, "layers[1].thickness_nm: missing"),
        ({"layers": [({"cauchy": [1.0]}, 10)]}, ValueError, "layers[1].cauchy"),
        ({"layers": [({"n": 1.5, "material": "gold"}, 10)]}, ValueError, "give exactly one of"),
        ({"layers": [({"colour": "red"}, 10)]}, ValueError, "unknown field"),
        ({"substrate": {"table": "/nonexistent/x.csv"}}, FileNotFoundError, "substrate.table"),
        ({"substrate": True}, TypeError, "bool"),
        ({"substrate": object()}, TypeError, "expected a number"),
    ],
)
def test_bad_stack_arguments(kwargs, error, needle):
    with pytest.raises(error) as e:
        irid.Stack(**kwargs)
    assert needle in str(e.value)


def test_bad_solve_color_and_material_arguments():
    film = irid.Stack(layers=[(1.33, 300)])
    with pytest.raises(ValueError, match="angles_deg: 90 is outside"):
        film.solve([500.0], [90.0])
    with pytest.raises(ValueError, match="layer: must be between 1 and 1"):
        film.solve([500.0], [0.0], thickness_nm=[10.0], layer=2)
    with pytest.raises(ValueError, match="thickness_nm"):
        film.solve([500.0], [0.0], thickness_nm=[-10.0])
    with pytest.raises(ValueError, match="wavelength"):
        film.solve([0.0], [0.0])
    with pytest.raises(ValueError, match="outside"):
        irid.Stack(substrate="gold").solve([5000.0], [0.0])
    with pytest.raises(ValueError, match="sampling 'uniform:1'"):
        film.color([0.0], sampling="uniform:1")
    with pytest.raises(ValueError, match="angle"):
        film.color([95.0])
    with pytest.raises(ValueError, match="unknown material 'kryptonite'"):
        irid.material("kryptonite")
    with pytest.raises(ValueError, match="gold"):
        irid.material("gold").index(20000.0)
    with pytest.raises(ValueError, match="either one form or keyword"):
        irid.Material(1.5, n=1.4)


def test_unsupported_white_is_a_clear_error():
    with pytest.raises(ValueError, match="white 'f2'"):
        irid.Stack(layers=[(1.33, 300)]).color([0.0], white="f2")


def test_bad_bake_and_table_arguments(tmp_path):
    film = irid.Stack(layers=[(1.33, 300)])
    with pytest.raises(ValueError, match="layer"):
        irid.bake(film, layer=3)
    with pytest.raises(ValueError, match="thickness"):
        irid.bake(film, thickness_nm=(500, 100))
    with pytest.raises(ValueError, match="either resolution or max_error"):
        irid.bake(film, resolution=(4, 4), max_error=1e-3)
    with pytest.raises(ValueError, match="max-error"):
        irid.bake(film, max_error=-1.0)
    with pytest.raises(ValueError, match="kind"):
        irid.bake(film, kind="hyperspectral")
    with pytest.raises(FileNotFoundError):
        irid.Lut.load(tmp_path / "missing.exr")
    junk = tmp_path / "junk.exr"
    junk.write_bytes(b"not an exr")
    with pytest.raises(ValueError, match="junk.exr"):
        irid.Lut.load(junk)
    lut = irid.bake(film, thickness_nm=(0, 600), resolution=(8, 4), validation_points=0)
    with pytest.raises(ValueError, match="points"):
        lut.validate(0)
    with pytest.raises(ValueError, match="wavelength_nm"):
        lut.sample(100.0, 1.0, 500.0)
    with pytest.raises(ValueError, match="broadcast"):
        lut.sample(np.zeros(3), np.zeros(4))
    with pytest.raises(OSError):
        lut.save(tmp_path / "no-such-dir" / "t.exr")
    assert not (tmp_path / "no-such-dir").exists()
