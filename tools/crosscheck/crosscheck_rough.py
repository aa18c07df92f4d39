#!/usr/bin/env python3
"""Cross-checks `irid color --roughness` against an independent Monte Carlo
of the rough-film definition (docs/rough.md).

The definition: GGX with alpha = roughness^2, height-correlated Smith
G2 = 1 / (1 + Lambda(v) + Lambda(l)), single scattering, and

    F_eff = int D G2 F(v.h) / (4 n.v) dl  /  int D G2 / (4 n.v) dl

with F the film's unpolarized reflectance at incidence cos = v.h as a
colour. Here, independently of irid:

  - F(mu) at a given mu: Byrnes' `tmm` (coh_tmm, s and p) at 1 nm over
    360-830 nm, integrated with colour-science's `sd_to_XYZ` (CIE 1931 2
    degree observer, CIE D65), then to linear sRGB with the matrix of the
    sRGB primaries and that D65's own white (so a perfect reflector is
    (1, 1, 1), irid's convention). tmm is slow, so F is computed at
    Chebyshev nodes in mu (in sqrt(mu - mu_c) above a critical angle) and
    interpolated barycentrically; the script checks that interpolation
    against tmm at random mu (it must be within 1e-6).
  - The lobe: microfacet normals drawn from D(h) cos(theta_h) (Walter et
    al. 2007's sampling, not the visible-normal sampling irid's renderer
    uses) on a jittered 512 x 512 grid, each weighted by
    G2 (v.h) / (n.v n.h), l the mirror of v about h, zero below the
    horizon. F_eff is the weighted mean of F(v.h). Four independent
    replicas estimate the Monte Carlo error.

Stacks: a dielectric film on glass, an absorbing film on a metal, three
layers on a metal (one dispersive, Cauchy), and a film seen from its glass
side (total internal reflection inside the lobe); roughness 0.2 and 0.5;
view angles 0-70 degrees.

Pass: every channel within 2e-4 of the Monte Carlo and CIEDE2000 <= 0.05
(the issue's bar is 2e-3 and 0.2), and the Monte Carlo's own error
estimate below a quarter of the tolerance. Also checks that irid's
`lobe_albedo` matches the Monte Carlo's directional albedo to 2e-4.

Transmission and the substrate side (docs/rough.md): microfacet normals
drawn from the distribution of visible normals D_v (Heitz 2018's sampling,
jittered), each reflecting into l_r and refracting by Snell about h (the
relative index of the real parts at 589.3 nm) into l_t, weighted by
G2(v, l)/G1(v) where l leaves on its own side; the film's R and T at v.h
by tmm from the side seen from (the reversed stack from the substrate).
F_eff, T_eff, A_R and A_T against `irid color --roughness R --side S
--json` on a dielectric film, a 15 nm metal film and three layers (one
dispersive), all on glass, from both sides. Pass: within the issue's bar,
2e-3 per channel and CIEDE2000 0.2; T_eff is compared where A_T > 0.02
(below, too few samples transmit), A_T and A_R everywhere.

By default (as CI runs it) the reflection's view angles are 0, 40 and 70
degrees (24 cases) and the transmission part checks the film on glass seen
from the glass at 0 and 35 degrees (4 cases). `--full` checks every angle
of ANGLES_DEG and every stack from both sides (the figures of
docs/rough.md come from it); `--sides` skips the reflection part.

Env: IRID_BIN (default target/release/irid). Exits non-zero on failure.
"""

import json
import math
import os
import subprocess
import sys
import tempfile
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

warnings.filterwarnings("ignore")  # colour warns about optional scipy/matplotlib

import colour  # noqa: E402
import numpy as np  # noqa: E402
import tmm  # noqa: E402

TOLERANCE = 2e-4
DE_TOLERANCE = 0.05
INTERPOLATION_TOLERANCE = 1e-6
ROUGHNESS = (0.2, 0.5)
ANGLES_DEG = (0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0)
CI_ANGLES_DEG = (0.0, 40.0, 70.0)
GRID = 512  # jittered strata per side, per replica
REPLICAS = 4
CHEBYSHEV_NODES = 20
DENSE = 8193  # the interpolant tabulated at this many points in s
WAVELENGTHS = np.arange(360.0, 831.0)


def cauchy(a, b, wl):
    """n = A + B / lambda^2, lambda in micrometres."""
    return a + b / (wl / 1000.0) ** 2


# name: (stack file text, indices(wl) -> list of complex, thicknesses, ambient index)
STACKS = {
    "dielectric film on glass": (
        """
ambient = { n = 1.0 }
substrate = { n = 1.52 }
[[layers]]
n = 1.38
thickness_nm = 350.0
""",
        lambda wl: [1.0, 1.38, 1.52],
        [350.0],
    ),
    "absorbing film on a metal": (
        """
ambient = { n = 1.0 }
substrate = { n = [0.13, 3.6] }
[[layers]]
n = [1.5, 0.15]
thickness_nm = 300.0
""",
        lambda wl: [1.0, 1.5 + 0.15j, 0.13 + 3.6j],
        [300.0],
    ),
    "three layers on a metal": (
        """
ambient = { n = 1.0 }
substrate = { n = [0.3, 2.9] }
[[layers]]
cauchy = [2.2, 0.03]
thickness_nm = 90.0
[[layers]]
n = [1.38, 0.01]
thickness_nm = 120.0
[[layers]]
n = 1.6
thickness_nm = 60.0
""",
        lambda wl: [1.0, cauchy(2.2, 0.03, wl), 1.38 + 0.01j, 1.6, 0.3 + 2.9j],
        [90.0, 120.0, 60.0],
    ),
    "film seen from its glass side": (
        """
ambient = { n = 1.5 }
substrate = { n = 1.0 }
[[layers]]
n = 1.38
thickness_nm = 300.0
""",
        lambda wl: [1.5, 1.38, 1.0],
        [300.0],
    ),
}


# ---------------------------------------------------------------- colour


def colour_weights():
    """XYZ of a spectrum sampled at WAVELENGTHS (colour-science's
    sd_to_XYZ, Y = 1 for a perfect reflector) and the XYZ -> linear sRGB
    matrix whose white is that perfect reflector."""
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]

    def xyz(values):
        sd = colour.SpectralDistribution(np.asarray(values, float), WAVELENGTHS)
        return colour.sd_to_XYZ(sd, cmfs, d65) / 100.0

    white = xyz(np.ones_like(WAVELENGTHS))
    primaries = colour.RGB_COLOURSPACES["sRGB"].primaries
    rgb_to_xyz = colour.normalised_primary_matrix(primaries, colour.XYZ_to_xy(white))
    return xyz, np.linalg.inv(rgb_to_xyz)


# ---------------------------------------------------------------- the film, by tmm


def film_spectrum(indices, thicknesses, mu):
    """Unpolarized R and T at every wavelength for incidence cos = mu in the
    first medium of indices(wl)."""
    d = [np.inf, *thicknesses, np.inf]
    out = np.empty((2, len(WAVELENGTHS)))
    theta = math.acos(min(max(mu, 0.0), 1.0))
    for i, wl in enumerate(WAVELENGTHS):
        n = indices(wl)
        solved = [tmm.coh_tmm(p, n, d, theta, wl) for p in "sp"]
        out[0, i] = 0.5 * sum(r["R"] for r in solved)
        out[1, i] = 0.5 * sum(np.real(r["T"]) for r in solved)
    return out


def film_xyz(args):
    """XYZ of R (and, for a stack seen from a side, of T after it) at mu."""
    name, mu = args
    if isinstance(name, tuple):
        indices, thicknesses = seen_stack(*name)
        r, t = film_spectrum(indices, thicknesses, mu)
        return np.concatenate([COLOUR[0](r), COLOUR[0](t)])
    _, indices, thicknesses = STACKS[name]
    return COLOUR[0](film_spectrum(indices, thicknesses, mu)[0])


COLOUR = None


def init_worker():
    global COLOUR
    COLOUR = colour_weights()


class Chebyshev:
    """Barycentric interpolation at Chebyshev points of the second kind in a
    variable s in [0, 1], mu = mu_of(s)."""

    def __init__(self, mu_of, n):
        self.s = 0.5 * (1.0 - np.cos(np.pi * np.arange(n) / (n - 1)))
        self.mu = mu_of(self.s)
        w = np.ones(n)
        w[0] = w[-1] = 0.5
        self.w = w * (-1.0) ** np.arange(n)

    def __call__(self, s, values):
        diff = s[:, None] - self.s[None, :]
        exact = np.isclose(diff, 0.0, atol=1e-15)
        diff[exact] = 1.0
        c = self.w[None, :] / diff
        out = (c @ values) / c.sum(axis=1)[:, None]
        rows, cols = np.nonzero(exact)
        out[rows] = values[cols]
        return out


class FilmColour:
    """F(mu) as XYZ, by Chebyshev interpolation of tmm colours on [MU_MIN, 1]
    (two pieces meeting at a critical angle, in sqrt(|mu - mu_c|))."""

    MU_MIN = 0.15  # below every mu a view of at most 70 degrees reaches by reflection

    def __init__(self, name, pool, grazing=False):
        indices = seen_stack(*name)[0] if isinstance(name, tuple) else STACKS[name][1]
        n0, n_sub = indices(550.0)[0], indices(550.0)[-1]
        self.crit = None
        if np.imag(n_sub) == 0 and np.real(n_sub) < np.real(n0):
            self.crit = math.sqrt(1.0 - (np.real(n_sub) / np.real(n0)) ** 2)
        lo = self.MU_MIN
        if self.crit is None:
            self.pieces = [(lo, 1.0, "linear")]
        else:
            self.pieces = [(lo, self.crit, "below"), (self.crit, 1.0, "above")]
        if grazing:  # a refraction lobe reaches every mu > 0
            self.pieces.insert(0, (GRAZING_MU, lo, "linear"))
            self.MU_MIN = GRAZING_MU
        self.interps = []
        jobs = []
        for a, b, kind in self.pieces:
            nodes = GRAZING_NODES if a == GRAZING_MU else CHEBYSHEV_NODES
            interp = Chebyshev(lambda s, a=a, b=b, kind=kind: self.mu_of(s, a, b, kind), nodes)
            self.interps.append(interp)
            jobs += [(name, m) for m in interp.mu]
        xyz = np.array(list(pool.map(film_xyz, jobs)))
        self.channels = xyz.shape[1]
        # Tabulated densely in s once; the samples then read it linearly.
        self.dense_s = np.linspace(0.0, 1.0, DENSE)
        self.dense = [interp(self.dense_s, v) for interp, v in zip(self.interps, np.split(xyz, np.cumsum([len(i.mu) for i in self.interps])[:-1]))]

    @staticmethod
    def mu_of(s, a, b, kind):
        if kind == "linear":
            return a + (b - a) * s
        if kind == "above":  # sqrt(mu - mu_c) proportional to s
            return a + (b - a) * s * s
        return b - (b - a) * (1.0 - s) ** 2  # sqrt(mu_c - mu) proportional to 1 - s

    @staticmethod
    def s_of(mu, a, b, kind):
        x = np.clip((mu - a) / (b - a), 0.0, 1.0)
        if kind == "linear":
            return x
        if kind == "above":
            return np.sqrt(x)
        return 1.0 - np.sqrt(1.0 - x)

    def __call__(self, mu):
        mu = np.asarray(mu, float)
        out = np.zeros((len(mu), self.channels))
        if self.MU_MIN == GRAZING_MU:
            mu = np.maximum(mu, GRAZING_MU)  # below it, within 1e-7 in weight (D_v is ~ mu)
        for (a, b, kind), dense in zip(self.pieces, self.dense):
            inside = (mu >= a) & (mu <= b)
            if inside.any():
                s = self.s_of(mu[inside], a, b, kind)
                out[inside] = np.stack([np.interp(s, self.dense_s, dense[:, c])
                                        for c in range(self.channels)], -1)
        if (mu < self.MU_MIN).any():
            raise ValueError("mu below the interpolated range")
        return out


# ---------------------------------------------------------------- the lobe, by Monte Carlo


def microfacet_normals(roughness, seed):
    """One jittered replica of normals drawn from D(h) cos(theta_h) (Walter
    et al. 2007: tan^2 theta_h = alpha^2 u1 / (1 - u1)): h and cos theta_h.
    They do not depend on the view, so each replica serves every case."""
    alpha = roughness * roughness
    rng = np.random.default_rng(seed)
    i, j = np.meshgrid(np.arange(GRID), np.arange(GRID), indexing="ij")
    u1 = ((i + rng.random(i.shape)) / GRID).ravel()
    u2 = ((j + rng.random(j.shape)) / GRID).ravel()
    tan2 = alpha * alpha * u1 / (1.0 - u1)
    cos_h = 1.0 / np.sqrt(1.0 + tan2)
    sin_h = np.sqrt(np.maximum(0.0, 1.0 - cos_h * cos_h))
    phi = 2.0 * np.pi * u2
    return np.stack([sin_h * np.cos(phi), sin_h * np.sin(phi), cos_h], -1), cos_h


def lobe_estimate(film, cos_v, roughness, normals):
    """(F_eff as XYZ, directional albedo) from one replica of normals."""
    alpha = roughness * roughness
    h, cos_h = normals
    v = np.array([math.sqrt(1.0 - cos_v * cos_v), 0.0, cos_v])
    mu = h @ v
    cos_l = 2.0 * mu * cos_h - cos_v

    def smith_lambda(c):
        c = np.clip(c, 1e-300, 1.0)
        return 0.5 * (-1.0 + np.sqrt(1.0 + alpha * alpha * (1.0 - c * c) / (c * c)))

    # The pdf is D cos theta_h over h; the integrand D G2 F / (4 n.v) over l
    # is D G2 F (v.h) / (n.v) over h.
    visible = (mu > 0.0) & (cos_l > 0.0)
    weight = np.zeros_like(mu)
    weight[visible] = (mu[visible] / (cos_v * cos_h[visible])
                       / (1.0 + smith_lambda(cos_v) + smith_lambda(cos_l[visible])))
    f = film(mu[visible])
    return (weight[visible, None] * f).sum(0) / weight.sum(), weight.mean()


def lab(rgb):
    xyz = np.asarray(rgb) @ colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ.T
    return colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(colour.RGB_COLOURSPACES["sRGB"].matrix_RGB_to_XYZ @ np.ones(3)))


def run_json(cmd):
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"FAIL: {' '.join(cmd)} exited {proc.returncode}: {proc.stderr.strip()}")
    return json.loads(proc.stdout)


def check_interpolation(name, film, pool, rng):
    """The interpolated F against tmm at random mu."""
    mus = rng.uniform(FilmColour.MU_MIN, 1.0, 4)
    exact = np.array(list(pool.map(film_xyz, [(name, m) for m in mus])))
    return np.abs(film(mus) - exact).max()


# ---------------------------------------------------------------- transmission and the substrate side

GRAZING_MU = 1e-4
SIDE_TOLERANCE = 2e-3  # the bar, per channel
SIDE_DE_TOLERANCE = 0.2
SIDE_INTERPOLATION_TOLERANCE = SIDE_TOLERANCE / 4  # as the Monte Carlo error
# A_T below this leaves too few Monte Carlo samples for T_eff: A_T itself is checked.
MIN_TRANSMISSION_ALBEDO = 0.02
SIDES = ("front", "substrate")
# CI checks the film on glass seen from the glass (its transmission below,
# its total internal reflection inside the lobe) at these angles.
CI_SIDE_ANGLES_DEG = (0.0, 35.0)
CI_SIDE_CASES = (("dielectric film on glass", "substrate"),)
GRAZING_NODES = 20  # Chebyshev nodes on [GRAZING_MU, MU_MIN]

# name: (stack file text, indices(wl) ambient to substrate, thicknesses); all on
# lossless substrates, so that each is seen from both sides.
TRANSMISSIVE = {
    "dielectric film on glass": STACKS["dielectric film on glass"],
    "metal film on glass": (
        """
ambient = { n = 1.0 }
substrate = { n = 1.52 }
[[layers]]
n = [0.13, 3.6]
thickness_nm = 15.0
""",
        lambda wl: [1.0, 0.13 + 3.6j, 1.52],
        [15.0],
    ),
    "three layers on glass (one dispersive)": (
        """
ambient = { n = 1.0 }
substrate = { n = 1.52 }
[[layers]]
cauchy = [2.2, 0.03]
thickness_nm = 90.0
[[layers]]
n = [1.38, 0.01]
thickness_nm = 120.0
[[layers]]
n = 1.6
thickness_nm = 60.0
""",
        lambda wl: [1.0, cauchy(2.2, 0.03, wl), 1.38 + 0.01j, 1.6, 1.52],
        [90.0, 120.0, 60.0],
    ),
}


def seen_stack(name, side):
    """indices(wl) and thicknesses of a TRANSMISSIVE stack as seen from side."""
    _, indices, thicknesses = TRANSMISSIVE[name]
    if side == "front":
        return indices, thicknesses
    return (lambda wl: indices(wl)[::-1]), thicknesses[::-1]


def visible_normals(roughness, cos_v, seed):
    """One jittered replica of normals drawn from the distribution of visible
    normals D_v(h) = G1(v) max(0, v.h) D(h) / (n.v) (Heitz 2018's sampling
    of the stretched hemisphere), for the view in the x-z plane."""
    alpha = roughness * roughness
    rng = np.random.default_rng(seed)
    i, j = np.meshgrid(np.arange(GRID), np.arange(GRID), indexing="ij")
    u1 = ((i + rng.random(i.shape)) / GRID).ravel()
    u2 = ((j + rng.random(j.shape)) / GRID).ravel()
    v = np.array([alpha * math.sqrt(1.0 - cos_v * cos_v), 0.0, cos_v])
    v /= np.linalg.norm(v)
    t1 = np.array([0.0, 1.0, 0.0]) if v[0] > 0 else np.array([1.0, 0.0, 0.0])
    t2 = np.cross(v, t1)
    r, phi = np.sqrt(u1), 2.0 * np.pi * u2
    p1, p2 = r * np.cos(phi), r * np.sin(phi)
    s = 0.5 * (1.0 + v[2])
    p2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - p1 * p1)) + s * p2
    p3 = np.sqrt(np.maximum(0.0, 1.0 - p1 * p1 - p2 * p2))
    nh = p1[:, None] * t1 + p2[:, None] * t2 + p3[:, None] * v
    h = np.stack([alpha * nh[:, 0], alpha * nh[:, 1], np.maximum(1e-300, nh[:, 2])], -1)
    return h / np.linalg.norm(h, axis=1)[:, None]


def side_estimate(film, cos_v, roughness, eta, h):
    """(F_eff, T_eff as XYZ, A_R, A_T) from one replica of visible normals:
    each h reflects into l_r and refracts (Snell about h, relative index eta)
    into l_t, weighted by G2(v, l)/G1(v) where l leaves on its own side."""
    alpha = roughness * roughness
    v = np.array([math.sqrt(1.0 - cos_v * cos_v), 0.0, cos_v])
    mu = np.maximum(h @ v, 0.0)

    def smith_lambda(c):
        c = np.clip(np.abs(c), 1e-300, 1.0)
        return 0.5 * (-1.0 + np.sqrt(1.0 + alpha * alpha * (1.0 - c * c) / (c * c)))

    g1 = 1.0 / (1.0 + smith_lambda(cos_v))
    cos_r = 2.0 * mu * h[:, 2] - cos_v
    w_r = np.where(cos_r > 0.0, 1.0 / (1.0 + smith_lambda(cos_v) + smith_lambda(cos_r)) / g1, 0.0)
    cos_t2 = eta * eta - 1.0 + mu * mu
    exists = cos_t2 > 0.0
    m = (mu - np.sqrt(np.maximum(cos_t2, 0.0))) / eta
    cos_lt = -cos_v / eta + m * h[:, 2]
    w_t = np.where(exists & (cos_lt < 0.0),
                   1.0 / (1.0 + smith_lambda(cos_v) + smith_lambda(cos_lt)) / g1, 0.0)
    f = film(mu)
    a_r, a_t = w_r.mean(), w_t.mean()
    f_eff = (w_r[:, None] * f[:, :3]).mean(0) / a_r
    t_eff = (w_t[:, None] * f[:, 3:]).mean(0) / a_t if a_t > 0 else np.zeros(3)
    return f_eff, t_eff, a_r, a_t


def check_sides(irid, cases, angles_deg, pool, rng, tmp, xyz_to_rgb):
    """T_eff, A_T and F_eff of (TRANSMISSIVE stack, side) cases against the
    Monte Carlo of visible normals; returns (worst figures, failures)."""
    worst = {"rgb": 0.0, "de": 0.0, "mc": 0.0, "albedo": 0.0, "interp": 0.0}
    failures = []
    for name, side in cases:
        text = TRANSMISSIVE[name][0]
        path = Path(tmp) / "transmissive.toml"
        path.write_text(text)
        film = FilmColour((name, side), pool, grazing=True)
        mus = rng.uniform(GRAZING_MU, 1.0, 4)
        exact = np.array(list(pool.map(film_xyz, [((name, side), m) for m in mus])))
        worst["interp"] = max(worst["interp"], np.abs(film(mus) - exact).max())
        seen = seen_stack(name, side)[0](589.3)
        eta = float(np.real(seen[-1]) / np.real(seen[0]))
        for roughness in ROUGHNESS:
            got = run_json([irid, "color", str(path), "--roughness", str(roughness), "--side", side,
                            "--angles", ",".join(f"{a:g}" for a in angles_deg), "--json"])
            for row, angle in zip(got, angles_deg):
                cos_v = math.cos(math.radians(angle))
                reps = [side_estimate(film, cos_v, roughness, eta,
                                      visible_normals(roughness, cos_v, 1000 + seed))
                        for seed in range(REPLICAS)]
                where = f"{name} from the {side}, roughness {roughness}, {angle:g} deg"
                a_r, a_t = np.mean([r[2] for r in reps]), np.mean([r[3] for r in reps])
                da = max(abs(a_r - row["lobe_albedo"]), abs(a_t - row["transmission_lobe_albedo"]))
                worst["albedo"] = max(worst["albedo"], da)
                if da > SIDE_TOLERANCE / 4:
                    failures.append(f"{where}: albedos {row['lobe_albedo']:.5f}, "
                                    f"{row['transmission_lobe_albedo']:.5f} vs {a_r:.5f}, {a_t:.5f}")
                keys = [("reflectance_rgb", 0)] + ([("transmittance_rgb", 1)] if a_t > MIN_TRANSMISSION_ALBEDO else [])
                for key, at in keys:
                    rgb = xyz_to_rgb @ np.mean([r[at] for r in reps], 0)
                    spread = np.std([xyz_to_rgb @ r[at] for r in reps], 0).max() / math.sqrt(REPLICAS)
                    d = np.abs(rgb - np.array(row[key])).max()
                    de = float(colour.delta_E(lab(rgb), lab(row[key]), method="CIE 2000"))
                    if d > worst["rgb"]:
                        worst["where"] = f"{where}, {key}"
                    for k, value in (("rgb", d), ("de", de), ("mc", spread)):
                        worst[k] = max(worst[k], value)
                    if d > SIDE_TOLERANCE or de > SIDE_DE_TOLERANCE:
                        failures.append(f"{where}: {key} irid {row[key]} vs Monte Carlo {rgb.tolist()} "
                                        f"(|d| {d:.1e}, dE00 {de:.3f})")
    return worst, failures


def report_sides(worst, failures, cases, angles_deg, seconds):
    count = len(cases) * len(ROUGHNESS) * len(angles_deg)
    print(f"crosscheck_rough, transmission and sides: {count} cases ({len(cases)} stack-sides x "
          f"roughness {ROUGHNESS} x angles {angles_deg} deg), visible normals {REPLICAS} x "
          f"{GRID}^2, {seconds:.1f} s")
    print(f"  max |d linear sRGB| = {worst['rgb']:.1e} (tolerance {SIDE_TOLERANCE:g}; worst at "
          f"{worst.get('where')}), max dE00 = {worst['de']:.4f} (tolerance {SIDE_DE_TOLERANCE})")
    print(f"  max |d albedo| (A_R, A_T) = {worst['albedo']:.1e}; Monte Carlo error estimate <= "
          f"{worst['mc']:.1e}; film colour interpolation within {worst['interp']:.1e} of tmm")
    if worst["mc"] > SIDE_TOLERANCE / 4:
        failures.append(f"Monte Carlo error estimate {worst['mc']:.1e} is too large to check {SIDE_TOLERANCE:g}")
    if worst["interp"] > SIDE_INTERPOLATION_TOLERANCE:
        failures.append(f"film colour interpolation error {worst['interp']:.1e} > {SIDE_INTERPOLATION_TOLERANCE:g}")
    return failures


def main():
    args = sys.argv[1:]
    full = "--full" in args
    only_sides = "--sides" in args
    unknown = [a for a in args if a not in ("--full", "--sides")]
    if unknown:
        sys.exit(f"crosscheck_rough.py: unknown arguments {unknown} (only --full, --sides)")
    angles_deg = ANGLES_DEG if full else CI_ANGLES_DEG
    irid = os.environ.get("IRID_BIN", "target/release/irid")
    xyz_to_rgb = colour_weights()[1]
    start = time.time()
    failures = []
    worst = {"rgb": 0.0, "de": 0.0, "mc": 0.0, "albedo": 0.0, "interp": 0.0}
    rng = np.random.default_rng(29)
    normals = {(r, seed): microfacet_normals(r, seed) for r in ROUGHNESS for seed in range(REPLICAS)}
    with tempfile.TemporaryDirectory() as tmp, ProcessPoolExecutor(2, initializer=init_worker) as pool:
        side_angles = ANGLES_DEG if full else CI_SIDE_ANGLES_DEG
        side_cases = [(n, s) for n in TRANSMISSIVE for s in SIDES] if full else CI_SIDE_CASES
        side_worst, side_failures = check_sides(irid, side_cases, side_angles, pool, rng, tmp, xyz_to_rgb)
        failures += report_sides(side_worst, side_failures, side_cases, side_angles, time.time() - start)
        start = time.time()
        for name, (text, _, _) in ({} if only_sides else STACKS).items():
            path = Path(tmp) / "stack.toml"
            path.write_text(text)
            film = FilmColour(name, pool)
            worst["interp"] = max(worst["interp"], check_interpolation(name, film, pool, rng))
            for roughness in ROUGHNESS:
                got = run_json([irid, "color", str(path), "--roughness", str(roughness),
                                "--angles", ",".join(f"{a:g}" for a in angles_deg), "--json"])
                for row, angle in zip(got, angles_deg):
                    cos_v = math.cos(math.radians(angle))
                    replicas = [lobe_estimate(film, cos_v, roughness, normals[roughness, seed])
                                for seed in range(REPLICAS)]
                    xyz = np.mean([r[0] for r in replicas], 0)
                    albedo = np.mean([r[1] for r in replicas])
                    spread = np.std([xyz_to_rgb @ r[0] for r in replicas], 0).max() / math.sqrt(REPLICAS)
                    rgb = xyz_to_rgb @ xyz
                    d = np.abs(rgb - np.array(row["reflectance_rgb"])).max()
                    de = float(colour.delta_E(lab(rgb), lab(row["reflectance_rgb"]), method="CIE 2000"))
                    da = abs(albedo - row["lobe_albedo"])
                    where = f"{name}, roughness {roughness}, {angle:g} deg"
                    if d > worst["rgb"]:
                        worst["where"] = where
                    for key, value in (("rgb", d), ("de", de), ("mc", spread), ("albedo", da)):
                        worst[key] = max(worst[key], value)
                    if d > TOLERANCE or de > DE_TOLERANCE or da > TOLERANCE:
                        failures.append(f"{where}: irid {row['reflectance_rgb']} vs Monte Carlo "
                                        f"{rgb.tolist()} (|d| {d:.1e}, dE00 {de:.3f}, albedo {da:.1e})")
    cases = 0 if only_sides else len(STACKS) * len(ROUGHNESS) * len(angles_deg)
    print(f"crosscheck_rough: {cases} cases ({len(STACKS)} stacks x roughness {ROUGHNESS} x "
          f"angles {angles_deg} deg), Monte Carlo of {REPLICAS} x {GRID}^2 jittered samples, "
          f"film colours by tmm and colour-science {colour.__version__}, {time.time() - start:.1f} s")
    print(f"  max |d linear sRGB| = {worst['rgb']:.1e} (tolerance {TOLERANCE:g}; worst at {worst.get('where')}), "
          f"max dE00 = {worst['de']:.4f} (tolerance {DE_TOLERANCE})")
    print(f"  max |d lobe albedo| = {worst['albedo']:.1e}; Monte Carlo error estimate <= {worst['mc']:.1e}; "
          f"film colour interpolation within {worst['interp']:.1e} of tmm")
    if worst["mc"] > TOLERANCE / 4:
        failures.append(f"Monte Carlo error estimate {worst['mc']:.1e} is too large to check {TOLERANCE:g}")
    if worst["interp"] > INTERPOLATION_TOLERANCE:
        failures.append(f"film colour interpolation error {worst['interp']:.1e} > {INTERPOLATION_TOLERANCE:g}")
    if failures:
        print("FAIL:\n  " + "\n  ".join(failures[:10]))
        sys.exit(1)
    print("OK")


if __name__ == "__main__":
    main()
