"""irid.coherent against Byrnes' tmm (the reference, 1e-9) and tmm-faster
(the API it replaces: same keys and shapes; same values where tmm-faster is
right)."""

import math

import numpy as np
import pytest
import tmm
import tmm_faster

import irid

TOL = 1e-9
KEYS = ["R_s", "R_p", "T_s", "T_p", "R_avg", "T_avg"]


def byrnes(n, d, angles_deg, wavelengths_nm):
    """Byrnes' coh_tmm at every point, in calc_coherent's layout."""
    out = {k: np.empty((len(wavelengths_nm), len(angles_deg))) for k in KEYS}
    for i, w in enumerate(wavelengths_nm):
        for j, a in enumerate(angles_deg):
            s = tmm.coh_tmm("s", list(n[i]), list(d), math.radians(a), w)
            p = tmm.coh_tmm("p", list(n[i]), list(d), math.radians(a), w)
            out["R_s"][i, j], out["R_p"][i, j] = s["R"], p["R"]
            out["T_s"][i, j], out["T_p"][i, j] = s["T"], p["T"]
    out["R_avg"] = 0.5 * (out["R_s"] + out["R_p"])
    out["T_avg"] = 0.5 * (out["T_s"] + out["T_p"])
    return out


def max_diff(a, b):
    return max(float(np.max(np.abs(a[k] - b[k]))) for k in KEYS)


def random_stack(rng, layers, *, ambient=None, gain=False, absorbing_substrate=False, wavelengths=5):
    """A random stack with per-wavelength (dispersive) indices."""
    media = layers + 2
    n = np.empty((wavelengths, media), dtype=complex)
    n[:, 0] = ambient if ambient is not None else rng.uniform(1.0, 1.8)
    for j in range(1, media):
        re = rng.uniform(0.2, 3.0, wavelengths) if j == media - 1 else rng.uniform(1.0, 2.8, wavelengths)
        im = np.zeros(wavelengths)
        if j < media - 1:
            kind = rng.integers(3)
            if kind == 1:
                im = rng.uniform(0.0, 1.5, wavelengths)
            elif kind == 2 and gain:
                im = -rng.uniform(0.0, 0.2, wavelengths)
        elif absorbing_substrate:
            im = rng.uniform(0.0, 4.0, wavelengths)
        n[:, j] = re + 1j * im
    d = [np.inf, *rng.uniform(0.0, 600.0, layers), np.inf]
    w = np.sort(rng.uniform(300.0, 1200.0, wavelengths))
    return n, d, w


ANGLES = np.array([0.0, 10.0, 33.0, 45.0, 60.0, 75.0, 89.0])


@pytest.mark.parametrize("seed", range(12))
def test_random_stacks_match_byrnes(seed):
    rng = np.random.default_rng(seed)
    n, d, w = random_stack(
        rng, int(rng.integers(0, 7)), gain=seed % 2 == 0, absorbing_substrate=seed % 3 == 0
    )
    got = irid.coherent(n, d, ANGLES, w)
    assert max_diff(got, byrnes(n, d, ANGLES, w)) <= TOL


HARD = {
    # A gain film (k < 0) on gold: tmm-faster's T is wrong here.
    "gain film on gold": ([1.0, 1.5 - 0.05j, 0.2 + 3.3j], [np.inf, 700.0, np.inf]),
    # A glass ambient over a metal: tmm-faster's T is wrong here too.
    "metal under glass": ([1.52, 1.38, 0.13 + 3.4j], [np.inf, 120.0, np.inf]),
    # Absorbing substrate, both polarizations' flux (T_p convention).
    "absorbing substrate": ([1.0, 1.5, 0.4 + 2.4j], [np.inf, 250.0, np.inf]),
    # Total internal reflection with an evanescent gap (frustrated TIR).
    "frustrated TIR": ([1.7, 1.0, 1.7], [np.inf, 150.0, np.inf]),
    # A thick absorber: the plain matrix product overflows.
    "thick absorber": ([1.0, 2.0 + 1.0j, 1.5, 1.45], [np.inf, 5000.0, 80.0, np.inf]),
    # Layers at their own critical angle near 36°/45° in the ambient.
    "near-critical layer": ([1.7, 1.0, 2.0, 1.2], [np.inf, 90.0, 40.0, np.inf]),
    # Strong gain over a mirror-like stack.
    "gain over a dielectric mirror": (
        [1.0, 1.5 - 0.2j, 2.4, 1.46, 2.4, 1.46, 1.52],
        [np.inf, 300.0, 57.0, 94.0, 57.0, 94.0, np.inf],
    ),
}


@pytest.mark.parametrize("case", sorted(HARD))
def test_hard_cases_match_byrnes(case):
    n_list, d = HARD[case]
    w = np.linspace(380.0, 780.0, 21)
    n = np.tile(np.array(n_list, dtype=complex), (len(w), 1))
    angles = np.linspace(0.0, 89.0, 31)
    got = irid.coherent(n, d, angles, w)
    assert max_diff(got, byrnes(n, d, angles, w)) <= TOL


def test_same_keys_shapes_and_dtypes_as_tmm_faster():
    rng = np.random.default_rng(7)
    n, d, w = random_stack(rng, 3, wavelengths=11)
    angles = np.linspace(0.0, 80.0, 5)
    mine = irid.coherent(n, d, angles, w)
    theirs = tmm_faster.calc_coherent(n, d, angles, w)
    assert isinstance(mine, dict)
    assert sorted(mine) == sorted(theirs) == sorted(KEYS)
    for k in KEYS:
        assert mine[k].shape == theirs[k].shape == (11, 5)
        assert mine[k].dtype == np.float64


@pytest.mark.parametrize("seed", range(8))
def test_matches_tmm_faster_where_it_is_right(seed):
    """Lossless substrates without gain: tmm-faster agrees with Byrnes'
    tmm there, and irid must agree with both."""
    rng = np.random.default_rng(100 + seed)
    n, d, w = random_stack(rng, int(rng.integers(0, 8)), wavelengths=40)
    angles = np.linspace(0.0, 89.0, 25)
    mine = irid.coherent(n, d, angles, w)
    theirs = tmm_faster.calc_coherent(n, d, angles, w)
    assert max_diff(mine, theirs) <= TOL


@pytest.mark.parametrize("ends", [(0.0, 0.0), (0, np.inf), (np.inf, 0)])
def test_zero_end_thicknesses_as_tmm_faster_examples_write_them(ends):
    """tmm-faster ignores the ambient's and substrate's thicknesses, and its
    examples give 0 there: the same call must run unchanged on irid."""
    rng = np.random.default_rng(11)
    n, d, w = random_stack(rng, 3, wavelengths=20)
    angles = np.linspace(0.0, 85.0, 7)
    zero_ends = [ends[0], *d[1:-1], ends[1]]
    want = irid.coherent(n, d, angles, w)
    got = irid.coherent(n, zero_ends, angles, w)
    for k in KEYS:
        np.testing.assert_array_equal(got[k], want[k])
    assert max_diff(got, tmm_faster.calc_coherent(n, np.array(zero_ends, dtype=float), angles, w)) <= TOL
    c = ["i", "c", "i", "c", "i"]
    np.testing.assert_array_equal(
        irid.incoherent(n, zero_ends, c, angles, w)["R_avg"], irid.incoherent(n, d, c, angles, w)["R_avg"]
    )


@pytest.mark.parametrize("case", ["gain film on gold", "metal under glass"])
def test_right_where_tmm_faster_is_wrong(case):
    n_list, d = HARD[case]
    w = np.linspace(400.0, 700.0, 16)
    n = np.tile(np.array(n_list, dtype=complex), (len(w), 1))
    angles = np.linspace(0.0, 85.0, 18)
    ref = byrnes(n, d, angles, w)
    assert max_diff(irid.coherent(n, d, angles, w), ref) <= TOL
    # tmm-faster 0.1.3 misses here by far more than rounding.
    assert max_diff(tmm_faster.calc_coherent(n, d, angles, w), ref) > 1e-3


def test_plain_lists_and_shared_indices():
    """Lists work as arrays do; a 1-D n is the same at every wavelength."""
    n_row = [1.0, 1.33, 1.0]
    w = [400.0, 500.0, 600.0]
    a = irid.coherent([n_row] * 3, [math.inf, 300.0, math.inf], [0.0, 45.0], w)
    b = irid.coherent(np.array(n_row), np.array([np.inf, 300.0, np.inf]), np.array([0.0, 45.0]), np.array(w))
    for k in KEYS:
        np.testing.assert_array_equal(a[k], b[k])


def test_any_memory_layout_reads_in_logical_order():
    """Fortran-ordered, strided and broadcast views give what a C-ordered
    copy gives."""
    rng = np.random.default_rng(2)
    w = np.linspace(400.0, 700.0, 7)
    n = np.ones((7, 4), dtype=complex)
    n[:, 1:3] = rng.uniform(1.2, 2.0, (7, 2)) + 1j * rng.uniform(0, 0.1, (7, 2))
    d = [np.inf, 120.0, 80.0, np.inf]
    angles = np.linspace(0.0, 80.0, 10)
    want = irid.coherent(n, d, angles, w)
    views = [
        (np.asfortranarray(n), d, angles, w),
        (n, d, np.linspace(0.0, 80.0, 19)[::2], w),
        (n, d, angles, np.broadcast_to(w[:, None], (7, 3))[:, 1]),
    ]
    for args in views:
        got = irid.coherent(*args)
        for k in KEYS:
            np.testing.assert_array_equal(got[k], want[k])


def test_closed_forms():
    """A bare interface (Fresnel) at normal incidence, energy conservation
    in a lossless stack, and grazing incidence at exactly 90°."""
    r = irid.coherent([1.0, 1.5], [np.inf, np.inf], [0.0, 90.0], [550.0])
    assert abs(r["R_avg"][0, 0] - 0.04) <= 1e-15
    assert abs(r["T_avg"][0, 0] - 0.96) <= 1e-15
    assert r["R_avg"][0, 1] == 1.0 and r["T_avg"][0, 1] == 0.0
    rng = np.random.default_rng(3)
    n = np.concatenate([[1.0], rng.uniform(1.2, 2.5, 6), [1.52]])
    out = irid.coherent(n, [np.inf, *rng.uniform(10, 300, 6), np.inf], np.linspace(0, 89, 90), np.linspace(380, 780, 41))
    np.testing.assert_allclose(out["R_s"] + out["T_s"], 1.0, atol=1e-13, rtol=0)
    np.testing.assert_allclose(out["R_p"] + out["T_p"], 1.0, atol=1e-13, rtol=0)
