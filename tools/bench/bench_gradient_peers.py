#!/usr/bin/env python3
"""Times the gradient of a spectrum with respect to every layer thickness in
irid against the differentiable thin-film peers, in one process, and checks
that every peer's gradient agrees with irid's before printing a ratio.

The problem (issue 38's): a 20-layer stack (air, films alternating 1.5 and
2.3 + 0.05i, 100, 107, 114, ... nm, on glass 1.52: the films of
benches/gradient.rs on a real substrate, because tmm_fast requires real
outer media), unpolarized R over 401 wavelengths (400-800 nm) x 3 angles
(0, 30, 60 deg), and the gradient of the scalar loss sum(R) with respect to
all 20 thicknesses, in float64 on the CPU.

- irid: `Stack.solve(wavelengths, angles, gradient=True)` gives dR_dd for
  every layer and point (the whole Jacobian, from the forward sweep and one
  backward sweep); the loss's gradient is its sum over points.
- peers: one forward pass and one reverse-mode backward pass of sum(R)
  (`loss.backward()` in PyTorch, `jax.jit(jax.grad(loss))` in JAX, compiled
  once outside the timed region). R = (Rs + Rp) / 2 from two polarized solves.

Peers, each where it imports: tmm_fast (PyTorch), tmmax (JAX). difftmm is
not timed: its isotropic solver hard-codes complex64 (single precision).

Times are medians of --repeat runs in this process. irid and JAX use all
the machine's cores (their default); tmm_fast is timed with torch on one
thread (Debian's torch's default here) and on all cores.

Usage: python tools/bench/bench_gradient_peers.py [--repeat N] [--peers tmmax,tmm_fast,...]
(benches/results/2026-12-07-amd-epyc-2core-gradient/SETUP.md has the two
virtualenvs and the commands.)
Prints a Markdown table. Exits non-zero if a peer's gradient differs from
irid's by more than 1e-6 relative (max over layers / max |gradient|).
"""

import argparse
import os
import platform
import statistics
import sys
import time

import numpy as np

import irid

TOLERANCE = 1e-6
LAYERS = 20
WAVELENGTHS_NM = np.linspace(400.0, 800.0, 401)
ANGLES_DEG = np.array([0.0, 30.0, 60.0])
AMBIENT, SUBSTRATE = 1.0, 1.52


def layer_indices():
    return [1.5 + 0j if i % 2 == 0 else 2.3 + 0.05j for i in range(LAYERS)]


def thicknesses_nm():
    return np.array([100.0 + 7.0 * i for i in range(LAYERS)])


def median_seconds(run, repeat):
    run()  # warm-up (and compilation, for JAX)
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def irid_stack():
    return irid.Stack(
        ambient=AMBIENT,
        layers=list(zip(layer_indices(), thicknesses_nm())),
        substrate=SUBSTRATE,
    )


def irid_gradient():
    out = irid_stack().solve(WAVELENGTHS_NM, ANGLES_DEG, gradient=True)
    return out["R"].sum(), out["dR_dd"].sum(axis=(1, 2))


def irid_forward():
    return irid_stack().solve(WAVELENGTHS_NM, ANGLES_DEG)["R"].sum()


def tmm_fast_gradient(threads):
    """sum(R) and its gradient by tmm_fast's coh_tmm and torch autograd,
    torch running `threads` intra-op threads."""
    import torch
    import tmm_fast

    torch.set_num_threads(threads)

    n = np.array([AMBIENT, *layer_indices(), SUBSTRATE], dtype=np.complex128)
    N = torch.from_numpy(np.repeat(n[None, :, None], WAVELENGTHS_NM.size, axis=2))
    wavelengths_m = torch.from_numpy(WAVELENGTHS_NM * 1e-9)
    theta = torch.from_numpy(np.deg2rad(ANGLES_DEG))
    d = torch.from_numpy(thicknesses_nm() * 1e-9).requires_grad_(True)

    def run():
        d.grad = None
        T = torch.cat([torch.tensor([np.inf], dtype=torch.float64), d, torch.tensor([np.inf], dtype=torch.float64)])
        T = T[None, :]
        R = 0.5 * (tmm_fast.coh_tmm("s", N, T, theta, wavelengths_m)["R"]
                   + tmm_fast.coh_tmm("p", N, T, theta, wavelengths_m)["R"])
        loss = R.sum()
        loss.backward()
        # Thicknesses in metres: the gradient per nm is 1e-9 of it.
        return float(loss), d.grad.numpy() * 1e-9

    return run


def import_tmmax_float64():
    """tmmax 1.1.4 hard-codes complex64 (its transfer-matrix scan carry, the
    complex index list) and float32 (the incoherent scan), which under
    jax_enable_x64 either fails (the scan's carry type) or rounds the indices
    to single precision. And its coherent layer matrix (coh_matmul) builds
    the phase factors as shape-(1,) arrays, so the 2x2 matrix is (2, 2, 1)
    and `carry @ matrix` broadcasts it as two 2x1 matrices: the product is
    transposed at every step, and R is wrong for two or more layers (two
    layers of the same index, 100 + 107 nm, differ from one of 207 nm).
    This imports a copy of the installed package with those literals
    widened to complex128 and float64 and the two phase factors made
    scalars, nothing else changed, from a temporary folder placed first on
    sys.path."""
    import importlib.util
    import pathlib
    import tempfile

    spec = importlib.util.find_spec("tmmax")
    if spec is None:
        raise ImportError("No module named 'tmmax'")
    source = pathlib.Path(spec.origin).parent
    folder = pathlib.Path(tempfile.mkdtemp(prefix="tmmax-float64-"))
    for path in source.rglob("*"):
        target = folder / "tmmax" / path.relative_to(source)
        if path.is_dir() or "__pycache__" in path.parts:
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        if path.suffix == ".py":
            text = path.read_text().replace("complex64", "complex128").replace("float32", "float64")
            text = text.replace("jnp.array([-1j], dtype = jnp.complex128)", "jnp.complex128(-1j)")
            text = text.replace("jnp.array([1j], dtype = jnp.complex128)", "jnp.complex128(1j)")
            target.write_text(text)
        else:
            target.write_bytes(path.read_bytes())
    sys.path.insert(0, str(folder))
    import tmmax.tmm

    assert tmmax.tmm.__file__.startswith(str(folder)), tmmax.tmm.__file__
    return tmmax.tmm.vectorized_coh_tmm


def tmmax_gradient():
    """sum(R) and its gradient by tmmax's vectorized_coh_tmm under jax.grad
    (in float64: see import_tmmax_float64)."""
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    vectorized_coh_tmm = import_tmmax_float64()

    # tmmax interpolates each material's n and k in a (materials, 3, points)
    # table of (wavelength, n, k); a constant index is two equal points.
    indices = [AMBIENT + 0j, 1.5 + 0j, 2.3 + 0.05j, SUBSTRATE + 0j]
    data = jnp.array([[[300.0, 900.0], [m.real] * 2, [m.imag] * 2] for m in indices])
    distribution = jnp.array([0] + [1 if i % 2 == 0 else 2 for i in range(LAYERS)] + [3])
    wavelengths = jnp.asarray(WAVELENGTHS_NM)
    angles = jnp.asarray(np.deg2rad(ANGLES_DEG))

    def loss(d):
        rs, _ = vectorized_coh_tmm(data, distribution, d, wavelengths, angles, jnp.array([False]))
        rp, _ = vectorized_coh_tmm(data, distribution, d, wavelengths, angles, jnp.array([True]))
        return 0.5 * (jnp.sum(rs) + jnp.sum(rp))

    value_and_grad = jax.jit(jax.value_and_grad(loss))
    d = jnp.asarray(thicknesses_nm())

    def run():
        value, grad = value_and_grad(d)
        grad = np.asarray(grad.block_until_ready())
        return float(value), grad

    return run


# Debian's torch starts with one intra-op thread; it is timed with one and
# with all cores, and the faster counts.
PEERS = {
    "tmm_fast": lambda: tmm_fast_gradient(1),
    f"tmm_fast-{os.cpu_count()}-threads": lambda: tmm_fast_gradient(os.cpu_count()),
    "tmmax": tmmax_gradient,
}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=20)
    parser.add_argument("--peers", default=",".join(PEERS), help="comma-separated, of " + ", ".join(PEERS))
    # The torch-based and JAX-based peers may need different environments
    # (Debian's torch wants Debian's numpy 1.24; jax wants numpy >= 2):
    # a peer that does not import is left out with a note on stderr.
    args = parser.parse_args()

    loss, grad = irid_gradient()
    t_forward = median_seconds(irid_forward, args.repeat)
    t_irid = median_seconds(irid_gradient, args.repeat)
    rows = [("irid, forward only (`Stack.solve`)", t_forward, None, None),
            ("irid, R and dR/dd (`Stack.solve(gradient=True)`)", t_irid, 1.0, None)]
    failed = False
    for name in args.peers.split(","):
        try:
            run = PEERS[name]()
            peer_loss, peer_grad = run()
        except ImportError as e:
            print(f"{name}: not installed here ({e})", file=sys.stderr)
            continue
        error = np.max(np.abs(peer_grad - grad)) / np.max(np.abs(grad))
        loss_error = abs(peer_loss - loss) / abs(loss)
        if error > TOLERANCE or loss_error > TOLERANCE:
            failed = True
        t = median_seconds(run, args.repeat)
        rows.append((f"{name}, sum(R) and one backward pass", t, t / t_irid, (loss_error, error)))

    print(f"{platform.node()}, {platform.processor() or platform.machine()}, "
          f"Python {platform.python_version()}, irid {irid.__version__ if hasattr(irid, '__version__') else ''}, "
          f"median of {args.repeat}\n")
    print("| implementation | median | peer / irid gradient | rel. diff. sum(R), gradient |")
    print("|---|---|---|---|")
    for name, t, ratio, diff in rows:
        r = "" if ratio is None else f"{ratio:.1f}×"
        d = "" if diff is None else f"{diff[0]:.1e}, {diff[1]:.1e}"
        print(f"| {name} | {t * 1e3:.2f} ms | {r} | {d} |")
    if failed:
        print(f"a peer's gradient differs from irid's by more than {TOLERANCE}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
