"""irid.Stack and irid.Material: every stack-file material form, solve
against Byrnes' tmm (R, T and the complex amplitudes), colours against the
CLI."""

import json
import math

import numpy as np
import pytest
import tmm

import irid

TOL = 1e-9


def test_every_material_form_matches_the_stack_file(tmp_path):
    (tmp_path / "film.csv").write_text("wl,n\n0.3,1.40\n0.9,1.60\nwl,k\n0.3,0.02\n0.9,0.0\n")
    toml = """
ambient = { n = 1.0 }
substrate = { material = "gold" }
[[layers]]
n = [1.5, 0.1]
thickness_nm = 50
[[layers]]
material = "TiO2"
thickness_nm = 80
[[layers]]
cauchy = [1.45, 0.0036]
thickness_nm = 120
[[layers]]
sellmeier = { b = [0.6961663, 0.4079426, 0.8974794], c = [0.004679148, 0.01351206, 97.934] }
thickness_nm = 60
[[layers]]
table = "film.csv"
thickness_nm = 30
[[layers]]
n = 1.38
thickness_nm = 95
"""
    (tmp_path / "stack.toml").write_text(toml)
    from_file = irid.Stack.load(tmp_path / "stack.toml")
    built = irid.Stack(
        ambient=1.0,
        layers=[
            ((1.5, 0.1), 50),
            ("TiO2", 80),
            ({"cauchy": [1.45, 0.0036]}, 120),
            (irid.Material(sellmeier={"b": [0.6961663, 0.4079426, 0.8974794], "c": [0.004679148, 0.01351206, 97.934]}), 60),
            ({"table": str(tmp_path / "film.csv")}, 30),
            {"n": 1.38, "thickness_nm": 95},
        ],
        substrate=irid.material("Au"),
    )
    w = np.linspace(400, 800, 9)
    a = np.array([0.0, 30.0, 70.0])
    x, y = from_file.solve(w, a), built.solve(w, a)
    for k in ["Rs", "Rp", "Ts", "Tp", "rs", "rp", "ts", "tp"]:
        np.testing.assert_array_equal(x[k], y[k])
    assert [t for _, t in built.layers] == [50, 80, 120, 60, 30, 95]
    assert built.substrate.name == "gold"
    # The same stack from its text.
    z = irid.Stack.from_toml(toml, base_dir=tmp_path).solve(w, a)
    np.testing.assert_array_equal(x["R"], z["R"])


def test_material_index_forms():
    assert irid.Material(1.5).index(500.0) == 1.5
    assert irid.Material((1.5, 0.2)).index(500.0) == 1.5 + 0.2j
    assert irid.Material(1.5 - 0.05j).index(500.0) == 1.5 - 0.05j
    # Cauchy: n = A + B/λ² (λ in µm).
    assert abs(irid.Material(cauchy=[1.45, 0.01]).index(500.0) - (1.45 + 0.01 / 0.25)) < 1e-15
    silica = irid.material("fused-silica")
    n = silica.index(np.array([[400.0, 589.3], [700.0, 1000.0]]))
    assert n.shape == (2, 2) and n.dtype == np.complex128
    assert abs(n[0, 1].real - 1.4585) < 1e-3  # fused silica at the sodium D line
    gold = irid.material("gold")
    lo, hi = gold.range_nm
    assert lo < 400 and hi > 800
    assert gold.index(600.0).imag > 2.0
    assert "gold" in irid.materials() and "TiO2" in irid.materials()


def byrnes_point(stack_n, d, angle_deg, wavelength_nm):
    return {p: tmm.coh_tmm(p, stack_n, d, math.radians(angle_deg), wavelength_nm) for p in "sp"}


@pytest.mark.parametrize("name", ["two-layer", "gain-on-gold", "mirror-10", "absorbing-film"])
def test_solve_matches_byrnes_including_amplitudes(luts, name):
    stack = irid.Stack.load(luts / f"{name}.toml")
    w = np.array([380.0, 455.5, 532.0, 640.0, 780.0])
    a = np.array([0.0, 20.0, 45.0, 70.0, 88.0])
    out = stack.solve(w, a)
    media = [stack.ambient, *[m for m, _ in stack.layers], stack.substrate]
    d = [np.inf, *[t for _, t in stack.layers], np.inf]
    for i, wl in enumerate(w):
        n = [complex(m.index(wl)) for m in media]
        for j, ang in enumerate(a):
            ref = byrnes_point(n, d, ang, wl)
            for pol in "sp":
                assert abs(out["R" + pol][i, j] - ref[pol]["R"]) <= TOL
                assert abs(out["T" + pol][i, j] - ref[pol]["T"]) <= TOL
                for amp in "rt":
                    want = ref[pol][amp]
                    got = out[amp + pol][i, j]
                    assert abs(got - want) <= TOL * max(1.0, abs(want)), (pol, amp, got, want)
    np.testing.assert_allclose(out["R"], 0.5 * (out["Rs"] + out["Rp"]), rtol=0, atol=0)
    np.testing.assert_allclose(np.abs(out["rs"]) ** 2, out["Rs"], rtol=1e-12, atol=1e-15)


def test_solve_over_thicknesses_agrees_with_coherent(luts):
    stack = irid.Stack.load(luts / "two-layer.toml")
    w = np.linspace(380, 780, 17)
    a = np.linspace(0, 85, 6)
    t = np.array([0.0, 37.5, 300.0, 999.0])
    out = stack.solve(w, a, thickness_nm=t, layer=1)
    assert out["R"].shape == (4, 17, 6)
    media = [stack.ambient, *[m for m, _ in stack.layers], stack.substrate]
    n = np.array([[complex(m.index(wl)) for m in media] for wl in w])
    for k, th in enumerate(t):
        d = [np.inf, th, stack.layers[1][1], np.inf]
        ref = irid.coherent(n, d, a, w)
        for mine, theirs in [("Rs", "R_s"), ("Rp", "R_p"), ("Ts", "T_s"), ("Tp", "T_p")]:
            np.testing.assert_allclose(out[mine][k], ref[theirs], rtol=0, atol=1e-12)


def test_color_matches_the_cli(luts, irid_cli):
    path = luts / "soap-film.toml"
    angles = [0.0, 25.0, 50.0, 75.0]
    for sampling, white in [("exact", "d65"), ("uniform:16", "d65"), ("rgb3", "d65"), ("exact", "e"), ("uniform:16", "e")]:
        mine = irid.Stack.load(path).color(angles, sampling=sampling, white=white)
        run = irid_cli(
            "color", path, "--angles", ",".join(map(str, angles)), "--sampling", sampling, "--white", white, "--json"
        )
        assert run.returncode == 0, run.stderr
        cli = json.loads(run.stdout)
        for j, c in enumerate(cli):
            assert mine["angle_deg"][j] == c["angle_deg"]
            for key in ["reflectance_rgb", "transmittance_rgb", "reflectance_xyz", "transmittance_xyz"]:
                np.testing.assert_allclose(mine[key][j], c[key], rtol=0, atol=1e-15)


def test_color_of_a_lossless_film_sums_to_white():
    out = irid.Stack(layers=[(1.33, 400.0)]).color(np.linspace(0, 80, 5))
    np.testing.assert_allclose(out["reflectance_rgb"] + out["transmittance_rgb"], 1.0, atol=1e-9)
    np.testing.assert_allclose(out["reflectance_xyz"][:, 1] + out["transmittance_xyz"][:, 1], 1.0, atol=1e-12)


def test_rough_color_matches_the_cli(luts, irid_cli):
    path = luts / "absorbing-film.toml"
    angles = [0.0, 30.0, 60.0, 85.0]
    keys = ["reflectance_rgb", "reflectance_xyz", "transmittance_rgb", "transmittance_xyz"]
    ms = ["reflectance_ms_rgb", "reflectance_ms_xyz", "transmittance_ms_rgb", "transmittance_ms_xyz"]
    for roughness, side in [(0.0, "front"), (0.25, "front"), (1.0, "front"), (0.0, "substrate"), (0.25, "substrate")]:
        mine = irid.Stack.load(path).color(angles, white="e", roughness=roughness, side=side)
        assert sorted(mine) == sorted(["angle_deg", "lobe_albedo", "transmission_lobe_albedo", *keys, *ms])
        run = irid_cli("color", path, "--angles", ",".join(map(str, angles)), "--white", "e",
                       "--roughness", str(roughness), "--side", side, "--json")
        assert run.returncode == 0, run.stderr
        for j, c in enumerate(json.loads(run.stdout)):
            for key in keys + ms:
                np.testing.assert_allclose(mine[key][j], c[key], rtol=0, atol=1e-15)
            assert mine["lobe_albedo"][j] == c["lobe_albedo"]
            assert mine["transmission_lobe_albedo"][j] == c["transmission_lobe_albedo"]


@pytest.mark.parametrize("side", ["front", "substrate"])
def test_compensated_coated_glass_passes_the_furnace(side):
    """A lossless film (1.33 on glass 1.5): lobe_albedo x reflectance_ms +
    transmission_lobe_albedo x transmittance_ms is 1 within 1 % per channel
    at roughness 0.2-1, views 0-80 degrees; single scattering is not."""
    stack = irid.Stack(ambient=1.0, layers=[(1.33, 300.0)], substrate=1.5)
    angles = np.arange(0.0, 81.0, 10.0)
    worst = 1.0
    for roughness in (0.2, 0.4, 0.6, 0.8, 1.0):
        out = stack.color(angles, roughness=roughness, side=side)
        a_r, a_t = out["lobe_albedo"][:, None], out["transmission_lobe_albedo"][:, None]
        np.testing.assert_allclose(a_r * out["reflectance_ms_rgb"] + a_t * out["transmittance_ms_rgb"], 1.0, atol=0.01)
        worst = min(worst, float(np.min(a_r * out["reflectance_rgb"] + a_t * out["transmittance_rgb"])))
    zero = stack.color(angles, roughness=0.0, side=side)
    np.testing.assert_array_equal(zero["reflectance_ms_rgb"], zero["reflectance_rgb"])
    np.testing.assert_array_equal(zero["transmittance_ms_rgb"], zero["transmittance_rgb"])
    assert worst < 0.97


def test_smooth_color_from_the_substrate_is_the_reversed_stacks():
    stack = irid.Stack(ambient=1.0, layers=[(2.1, 150.0), (1.38, 90.0)], substrate=1.5)
    reversed_ = irid.Stack(ambient=1.5, layers=[(1.38, 90.0), (2.1, 150.0)], substrate=1.0)
    back, want = stack.color([0, 30, 60], side="substrate"), reversed_.color([0, 30, 60])
    for key in want:
        np.testing.assert_array_equal(back[key], want[key])


def test_sides_a_stack_cannot_be_seen_from_are_value_errors():
    on_silver = irid.Stack(layers=[(1.5, 300.0)], substrate="silver")
    for roughness in (None, 0.3):
        with pytest.raises(ValueError, match=r"^side: the substrate [^\n]*absorbs[^\n]*$"):
            on_silver.color([0.0], roughness=roughness, side="substrate")
    with pytest.raises(ValueError, match=r'^side: expected "front" or "substrate", got "back"$'):
        on_silver.color([0.0], side="back")


def test_roughness_zero_is_the_smooth_reflectance():
    stack = irid.Stack(layers=[(1.33, 400.0)])
    smooth, zero = stack.color([0, 45, 80]), stack.color([0, 45, 80], roughness=0)
    np.testing.assert_array_equal(smooth["reflectance_rgb"], zero["reflectance_rgb"])
    np.testing.assert_array_equal(zero["lobe_albedo"], 1.0)


@pytest.mark.parametrize("bad", [float("nan"), -0.1, 1.5, float("inf"), -float("inf"), 1 + 1e-12])
def test_bad_roughness_is_a_value_error(bad):
    with pytest.raises(ValueError, match=r"^roughness: must be in \[0, 1\], got [^\n]*$"):
        irid.Stack(layers=[(1.33, 400.0)]).color([0.0], roughness=bad)


@pytest.mark.parametrize("bad", ["0.5", True, [0.5], object()])
def test_roughness_of_another_type_is_a_type_error(bad):
    with pytest.raises(TypeError, match=r"^roughness: expected a number"):
        irid.Stack(layers=[(1.33, 400.0)]).color([0.0], roughness=bad)
