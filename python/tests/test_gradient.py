"""Stack.solve(..., gradient=True) and Stack.color(..., gradient=True): the
exact thickness derivatives against an independent 50-digit oracle
(mp_tmm.py, a characteristic-matrix solver differenced at 50 digits), on
random coherent and mixed stacks and the hard cases, within 1e-7 relative
or 1e-10 absolute; the colour derivatives against finite differences of
Stack.color; shapes, keys and bad input."""

import math
import random

import numpy as np
import pytest

import irid
import mp_tmm  # needs mpmath, which tools/ci/python.sh installs

KEYS = {"Rs": "dRs_dd", "Rp": "dRp_dd", "Ts": "dTs_dd", "Tp": "dTp_dd"}


def stack_of(indices, thicknesses, coherent=None):
    coherent = coherent or [True] * len(thicknesses)
    return irid.Stack(
        ambient=indices[0],
        layers=[(n, d, c) for n, d, c in zip(indices[1:-1], thicknesses, coherent)],
        substrate=indices[-1],
    )


def check(indices, thicknesses, wavelengths, angles, coherent=None):
    """Every derivative irid gives at every point against the oracle's."""
    coherent = coherent or [True] * len(thicknesses)
    out = stack_of(indices, thicknesses, coherent).solve(wavelengths, angles, gradient=True)
    for key in ("dR_dd", "dT_dd", *KEYS.values()):
        assert out[key].shape == (len(thicknesses), len(wavelengths), len(angles))
    for w, wl in enumerate(wavelengths):
        for a, angle in enumerate(angles):
            want = mp_tmm.solve(indices, thicknesses, coherent, wl, angle)
            for power in KEYS:
                got = out[power][w, a]
                assert abs(got - float(want[power])) <= 1e-12 + 1e-10 * abs(got), (power, got, want[power])
            for layer in range(len(thicknesses)):
                d = mp_tmm.derivative(indices, thicknesses, coherent, wl, angle, layer)
                for power, key in KEYS.items():
                    got, exact = out[key][layer, w, a], float(d[power])
                    assert abs(got - exact) <= max(1e-7 * abs(exact), 1e-10), (
                        f"{key} layer {layer} at {wl} nm, {angle}°: {got} vs {exact}"
                    )
                assert out["dR_dd"][layer, w, a] == pytest.approx(
                    0.5 * (out["dRs_dd"][layer, w, a] + out["dRp_dd"][layer, w, a]), abs=1e-300
                )


def random_index(rng, gain=False):
    k = rng.choice([0.0, rng.uniform(0.0, 0.6)]) if not gain else rng.uniform(-0.04, 0.3)
    return complex(rng.uniform(1.0, 2.8), k)


def random_coherent_case(rng, max_layers, gain):
    """A random coherent stack (its layers with gain if `gain`) and where to solve it: the
    arguments of check()."""
    layers = rng.randint(1, max_layers)
    indices = [complex(rng.uniform(1.0, 1.8), 0)]
    indices += [random_index(rng, gain=gain) for _ in range(layers)]
    indices.append(complex(rng.uniform(1.0, 2.5), rng.choice([0.0, rng.uniform(0, 4)])))
    thicknesses = [rng.uniform(0.0, 400.0) for _ in range(layers)]
    return indices, thicknesses, [rng.uniform(380, 800)], [rng.uniform(0, 85), rng.uniform(0, 85)]


def random_mixed_case(rng, max_layers):
    """A random stack with one or two incoherent layers, propagating (index
    above the ambient's, so no incoherent layer is evanescent) and at most
    weakly absorbing, and where to solve it: the arguments of check()."""
    layers = rng.randint(2, max_layers)
    indices = [complex(rng.uniform(1.0, 1.5), 0)]
    indices += [random_index(rng) for _ in range(layers)]
    indices.append(complex(rng.uniform(1.0, 2.5), rng.uniform(0, 0.3)))
    thicknesses = [rng.uniform(0.0, 300.0) for _ in range(layers)]
    coherent = [True] * layers
    for i in rng.sample(range(layers), rng.randint(1, min(2, layers))):
        coherent[i] = False
        indices[i + 1] = complex(rng.uniform(1.5, 2.0), rng.choice([0.0, 1e-4]))
        thicknesses[i] = rng.uniform(500.0, 5000.0)
    return indices, thicknesses, [rng.uniform(380, 800)], [rng.uniform(0, 80)], coherent


@pytest.mark.parametrize("seed", range(12))
def test_random_coherent_stacks(seed):
    check(*random_coherent_case(random.Random(seed), 6, gain=seed % 4 == 3))


@pytest.mark.parametrize("seed", range(8))
def test_random_mixed_stacks(seed):
    check(*random_mixed_case(random.Random(100 + seed), 6))


def test_thick_absorber():
    check([1.0, 1.4, 2 + 1j, 1.6, 1.5], [120.0, 3000.0, 80.0], [500.0], [0.0, 40.0])


def test_evanescent_gap_and_total_internal_reflection():
    # Frustrated total internal reflection through an air gap at 60°.
    check([1.5, 1.0, 1.5, 1.5], [150.0, 200.0], [600.0], [60.0])
    # Total internal reflection at the substrate under a lossy film.
    check([1.6, 2.1 + 0.3j, 1.45, 1.0], [90.0, 140.0], [550.0], [72.0])


def test_grazing_gain_and_near_critical():
    check([1.0, 1.5, 2.0 + 0.1j, 1.5], [150.0, 80.0], [500.0], [89.9, 89.999])
    check([1.0, 1.8 - 0.05j, 1.3, 2.2 - 0.02j, 1.5], [300.0, 120.0, 500.0], [550.0], [10.0])
    # sin θ0 = 0.8 from glass: β = 1.2, the index of layer 2 (q ≈ 0).
    near = math.degrees(math.asin(0.8))
    check([1.5, 2.0, 1.2, 1.7, 1.5], [80.0, 300.0, 150.0], [550.0], [near])


def test_hundred_layers():
    rng = random.Random(7)
    indices = [1.0] + [2.3 if i % 2 == 0 else 1.38 for i in range(100)] + [1.52]
    thicknesses = [(60.0 if i % 2 == 0 else 100.0) + rng.uniform(-5, 5) for i in range(100)]
    out = stack_of(indices, thicknesses).solve([700.0], [20.0], gradient=True)
    d = mp_tmm.derivative(indices, thicknesses, [True] * 100, 700.0, 20.0, 57)
    for power, key in KEYS.items():
        got, exact = out[key][57, 0, 0], float(d[power])
        assert abs(got - exact) <= max(1e-7 * abs(exact), 1e-10), (key, got, exact)


def test_color_gradient_matches_finite_differences():
    angles = [0.0, 45.0]
    for coherent in (True, False):
        stack = stack_of([1.0, 1.38, 2.3 + 0.05j, 1.5, 1.52], [110.0, 260.0, 1500.0], [True, True, coherent])
        out = stack.color(angles, gradient=True)
        plain = stack.color(angles)
        for key in ("reflectance_rgb", "transmittance_rgb"):
            np.testing.assert_allclose(out[key], plain[key], rtol=0, atol=1e-13)
        assert out["dreflectance_rgb_dd"].shape == (3, 2, 3)
        assert out["dtransmittance_rgb_dd"].shape == (3, 2, 3)
        for layer in range(3):
            h = 1e-2

            def colour(delta):
                d = [110.0, 260.0, 1500.0]
                d[layer] += delta
                s = stack_of([1.0, 1.38, 2.3 + 0.05j, 1.5, 1.52], d, [True, True, coherent])
                return s.color(angles)

            up, down, up2, down2 = (colour(x) for x in (h, -h, h / 2, -h / 2))
            for key in ("reflectance_rgb", "transmittance_rgb"):
                coarse = (up[key] - down[key]) / (2 * h)
                fine = (up2[key] - down2[key]) / h
                fd = (4 * fine - coarse) / 3
                np.testing.assert_allclose(out["d" + key + "_dd"][layer], fd, rtol=1e-6, atol=1e-10)


def test_bad_input():
    stack = stack_of([1.0, 1.5, 1.52], [100.0])
    with pytest.raises(ValueError, match="gradient"):
        stack.solve([500.0], [0.0], thickness_nm=[100.0, 120.0], gradient=True)
    with pytest.raises(ValueError, match="gradient"):
        stack.color([0.0], roughness=0.2, gradient=True)
    lasing = irid.Stack(ambient=1.0, layers=[(1.5 - 0.05j, 1e5, False)], substrate=1.0)
    with pytest.raises(ValueError, match=r"layers\[1\]"):
        lasing.solve([500.0], [0.0], gradient=True)


def test_without_layers_and_defaults():
    bare = irid.Stack(ambient=1.0, layers=[], substrate=1.5)
    out = bare.solve([500.0, 600.0], [0.0, 30.0], gradient=True)
    assert out["dR_dd"].shape == (0, 2, 2)
    assert "dR_dd" not in bare.solve([500.0], [0.0])
