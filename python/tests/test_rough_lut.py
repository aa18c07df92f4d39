"""irid.RoughLut: the rough table of `irid bake --rough`, loaded and
sampled as the library does, against Stack.color(..., roughness=R)."""

import numpy as np
import pytest

import irid

TARGET = 1e-2


@pytest.fixture(scope="module")
def rough_path(tmp_path_factory, luts, irid_cli):
    path = tmp_path_factory.mktemp("rough") / "soap-rough.exr"
    run = irid_cli("bake", luts / "soap-film.toml", "--rough", "--thickness", "200:400",
                   "--rough-max-error", TARGET, "-o", path)
    assert run.returncode == 0, run.stderr
    return path


@pytest.fixture(scope="module")
def rough(rough_path):
    return irid.RoughLut.load(rough_path)


def test_header_states_the_axes_and_error(rough):
    h = rough.header
    assert h["format"] == "irid-rough" and h["version"] == 1
    assert h["atlas"]["thickness_nm"] == [200.0, 400.0]
    assert h["error"]["target_max_abs"] == TARGET
    assert h["slices"] >= 2
    assert "RoughLut" in repr(rough)


def test_samples_agree_with_stack_color(rough, luts):
    """Above the grazing strip the table meets the error it states against
    irid's rough reflectance."""
    stack = irid.Stack.load(luts / "soap-film.toml")
    h = rough.header
    stated = max(h["error"]["measured"]["max_abs"])
    assert stated <= TARGET
    layer = h["layer"]
    angles = np.array([0.0, 30.0, 55.0])
    for roughness in (0.0, 0.1, 0.45, 1.0):
        for d in (210.0, 333.0, 390.0):
            layers = [(m, d if i == layer - 1 else t) for i, (m, t) in enumerate(stack.layers)]
            film = irid.Stack(ambient=stack.ambient, layers=layers, substrate=stack.substrate)
            want = film.color(angles, roughness=roughness)["reflectance_rgb"]
            got = rough.sample(d, np.cos(np.radians(angles)), roughness)
            assert got.shape == (3, 3) and got.dtype == np.float32
            np.testing.assert_allclose(got, want, atol=1.5 * stated + 1e-6)


def test_broadcasting_and_scalars(rough):
    d = np.linspace(200, 400, 5)[:, None]
    c = np.array([0.5, 0.9])
    out = rough.sample(d, c, 0.3)
    assert out.shape == (5, 2, 3)
    np.testing.assert_array_equal(out[2, 1], rough.sample(float(d[2, 0]), 0.9, 0.3))
    assert rough.sample(300, 1, 0).shape == (3,)


def test_bad_roughness_and_nan_are_value_errors(rough):
    with pytest.raises(ValueError, match=r"roughness\[1\].*\[0, 1\]"):
        rough.sample(300, 1, [0.2, 1.5])
    with pytest.raises(ValueError, match=r"roughness.*\[0, 1\]"):
        rough.sample(300, 1, -0.1)
    with pytest.raises(ValueError, match=r"cos_theta\[0\].*NaN"):
        rough.sample(300, [np.nan, 1], 0.2)


def test_each_loader_names_the_other_table(rough_path, tmp_path, luts, irid_cli):
    with pytest.raises(ValueError, match="rough table.*RoughLut.load"):
        irid.Lut.load(rough_path)
    smooth = tmp_path / "smooth.exr"
    run = irid_cli("bake", luts / "soap-film.toml", "--thickness", "0:400", "--resolution", "16,8",
                   "-o", smooth)
    assert run.returncode == 0, run.stderr
    with pytest.raises(ValueError, match="not a rough table"):
        irid.RoughLut.load(smooth)


def test_truncated_and_missing_files(rough_path, tmp_path):
    cut = tmp_path / "cut.exr"
    cut.write_bytes(rough_path.read_bytes()[:4000])
    with pytest.raises(ValueError, match="cut.exr"):
        irid.RoughLut.load(cut)
    with pytest.raises(FileNotFoundError, match="nowhere.exr"):
        irid.RoughLut.load(tmp_path / "nowhere.exr")
