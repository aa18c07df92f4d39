"""What tools/bench/bench_peers.py and tools/bench/bench_python.py both call: the best
of several timed calls, and the unpolarized R and T of colour-science and of
Byrnes' tmm (coh_tmm, and inc_tmm for stacks with incoherent layers) on a
wavelength x angle grid, each as [wavelength][angle]."""

import math
import time


def best_of(repeat, fn):
    """The fastest of `repeat` calls of `fn` in seconds, and the last result."""
    best, result = math.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - start)
    return best, result


def colour_grid(n_matrix, thicknesses_nm, angles_deg, wavelengths_nm):
    """colour-science's `multilayer_tmm`, its polarizations averaged.
    n_matrix is [wavelength][medium], ambient first."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from colour.phenomena import multilayer_tmm

        r, t = multilayer_tmm(n_matrix.T, thicknesses_nm, wavelengths_nm, angles_deg)
    # (W, A, 1, 2) -> unpolarized [wavelength][angle]
    return r[:, :, 0, :].mean(axis=-1), t[:, :, 0, :].mean(axis=-1)


def byrnes_grid(n_matrix, thicknesses_nm, angles_deg, wavelengths_nm, coherence=None):
    """Byrnes' `coh_tmm` point by point, s and p averaged; its `inc_tmm`
    when `coherence` gives the stack's letters ('c' or 'i' per medium)."""
    import numpy as np
    import tmm

    d = [math.inf, *thicknesses_nm, math.inf]
    if coherence is None:
        solve = lambda pol, n_list, th, w: tmm.coh_tmm(pol, n_list, d, th, w)  # noqa: E731
    else:
        solve = lambda pol, n_list, th, w: tmm.inc_tmm(pol, n_list, d, list(coherence), th, w)  # noqa: E731
    r = np.empty((len(wavelengths_nm), len(angles_deg)))
    t = np.empty_like(r)
    for wi, w in enumerate(wavelengths_nm):
        n_list = list(n_matrix[wi])
        for ai, a in enumerate(angles_deg):
            th = math.radians(a)
            s = solve("s", n_list, th, w)
            p = solve("p", n_list, th, w)
            r[wi, ai] = 0.5 * (s["R"] + p["R"])
            t[wi, ai] = 0.5 * (s["T"] + p["T"])
    return r, t
