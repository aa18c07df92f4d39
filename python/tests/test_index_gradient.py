"""Stack.solve(..., gradient=True, index_gradient=True): the exact
derivatives of Rs, Rp, Ts, Tp (and R, T) by each layer's n and k against
the independent 50-digit oracle (mp_tmm.index_derivative, a characteristic-
matrix solver differenced at 50 digits), within 1e-7 relative or 1e-10
absolute, on random coherent and mixed stacks and the hard cases (thick
absorber, evanescent gap, total internal reflection, gain, 100 layers); keys,
shapes and bad input."""

import math
import random

import numpy as np
import pytest

import mp_tmm  # needs mpmath, which tools/ci/python.sh installs
from test_gradient import random_coherent_case, random_mixed_case, stack_of

POWERS = ("Rs", "Rp", "Ts", "Tp")


def check(indices, thicknesses, wavelengths, angles, coherent=None):
    """Every index derivative irid gives at every point against the
    oracle's; the thickness derivatives and the solve as gradient=True
    alone gives them."""
    coherent = coherent or [True] * len(thicknesses)
    stack = stack_of(indices, thicknesses, coherent)
    out = stack.solve(wavelengths, angles, gradient=True, index_gradient=True)
    plain = stack.solve(wavelengths, angles, gradient=True)
    for key, value in plain.items():
        np.testing.assert_allclose(out[key], value, rtol=1e-12, atol=1e-15, err_msg=key)
    shape = (len(thicknesses), len(wavelengths), len(angles))
    for part in ("n", "k"):
        for power in ("R", "T", *POWERS):
            assert out[f"d{power}_d{part}"].shape == shape
        for w, wl in enumerate(wavelengths):
            for a, angle in enumerate(angles):
                for layer in range(len(thicknesses)):
                    d = mp_tmm.index_derivative(indices, thicknesses, coherent, wl, angle, layer, part)
                    for power in POWERS:
                        got, exact = out[f"d{power}_d{part}"][layer, w, a], float(d[power])
                        assert abs(got - exact) <= max(1e-7 * abs(exact), 1e-10), (
                            f"d{power}_d{part} layer {layer} at {wl} nm, {angle}°: {got} vs {exact}"
                        )
                    for power in ("R", "T"):
                        mean = 0.5 * (out[f"d{power}s_d{part}"] + out[f"d{power}p_d{part}"])
                        assert out[f"d{power}_d{part}"][layer, w, a] == mean[layer, w, a]


@pytest.mark.parametrize("seed", range(8))
def test_random_coherent_stacks(seed):
    check(*random_coherent_case(random.Random(200 + seed), 5, gain=seed % 4 == 3))


@pytest.mark.parametrize("seed", range(6))
def test_random_mixed_stacks(seed):
    check(*random_mixed_case(random.Random(300 + seed), 5))


def test_thick_absorber():
    check([1.0, 1.4, 2 + 1j, 1.6, 1.5], [120.0, 3000.0, 80.0], [500.0], [0.0, 40.0])


def test_evanescent_gap_and_total_internal_reflection():
    # Frustrated total internal reflection through an air gap at 60°.
    check([1.5, 1.0, 1.5, 1.5], [150.0, 200.0], [600.0], [60.0])
    # Total internal reflection at the substrate under a lossy film.
    check([1.6, 2.1 + 0.3j, 1.45, 1.0], [90.0, 140.0], [550.0], [72.0])


def test_gain_and_near_critical():
    check([1.0, 1.8 - 0.05j, 1.3, 2.2 - 0.02j, 1.5], [300.0, 120.0, 500.0], [550.0], [10.0])
    # sin θ0 = 0.8 from glass: β = 1.2 near layer 2's index (q ≈ 0).
    near = math.degrees(math.asin(0.8))
    check([1.5, 2.0, 1.21, 1.7, 1.5], [80.0, 300.0, 150.0], [550.0], [near])


def test_many_points_on_the_pool_match_one_by_one():
    # A grid large enough to be cut into tasks on the pool: the same
    # derivatives as each point solved alone.
    stack = stack_of([1.0, 1.45, 2.3 + 0.02j, 1.45, 1.52], [95.0, 60.0, 95.0])
    wavelengths, angles = np.linspace(400.0, 700.0, 300), np.linspace(0.0, 80.0, 7)
    out = stack.solve(wavelengths, angles, gradient=True, index_gradient=True)
    for w in (0, 151, 299):
        for a in (0, 6):
            one = stack.solve([wavelengths[w]], [angles[a]], gradient=True, index_gradient=True)
            for key in ("dR_dn", "dT_dk", "dRp_dk", "dTs_dn"):
                assert out[key][:, w, a] == pytest.approx(one[key][:, 0, 0], rel=1e-12, abs=1e-15)


def test_opt_in_and_bad_input():
    stack = stack_of([1.0, 1.5, 1.52], [100.0])
    assert "dR_dn" not in stack.solve([500.0], [0.0], gradient=True)
    with pytest.raises(ValueError, match="index_gradient"):
        stack.solve([500.0], [0.0], index_gradient=True)
    with pytest.raises(ValueError, match="gradient"):
        stack.solve([500.0], [0.0], thickness_nm=[100.0], gradient=True, index_gradient=True)
    bare = stack_of([1.0, 1.5], [])
    assert bare.solve([500.0, 600.0], [0.0], gradient=True, index_gradient=True)["dT_dk"].shape == (0, 2, 1)


def test_hundred_layers():
    rng = random.Random(11)
    indices = [1.0] + [2.3 + 0.01j if i % 2 == 0 else 1.38 for i in range(100)] + [1.52]
    thicknesses = [(60.0 if i % 2 == 0 else 100.0) + rng.uniform(-5, 5) for i in range(100)]
    out = stack_of(indices, thicknesses).solve([700.0], [20.0], gradient=True, index_gradient=True)
    for layer in (0, 57, 99):
        for part in ("n", "k"):
            d = mp_tmm.index_derivative(indices, thicknesses, [True] * 100, 700.0, 20.0, layer, part)
            for power in POWERS:
                got, exact = out[f"d{power}_d{part}"][layer, 0, 0], float(d[power])
                assert abs(got - exact) <= max(1e-7 * abs(exact), 1e-10), (power, part, layer, got, exact)
