"""irid.fit and irid.fit_color: thicknesses recovered from synthetic
measurements of hidden stacks, the batched fit (and the same call over
chunks on a local Dask cluster), and bad input as ValueError naming the
argument."""

import numpy as np
import pytest

import irid

WAVELENGTHS = np.arange(380.0, 781.0, 2.0)
ANGLES = np.array([0.0, 45.0])


def stack_of(thicknesses, indices):
    return irid.Stack(1.0, [(n, d) for n, d in zip(indices, thicknesses)], 1.52)


def measure(stack, rng, noise=1e-3):
    R = stack.solve(WAVELENGTHS, ANGLES)["R"]
    return R + noise * rng.standard_normal(R.shape)


@pytest.mark.parametrize("layers", [1, 2, 3, 4, 5, 6])
def test_recovers_hidden_stacks(layers):
    rng = np.random.default_rng(100 + layers)
    truth = rng.uniform(40.0, 300.0, layers)
    indices = [rng.uniform(2.0, 2.4) if i % 2 == 0 else rng.uniform(1.38, 1.5) for i in range(layers)]
    R = measure(stack_of(truth, indices), rng)
    start = truth * rng.uniform(0.6, 1.4, layers)
    bounds = [(0.5 * d, 1.5 * d) for d in truth]
    vary = list(range(1, layers + 1))
    fit = irid.fit(stack_of(start, indices), vary, WAVELENGTHS, ANGLES, R=R, sigma=1e-3, bounds=bounds)
    assert np.all(np.abs(fit.thickness_nm - truth) <= 3 * fit.sigma_nm), (fit, truth)
    assert np.all(fit.sigma_nm <= 1.0)
    assert 0.7 < fit.chi2 / fit.degrees_of_freedom < 1.3
    assert fit.residual_R.shape == R.shape
    np.testing.assert_allclose(fit.stack.layers[0][1], fit.thickness_nm[0])


def test_batch_matches_single_fits():
    rng = np.random.default_rng(7)
    indices = [2.3, 1.45]
    truths = [np.array([100.0 + 7 * i, 200.0 - 5 * i]) for i in range(6)]
    cube = np.stack([measure(stack_of(t, indices), rng) for t in truths]).reshape(2, 3, *WAVELENGTHS.shape, 2)
    start = stack_of([110.0, 190.0], indices)
    bounds = [(60.0, 160.0), (120.0, 260.0)]
    batch = irid.fit(start, [1, 2], WAVELENGTHS, ANGLES, R=cube, sigma=1e-3, bounds=bounds)
    assert batch.thickness_nm.shape == (2, 3, 2) and batch.chi2.shape == (2, 3)
    assert batch.stack is None
    for i in range(6):
        one = irid.fit(start, [1, 2], WAVELENGTHS, ANGLES, R=cube.reshape(6, -1, 2)[i], sigma=1e-3, bounds=bounds)
        np.testing.assert_allclose(batch.thickness_nm.reshape(6, 2)[i], one.thickness_nm, atol=1e-6)
        assert np.all(np.abs(one.thickness_nm - truths[i]) <= 3 * one.sigma_nm)


def test_ambiguity_is_reported():
    # R of a lossless film on a bare interface at one wavelength and angle
    # repeats every half wave of optical path: two orders fit equally.
    # At 500 and 600 nm, R of a free-standing film of index 1.5 is the
    # same at 100 and 900 nm: both phases 4πnd/λ reflect about whole turns.
    stack = irid.Stack(1.0, [(1.5, 100.0)], 1.0)
    R = stack.solve([500.0, 600.0], [0.0])["R"]
    fit = irid.fit(stack, [1], [500.0, 600.0], [0.0], R=R, sigma=1e-3, bounds=[(0.0, 1000.0)])
    assert fit.ambiguous
    others = [t[0] for t, _ in fit.alternatives[0]]
    assert any(abs(d - 900.0) < 1.0 for d in others + [fit.thickness_nm[0]]), fit.alternatives


def test_color_fit_reaches_reachable_targets():
    hidden = irid.Stack(1.0, [(1.33, 420.0)], 1.0)
    angles = [0.0, 30.0, 60.0]
    target = hidden.color(angles)["reflectance_rgb"]
    guess = irid.Stack(1.0, [(1.33, 300.0)], 1.0)
    fit = irid.fit_color(guess, [1], angles, target, bounds=[(150.0, 450.0)])
    assert np.all(fit.delta_e2000 <= 0.5), fit
    got = fit.stack.color(angles)["reflectance_rgb"]
    np.testing.assert_allclose(got, fit.rgb, atol=1e-12)


def test_color_fit_says_when_one_angle_cannot_tell_orders_apart():
    # A 2.0-index film on glass: at 0 deg its first order (92 nm) and its
    # third (near 358 nm) reflect colours within 1 ΔE00; at 0, 45 and 70 deg
    # they differ by tens.
    hidden = irid.Stack(1.0, [(2.0, 92.0)], 1.52)
    guess = irid.Stack(1.0, [(2.0, 200.0)], 1.52)
    one = irid.fit_color(guess, [1], [0.0], hidden.color([0.0])["reflectance_rgb"], bounds=[(60.0, 420.0)])
    assert abs(one.thickness_nm[0] - 92.0) < 0.5, one
    assert one.ambiguous and one.tolerance_de2000 == 1.0
    thicknesses, delta_e = one.alternatives[0]
    assert abs(thicknesses[0] - 358.0) < 10.0, one.alternatives
    assert max(delta_e) <= max(one.delta_e2000) + one.tolerance_de2000
    angles = [0.0, 45.0, 70.0]
    three = irid.fit_color(guess, [1], angles, hidden.color(angles)["reflectance_rgb"], bounds=[(60.0, 420.0)])
    assert abs(three.thickness_nm[0] - 92.0) < 0.5, three
    assert not three.ambiguous and three.alternatives == []


def test_color_fit_of_a_rough_film():
    hidden = irid.Stack(1.0, [(1.33, 380.0)], 1.0)
    angles = [0.0, 45.0]
    target = hidden.color(angles, roughness=0.3)["reflectance_rgb"]
    fit = irid.fit_color(hidden, [1], angles, target, roughness=0.3, bounds=[(300.0, 450.0)])
    assert np.all(fit.delta_e2000 <= 0.5), fit


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(vary=[0]), "vary"),
        (dict(vary=[3]), "vary"),  # the substrate
        (dict(vary=[5]), "vary"),
        (dict(vary=[]), "vary"),
        (dict(bounds=[(200.0, 300.0)]), "bounds[0]"),  # excludes the start, 100 nm
        (dict(bounds=[(50.0, 150.0), (1.0, 2.0)]), "bounds"),
        (dict(R=np.full((3, 1), np.nan)), "R"),
        (dict(R=np.zeros((2, 1))), "R"),
        (dict(wavelengths_nm=[-400.0, 500.0, 600.0]), "wavelengths_nm"),
        (dict(angles_deg=[90.0]), "angles_deg"),
        (dict(sigma=0.0), "sigma"),
    ],
)
def test_bad_input_names_the_argument(kwargs, name):
    args = dict(
        stack=irid.Stack(1.0, [(1.5, 100.0), (2.0, 50.0)], 1.5),
        vary=[1],
        wavelengths_nm=[400.0, 500.0, 600.0],
        angles_deg=[0.0],
        R=np.full((3, 1), 0.05),
    )
    args.update(kwargs)
    with pytest.raises(ValueError, match=r"^" + name.replace("[", r"\[").replace("]", r"\]")):
        irid.fit(**args)


def test_unreachable_colour_is_refused():
    stack = irid.Stack(1.0, [(1.33, 300.0)], 1.0)
    with pytest.raises(ValueError, match=r"^target_rgb\[1\]: .*passive film"):
        irid.fit_color(stack, [1], [0.0, 30.0], [[0.1, 0.1, 0.1], [2.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match=r"^target_rgb"):
        irid.fit_color(stack, [1], [0.0], [[0.1, 0.1]])


def test_dask_chunks_match_the_batch():
    distributed = pytest.importorskip("dask.distributed")
    rng = np.random.default_rng(11)
    indices = [2.3, 1.45]
    cube = np.stack([measure(stack_of([100.0 + 3 * i, 180.0 - 2 * i], indices), rng) for i in range(8)])
    # A worker gets the stack as JSON: an irid.Stack does not pickle.
    start_json = stack_of([110.0, 190.0], indices).to_json()
    bounds = [(60.0, 160.0), (120.0, 260.0)]

    def fit_chunk(chunk):
        start = irid.Stack.from_json(start_json)
        return irid.fit(start, [1, 2], WAVELENGTHS, ANGLES, R=chunk, sigma=1e-3, bounds=bounds).thickness_nm

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            futures = client.map(fit_chunk, np.array_split(cube, 4))
            chunks = client.gather(futures)
    whole = fit_chunk(cube)
    np.testing.assert_allclose(np.concatenate(chunks), whole, atol=1e-6)


def test_the_fitting_examples_of_docs_inverse_run(capsys):
    """The Python examples of docs/inverse.md's "Fitting" sections run in
    order, in one namespace, and print what their comments say."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "inverse.md").read_text()
    sections = re.split(r"^## ", text, flags=re.M)
    code = [b for s in sections if s.startswith("Fitting") for b in re.findall(r"```python\n(.*?)```", s, re.S)]
    assert len(code) >= 3
    namespace = {"__name__": "__docs__"}
    for block in code:
        exec(compile(block, "docs/inverse.md", "exec"), namespace)
        printed = capsys.readouterr().out
        for line, comment in re.findall(r"^(print\(.*\))\s*#\s*(.*)$", block, re.M):
            assert comment.strip() in printed, (line, comment, printed)
