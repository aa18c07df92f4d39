"""irid.bake and irid.Lut: the same tables as `irid bake`, sampled as an
independent bilinear interpolation of the stored nodes does, validated as
`irid validate` does."""

import json
import math

import numpy as np
import pytest

import irid


@pytest.fixture(scope="module")
def soap(luts):
    return irid.Stack.load(luts / "soap-film.toml")


@pytest.fixture(scope="module")
def table(soap):
    return irid.bake(soap, thickness_nm=(0, 1000), resolution=(96, 24), validation_points=2000)


def bilinear(lut, t, c):
    """The table's nodes interpolated in numpy: linear in each axis value
    between the listed nodes, clamped at the ends."""
    axes = {a["name"]: np.array(a["nodes"]) for a in lut.header["axes"]}
    tn, cn = axes["thickness_nm"], axes["cos_theta"]
    data = lut.data.astype(np.float64)  # (cos, thickness, 6)

    def locate(nodes, x):
        x = np.clip(x, nodes[0], nodes[-1])
        i = np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, max(len(nodes) - 2, 0))
        if len(nodes) == 1:
            return i, np.zeros_like(x), i
        f = (x - nodes[i]) / (nodes[i + 1] - nodes[i])
        return i, f, i + 1

    i, fx, i1 = locate(tn, t)
    j, fy, j1 = locate(cn, c)
    fx, fy = fx[:, None], fy[:, None]
    lo = data[j, i] * (1 - fx) + data[j, i1] * fx
    hi = data[j1, i] * (1 - fx) + data[j1, i1] * fx
    v = lo * (1 - fy) + hi * fy
    return v[:, :3], v[:, 3:]


def test_sample_matches_independent_bilinear(table):
    rng = np.random.default_rng(5)
    t = np.concatenate([rng.uniform(-50, 1050, 4000), [0.0, 1000.0]])
    c = np.concatenate([rng.uniform(-0.1, 1.1, 4000), [1.0, 0.0]])
    r, tr = table.sample(t, c)
    assert r.shape == tr.shape == (4002, 3) and r.dtype == np.float32
    want_r, want_t = bilinear(table, t, c)
    np.testing.assert_allclose(r, want_r, rtol=0, atol=2e-6)
    np.testing.assert_allclose(tr, want_t, rtol=0, atol=2e-6)


def test_sample_broadcasts(table):
    t = np.linspace(0, 1000, 7)[:, None]
    c = np.linspace(0.2, 1.0, 5)[None, :]
    r, tr = table.sample(t, c)
    assert r.shape == (7, 5, 3)
    r1, _ = table.sample(t[3, 0], c[0, 2])
    assert r1.shape == (3,)
    np.testing.assert_array_equal(r[3, 2], r1)


def test_sample_broadcasts_as_numpy_including_strided_views(table):
    rng = np.random.default_rng(11)
    t = rng.uniform(0, 1000, (4, 1, 3))
    c = rng.uniform(0.1, 1.0, (10, 2))[::2, :1]  # a strided (5, 1) view
    r, tr = table.sample(t, c)
    assert r.shape == (4, 5, 3, 3)
    tb, cb = np.broadcast_arrays(t, c)
    want_r, want_t = table.sample(tb.ravel().copy(), cb.ravel().copy())
    np.testing.assert_array_equal(r.reshape(-1, 3), want_r)
    np.testing.assert_array_equal(tr.reshape(-1, 3), want_t)
    # A transposed (Fortran-ordered) array is read in its logical order.
    grid = rng.uniform(0, 1000, (3, 6))
    np.testing.assert_array_equal(table.sample(grid.T, 0.5)[0], table.sample(grid.T.copy(), 0.5)[0])
    with pytest.raises(ValueError, match=r"do not broadcast together \(shapes \[\[4, 1, 3\], \[2\]\]\)"):
        table.sample(t, [0.5, 0.6])


def test_nan_coordinates_raise_naming_the_argument_and_position(table):
    t = np.full((2, 3), 100.0)
    t[1, 2] = np.nan
    with pytest.raises(ValueError, match=r"^thickness_nm\[1, 2\]: NaN is not a coordinate$"):
        table.sample(t, 1.0)
    # After broadcasting: cos θ NaN at [0] is NaN at every thickness of row 0.
    with pytest.raises(ValueError, match=r"^cos_theta\[0, 0\]: NaN"):
        table.sample(np.zeros((1, 4)), [[np.nan], [1.0]])
    with pytest.raises(ValueError, match=r"^cos_theta: NaN"):
        table.sample(100.0, np.nan)


def test_infinite_coordinates_clamp_to_the_axis_ends_as_any_value_beyond_them(table):
    axes = {a["name"]: a["nodes"] for a in table.header["axes"]}
    (t0, t1), (c0, c1) = [(axes[k][0], axes[k][-1]) for k in ["thickness_nm", "cos_theta"]]
    inf = np.inf
    got = table.sample([inf, -inf, 1e300, 300.0, 300.0, 300.0], [0.5, 0.5, 0.5, inf, -inf, -1e300])
    want = table.sample([t1, t0, t1, 300.0, 300.0, 300.0], [0.5, 0.5, 0.5, c1, c0, c0])
    for g, w in zip(got, want):
        np.testing.assert_array_equal(g, w)
        assert np.isfinite(g).all()


def test_nodes_hold_the_exact_colour(table, soap):
    axes = {a["name"]: a["nodes"] for a in table.header["axes"]}
    for ti in [0, 17, 95]:
        th = axes["thickness_nm"][ti]
        film = irid.Stack(ambient=soap.ambient, layers=[(soap.layers[0][0], th)], substrate=soap.substrate)
        for cj in [3, 23]:
            cos = axes["cos_theta"][cj]
            want = film.color([math.degrees(math.acos(cos))])
            r, tr = table.sample(th, cos)
            np.testing.assert_allclose(r, want["reflectance_rgb"][0], atol=2e-6)
            np.testing.assert_allclose(tr, want["transmittance_rgb"][0], atol=2e-6)


def test_same_table_as_the_cli(tmp_path, table, luts, irid_cli):
    path = tmp_path / "cli.exr"
    run = irid_cli("bake", luts / "soap-film.toml", "--thickness", "0:1000", "--resolution", "96,24",
                   "--validate-points", "2000", "-o", path)
    assert run.returncode == 0, run.stderr
    cli = irid.Lut.load(path)
    assert cli.header == table.header
    np.testing.assert_array_equal(cli.data, table.data)


def test_save_load_and_validate_as_the_cli(tmp_path, table, irid_cli, luts):
    path = tmp_path / "py.exr"
    table.save(path)
    again = irid.Lut.load(path)
    assert again.header == table.header and again.kind == "rgb"
    np.testing.assert_array_equal(again.data, table.data)
    mine = again.validate(3000, seed=9)
    run = irid_cli("validate", path, "--points", 3000, "--seed", 9, "--json")
    assert run.returncode == 0, run.stderr
    assert mine == json.loads(run.stdout)
    assert mine["points"] == 3000
    # The worst point's error is the table's sample against the exact colour there.
    th, cos, _ = mine["worst_point"]
    stack = irid.Stack.load(luts / "soap-film.toml")
    film = irid.Stack(ambient=stack.ambient, layers=[(stack.layers[0][0], th)], substrate=stack.substrate)
    exact = film.color([math.degrees(math.acos(cos))])
    r, tr = table.sample(th, cos)
    err = np.abs(np.concatenate([r - exact["reflectance_rgb"][0], tr - exact["transmittance_rgb"][0]]))
    assert abs(err.max() - max(mine["max_abs"])) <= 1e-6
    # The header's validation is the same computation with the bake's seed.
    assert table.validate(2000) == table.header["error"]["validation"]


def test_error_target_is_met(soap):
    lut = irid.bake(soap, thickness_nm=(0, 400), max_error=1e-2, validation_points=1000)
    h = lut.header
    assert h["error"]["target_max_abs"] == 1e-2
    assert h["error"]["bake_check"]["max_abs_all"] <= 1e-2
    assert max(lut.validate(1000, seed=3)["max_abs"]) <= 1e-2


@pytest.mark.parametrize("layout, version", [("grid", 2), ("atlas", 4)])
def test_layout_chooses_the_table_as_the_cli(tmp_path, soap, luts, irid_cli, layout, version):
    """layout= is `irid bake --layout`: the same table, header and data, from
    either, and the error target met on both."""
    lut = irid.bake(soap, thickness_nm=(0, 400), max_error=1e-2, cos_theta=(0.2, 1), layout=layout,
                    validation_points=500)
    header = lut.header
    assert header["version"] == version and bool(header.get("atlas")) == (layout == "atlas")
    assert header["error"]["bake_check"]["max_abs_all"] <= 1e-2
    path = tmp_path / "cli.exr"
    run = irid_cli("bake", luts / "soap-film.toml", "--thickness", "0:400", "--max-error", "1e-2",
                   "--angles", "0.2:1", "--layout", layout, "--validate-points", "500", "-o", path)
    assert run.returncode == 0, run.stderr
    cli = irid.Lut.load(path)
    assert cli.header == header
    np.testing.assert_array_equal(cli.data, lut.data)


def test_layout_is_checked(soap):
    with pytest.raises(ValueError, match=r"^layout 'cubes': expected atlas or grid"):
        irid.bake(soap, thickness_nm=(0, 400), max_error=1e-2, layout="cubes")
    with pytest.raises(ValueError, match=r"^layout: an atlas is sized for an error target"):
        irid.bake(soap, thickness_nm=(0, 400), resolution=(16, 8), layout="atlas")
    grid = irid.bake(soap, thickness_nm=(0, 400), resolution=(16, 8), validation_points=0)
    assert grid.header["version"] == 2


def test_spectral_atlas_table(soap):
    """An error target bakes a spectral table on the atlas (format version
    4): its data are the atlas image per wavelength node, and irid's
    sampler meets the target against the solver above its aliased strip."""
    lut = irid.bake(soap, thickness_nm=(0, 1000), max_error=1e-2, cos_theta=(0, 1), kind="spectral",
                    wavelengths_nm=(360, 830), validation_points=2000)
    header = lut.header
    assert header["version"] == 4 and lut.kind == "spectral"
    w = header["axes"][2]["nodes"]
    assert lut.data.shape == (len(w), header["atlas"]["height"], header["atlas"]["width"], 2)
    floor = header["atlas"]["aliased_below_cos"]
    rng = np.random.default_rng(5)
    d = rng.uniform(0, 1000, 2000)
    c = rng.uniform(floor, 1, 2000)
    lam = rng.uniform(360, 830, 2000)
    r, t = lut.sample(d, c, lam)
    ref_r, ref_t = soap.response(c, lam, thickness_nm=d)
    assert np.abs(r - ref_r).max() <= 1e-2 and np.abs(t - ref_t).max() <= 1e-2


def test_spectral_table(soap):
    lut = irid.bake(soap, thickness_nm=(100, 600), resolution=(11, 6, 9), kind="spectral",
                    wavelengths_nm=(400, 720), validation_points=0)
    assert lut.kind == "spectral" and lut.data.shape == (9, 6, 11, 2)
    axes = {a["name"]: np.array(a["nodes"]) for a in lut.header["axes"]}
    t, c, w = axes["thickness_nm"], axes["cos_theta"], axes["wavelength_nm"]
    T, C, W = np.meshgrid(t, c, w, indexing="ij")
    r, tr = lut.sample(T, C, W)
    assert r.shape == (11, 6, 9)
    ref = soap.solve(w, np.degrees(np.arccos(c)), thickness_nm=t)
    # ref: (thickness, wavelength, angle) -> (thickness, angle, wavelength)
    np.testing.assert_allclose(r, ref["R"].transpose(0, 2, 1), atol=1e-6)
    np.testing.assert_allclose(tr, ref["T"].transpose(0, 2, 1), atol=1e-6)
    # Wavelengths clamp at the axis's ends, ±inf included; NaN raises.
    for beyond, end in [(np.inf, w[-1]), (-np.inf, w[0]), (1e6, w[-1])]:
        np.testing.assert_array_equal(lut.sample(300.0, 0.7, beyond), lut.sample(300.0, 0.7, end))
    with pytest.raises(ValueError, match=r"^wavelength_nm\[1\]: NaN"):
        lut.sample(300.0, 0.7, [500.0, np.nan])
