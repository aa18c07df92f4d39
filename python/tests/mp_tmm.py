"""An independent thin-film solver at 50 significant digits (mpmath), the
oracle of test_gradient.py.

Written from the textbook characteristic-matrix form (H. A. Macleod,
"Thin-Film Optical Filters", ch. 2; Born & Wolf, "Principles of Optics",
sec. 1.6), not from irid's Γ recursion: each layer's 2×2 matrix relates the
tangential fields (E, H) at its top to those at its bottom, their product
over the stack gives (B, C) at the top for a unit tangential E in the
substrate, and r, t follow from the ambient's admittance. Fields vary as
e^{-iωt} with an index n + ik (k > 0 absorbing), so a layer's matrix is
[[cos δ, -i sin δ / η], [-i η sin δ, cos δ]], δ = k0 q d, q = √(n² − β²) on
the branch Im q ≥ 0, and the tilted admittance η is q (s) or n²/q (p).

Incoherent (thick) layers follow Katsidis & Siapkas (Appl. Opt. 41, 3978,
2002): each coherent group between two incoherent media is a power matrix
(1/|t|²) [[1, −|r'|²], [|r|², |t t'|² − |r r'|²]], each incoherent layer
[[1/P, 0], [0, P]] with P = |e^{iδ}|², and R, T come from their product.
At 50 digits nothing under- or overflows, so thick absorbers need no care.
"""

import math

import mpmath as mp

mp.mp.dps = 50


def _q(n, beta_sq):
    q = mp.sqrt(n * n - beta_sq)
    if mp.im(q) < 0 or (mp.im(q) == 0 and mp.re(q) < 0):
        q = -q
    return q


def _eta(n, q, pol):
    return q if pol == "s" else n * n / q


def _group(ns, ds, k0, beta_sq, pol):
    """r, t (tangential E) of the media ns (first and last semi-infinite)
    with layers ds in between, light from ns[0]."""
    qs = [_q(n, beta_sq) for n in ns]
    etas = [_eta(n, q, pol) for n, q in zip(ns, qs)]
    m = mp.eye(2)
    for n, q, eta, d in zip(ns[1:-1], qs[1:-1], etas[1:-1], ds):
        delta = k0 * q * d
        c, s = mp.cos(delta), mp.sin(delta)
        m = m * mp.matrix([[c, -1j * s / eta], [-1j * eta * s, c]])
    bc = m * mp.matrix([[1], [etas[-1]]])
    b, c = bc[0], bc[1]
    eta0 = etas[0]
    den = eta0 * b + c
    return (eta0 * b - c) / den, 2 * eta0 / den, etas


def solve(indices, thicknesses, coherent, wavelength_nm, angle_deg):
    """(Rs, Rp, Ts, Tp) of the stack: `indices` ambient, layers, substrate
    (complex), `thicknesses` in nm, `coherent` one flag per layer."""
    ns = [mp.mpc(n) for n in indices]
    ds = [mp.mpf(d) for d in thicknesses]
    k0 = 2 * mp.pi / mp.mpf(wavelength_nm)
    # cos θ0 as irid computes it from degrees in float64, then exact: near
    # a critical angle the answer is that sensitive to β.
    cos0 = mp.mpf(math.cos(math.radians(angle_deg)))
    beta_sq = mp.re(ns[0]) ** 2 * (1 - cos0 * cos0)
    # Incoherent media: the ambient, the incoherent layers, the substrate.
    cuts = [0] + [i + 1 for i, c in enumerate(coherent) if not c] + [len(ns) - 1]
    out = {}
    for pol in ("s", "p"):
        total = mp.eye(2)
        for g, (a, b) in enumerate(zip(cuts, cuts[1:])):
            group_n = ns[a : b + 1]
            group_d = ds[a : b - 1]
            r, t, etas = _group(group_n, group_d, k0, beta_sq, pol)
            r_up, t_up, _ = _group(group_n[::-1], group_d[::-1], k0, beta_sq, pol)
            if g > 0:
                # The incoherent layer `a` above this group: one pass.
                q = _q(ns[a], beta_sq)
                p = mp.exp(-2 * k0 * mp.im(q) * ds[a - 1])
                total = total * mp.matrix([[1 / p, 0], [0, p]])
            rr, rr_up = abs(r) ** 2, abs(r_up) ** 2
            tt = abs(t * t_up) ** 2
            total = total * (mp.matrix([[1, -rr_up], [rr, tt - rr * rr_up]]) / abs(t) ** 2)
        eta0 = _eta(ns[0], _q(ns[0], beta_sq), pol)
        eta_sub = _eta(ns[-1], _q(ns[-1], beta_sq), pol)
        out["R" + pol] = total[1, 0] / total[0, 0]
        out["T" + pol] = mp.re(eta_sub) / mp.re(eta0) / total[0, 0]
    return out


def derivative(indices, thicknesses, coherent, wavelength_nm, angle_deg, layer, h="1e-15"):
    """The central difference of `solve` by layer `layer`'s thickness
    (0-based), step h nm: at 50 digits its error is far below 1e-20."""
    h = mp.mpf(h)

    def at(delta):
        d = [mp.mpf(x) for x in thicknesses]
        d[layer] += delta
        return solve(indices, d, coherent, wavelength_nm, angle_deg)

    up, down = at(h), at(-h)
    return {k: (up[k] - down[k]) / (2 * h) for k in up}


def index_derivative(indices, thicknesses, coherent, wavelength_nm, angle_deg, layer, part, h="1e-15"):
    """The central difference of `solve` by layer `layer`'s (0-based) n
    (`part` "n") or k ("k"): its index shifted by ±h or ±ih everywhere it
    enters (both interfaces, the phase, an incoherent layer's pass).

    At k = 0 the difference is one-sided from the absorbing side (second
    order, f'(0) ≈ (4 f(h) − f(2h) − 3 f(0)) / 2h): `_q`'s branch Im q ≥ 0
    flips a propagating q's sign under the slightest gain, which a coherent
    layer's matrix does not see but an incoherent layer's pass and the power
    matrices at its interfaces do."""
    step = mp.mpf(h) * (1 if part == "n" else 1j)

    def at(delta):
        shifted = [mp.mpc(n) for n in indices]
        shifted[layer + 1] += delta
        return solve(shifted, thicknesses, coherent, wavelength_nm, angle_deg)

    if part == "k" and complex(indices[layer + 1]).imag == 0:
        f0, f1, f2 = at(0), at(step), at(2 * step)
        return {k: (4 * f1[k] - f2[k] - 3 * f0[k]) / (2 * mp.mpf(h)) for k in f0}
    up, down = at(step), at(-step)
    return {k: (up[k] - down[k]) / (2 * mp.mpf(h)) for k in up}
