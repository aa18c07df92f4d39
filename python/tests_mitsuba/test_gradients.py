"""irid_film's parameters in mi.traverse and their gradients in
llvm_ad_spectral: reverse-mode AD of a render loss against a central
finite difference of two renders with the same seed, on the table paths
(grid and atlas, smooth and rough) and the solver path."""

import numpy as np
import pytest

from mitsuba_setup import COATED_GLASS, FILM_ON_GOLD, JIT, dr, irid, mi, orthographic_sphere, use

SIZE, SPP = 12, 16
#: Thickness steps well inside a table's cells (a table is piecewise linear:
#: a step across a node measures the mean of two slopes), and a roughness step.
STEP = {"thickness_nm": 0.2, "roughness": 1e-3}
#: The seed of the renders the finite differences take, which is the seed of
#: the AD pass (mi.render's seed_grad; its primal pass must use another).
SEED = 7


@pytest.fixture(scope="module")
def gold_tables(tmp_path_factory):
    """The film on gold's spectral tables over 250–350 nm: the atlas (irid's
    default layout) and a grid."""
    folder = tmp_path_factory.mktemp("tables")
    common = dict(thickness_nm=(250.0, 350.0), kind="spectral", wavelengths_nm=(360.0, 830.0), validation_points=0)
    atlas = irid.bake(FILM_ON_GOLD, max_error=1e-2, cos_theta=(0.0, 1.0), **common)
    grid = irid.bake(FILM_ON_GOLD, resolution=(41, 24, 48), **common)
    paths = {"atlas": folder / "atlas.exr", "grid": folder / "grid.exr"}
    atlas.save(paths["atlas"])
    grid.save(paths["grid"])
    assert "atlas" in irid.Lut.load(paths["atlas"]).header and "atlas" not in irid.Lut.load(paths["grid"]).header
    return paths


def _render_loss(scene, params, weights, values, grad):
    """The linear render loss sum(weights × image) with the film's
    parameters set to ``values`` ({name: value}): in float64 from a plain
    render of seed SEED, or (``grad``) its AD derivative with respect to
    each of them, from mi.render's differential pass of seed SEED (a
    linear loss, so the primal pass's other seed does not enter)."""
    for name, value in values.items():
        params[f"sphere.bsdf.{name}"] = mi.Float(value)
        if grad:
            dr.enable_grad(params[f"sphere.bsdf.{name}"])
    params.update()
    if not grad:
        image = np.array(mi.render(scene, params, spp=SPP, seed=SEED), dtype=np.float64)
        return float(np.sum(weights * image))
    image = mi.render(scene, params, spp=SPP, seed=SEED + 1, seed_grad=SEED)
    dr.backward(dr.sum(mi.TensorXf(weights.astype(np.float32)) * image, axis=None))
    return {name: float(dr.grad(params[f"sphere.bsdf.{name}"])[0]) for name in values}


def ad_and_fd(bsdf, values, target_values, integrator="path"):
    """d(loss)/d(each of ``values``) by AD, in one backward pass, and by
    same-seed central differences; the loss weighs each pixel by how far
    the render at ``target_values`` is from the one at ``values`` (a
    linearized image distance)."""
    scene = orthographic_sphere(bsdf, SIZE, integrator=integrator)
    params = mi.traverse(scene)
    images = []
    for setting in (target_values, values):
        for name, value in setting.items():
            params[f"sphere.bsdf.{name}"] = mi.Float(value)
        params.update()
        images.append(np.array(mi.render(scene, spp=SPP, seed=3), dtype=np.float64))
    weights = images[0] - images[1]
    ad = _render_loss(scene, params, weights, values, grad=True)
    fd = {}
    for name in values:
        step = STEP[name]
        up = _render_loss(scene, params, weights, dict(values, **{name: values[name] + step}), grad=False)
        down = _render_loss(scene, params, weights, dict(values, **{name: values[name] - step}), grad=False)
        fd[name] = (up - down) / (2.0 * step)
    return ad, fd


def _check(label, ad, fd):
    for name in ad:
        ratio = ad[name] / fd[name]
        print(f"\n{label}: d(loss)/d({name}) AD {ad[name]:.6e} FD {fd[name]:.6e} AD/FD {ratio:.5f}")
        assert fd[name] != 0.0 and abs(ratio - 1.0) <= 0.02, (name, ad[name], fd[name])


THICKNESS_CASES = [(t, r) for t in ("atlas", "grid", None) for r in (0.0, 0.3)]


@pytest.mark.parametrize("table, roughness", THICKNESS_CASES, ids=[f"{t or 'solver'}-r{r}" for t, r in THICKNESS_CASES])
def test_thickness_ad_agrees_with_a_same_seed_finite_difference(jit, gold_tables, table, roughness):
    """The path integrator, smooth and rough films, both table layouts and
    the solver (irid's exact thickness derivative)."""
    bsdf = irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=300.0, roughness=roughness, table=None if table is None else gold_tables[table])
    ad, fd = ad_and_fd(bsdf, {"thickness_nm": 303.3}, {"thickness_nm": 290.0})
    _check(f"{table or 'solver'} roughness {roughness}, path", ad, fd)


def test_a_solver_films_thickness_gradient_from_the_substrate_side(jit):
    """Coated glass seen through the glass too (the stack reversed for the
    derivative), a textured thickness: AD of a few film values against a
    central difference of the solver, lane by lane."""
    bsdf = mi.load_dict(irid.mitsuba.bsdf(COATED_GLASS, thickness_nm=250.0))
    rng = np.random.default_rng(5)
    n = 400
    thickness = mi.Float(rng.uniform(150.0, 350.0, n).astype(np.float32))
    cos_theta = mi.Float(rng.uniform(0.3, 1.0, n).astype(np.float32))
    wavelengths = mi.UnpolarizedSpectrum(rng.uniform(380.0, 780.0, (4, n)).astype(np.float32))
    front = mi.Bool(rng.random(n) < 0.5)
    dr.enable_grad(thickness)
    r, t = bsdf.response(thickness, cos_theta, wavelengths, front, mi.Bool(True))
    dr.backward(dr.sum(r[0] + r[1] + r[2] + r[3]) + 0.5 * dr.sum(t[0] + t[1] + t[2] + t[3]))
    ad = np.array(dr.grad(thickness))
    w, c, f, d = (np.array(x, dtype=np.float64) for x in (wavelengths, cos_theta, front, thickness))
    step = 1e-3

    def summed(dd):
        out = np.zeros(n)
        for side, lanes in (("ambient", f > 0), ("substrate", f == 0)):
            for k in range(4):
                rr, tt = COATED_GLASS.response(c[lanes], w[k, lanes], dd[lanes], side=side)
                out[lanes] += rr + 0.5 * tt
        return out

    fd = (summed(d + step) - summed(d - step)) / (2 * step)
    np.testing.assert_allclose(ad, fd, rtol=1e-3, atol=1e-7)
    assert np.abs(fd).max() > 1e-4 and (np.abs(fd) > 1e-6).sum() > n // 4


@pytest.mark.parametrize("table", ["atlas", "grid", None], ids=["atlas", "grid", "solver"])
def test_roughness_ad_agrees_with_a_same_seed_finite_difference(jit, gold_tables, table):
    """Mitsuba's path and prb integrators detach the directions the BSDF
    samples and differentiate eval / pdf there instead, an estimator of the
    same derivative with other samples than the finite difference's, so a
    same-seed comparison takes the direct integrator with emitter sampling
    only: the directions are the emitter's, the same in every render."""
    bsdf = irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=300.0, roughness=0.3, table=None if table is None else gold_tables[table])
    ad, fd = ad_and_fd(bsdf, {"roughness": 0.3}, {"roughness": 0.4}, integrator="direct")
    _check(f"{table or 'solver'} roughness 0.3, direct", ad, fd)


def test_prb_differentiates_a_rough_table_film_in_symbolic_mode(gold_tables):
    """Mitsuba's prb in the symbolic mode register(symbolic=True) keeps (in
    the evaluated mode register() sets, Mitsuba 3.9.1's prb aborts the
    interpreter, docs/mitsuba.md)."""
    use(JIT, symbolic=True)
    try:
        bsdf = irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=300.0, roughness=0.3, table=gold_tables["grid"])
        ad, fd = ad_and_fd(bsdf, {"thickness_nm": 303.3}, {"thickness_nm": 290.0}, integrator="prb")
    finally:
        use(JIT)
    _check("grid roughness 0.3, prb", ad, fd)


@pytest.mark.parametrize("table", ["atlas", None], ids=["atlas", "solver"])
def test_sampled_weights_differentiate_through_the_microfacet_normal(jit, gold_tables, table):
    """The BSDF's own samples at fixed random numbers, where the microfacet
    normal (so the film's angle v·h) moves with the roughness: AD of the
    summed weights against a central difference of them (the solver path's
    d(R, T)/d cos θ, a float64 central difference of irid's solver, and the
    table's interpolation in cos θ both enter)."""
    bsdf = mi.load_dict(
        irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=300.0, roughness=0.3, table=None if table is None else gold_tables[table])
    )
    params = mi.traverse(bsdf)
    n = 20000
    u = np.random.default_rng(1).random((3, n)).astype(np.float32)

    def summed_weight(roughness, grad):
        params["roughness"] = mi.Float(roughness)
        if grad:
            dr.enable_grad(params["roughness"])
        params.update()
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(0.5, 0.0, float(np.sqrt(0.75)))
        si.wavelengths = mi.UnpolarizedSpectrum([450.0, 520.0, 600.0, 680.0])
        _, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
        if not grad:
            return np.array(weight, dtype=np.float64).sum()
        dr.backward(dr.sum(weight[0] + weight[1] + weight[2] + weight[3]))
        return float(dr.grad(params["roughness"])[0])

    # Small: a few samples' weights curve steeply with α near the horizon.
    step = 2e-4
    fd = (summed_weight(0.3 + step, False) - summed_weight(0.3 - step, False)) / (2 * step)
    _check(f"{table or 'solver'} sampled weights", {"roughness": summed_weight(0.3, True)}, {"roughness": fd})


def test_traverse_lists_the_films_parameters(jit, gold_tables):
    textured = {"type": "bitmap", "raw": True, "data": mi.TensorXf(np.full((4, 4, 1), 280.0, np.float32))}
    scene = mi.load_dict(
        {
            "type": "scene",
            "plain": {"type": "sphere", "bsdf": irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=300.0, roughness=0.2)},
            "painted": {
                "type": "sphere",
                "center": [3, 0, 0],
                "bsdf": irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=textured, table=gold_tables["atlas"]),
            },
        }
    )
    params = mi.traverse(scene)
    assert params["plain.bsdf.thickness_nm"][0] == 300.0
    assert abs(params["plain.bsdf.roughness"][0] - 0.2) < 1e-7
    assert np.array(params["painted.bsdf.thickness_nm.data"]).shape == (4, 4, 1)
    differentiable = {k for k in params.keys() if params.flags(k) & mi.ParamFlags.NonDifferentiable == 0}
    assert {"plain.bsdf.thickness_nm", "plain.bsdf.roughness", "painted.bsdf.thickness_nm.data"} <= differentiable
    # A smooth film's roughness is listed but cannot leave 0 (its lobes are deltas).
    assert "painted.bsdf.roughness" not in differentiable
    params["painted.bsdf.roughness"] = mi.Float(0.3)
    with pytest.raises(ValueError, match="^irid_film: roughness: this film was loaded smooth"):
        params.update()


def test_a_changed_thickness_changes_the_render(jit):
    scene = orthographic_sphere(irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=300.0), 8)
    params = mi.traverse(scene)
    before = np.array(mi.render(scene, spp=4, seed=1))
    params["sphere.bsdf.thickness_nm"] = mi.Float(250.0)
    params.update()
    after = np.array(mi.render(scene, spp=4, seed=1))
    fresh = np.array(mi.render(orthographic_sphere(irid.mitsuba.bsdf(FILM_ON_GOLD, thickness_nm=250.0), 8), spp=4, seed=1))
    assert np.abs(before - after).max() > 1e-2
    np.testing.assert_allclose(after, fresh, rtol=1e-6, atol=1e-7)
