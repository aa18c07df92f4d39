"""irid.autodiff: Stack.solve inside JAX (jax.custom_vjp) and PyTorch
(torch.autograd.Function). Each test runs where its framework is installed
(jax from PyPI, CPU; torch from Debian's python3-torch): the gradient of a
loss through the adapter against the loss's own finite difference and
against irid's dR_dd / dT_dd contracted by hand. With IRID_REQUIRE_TORCH=1
(tools/ci/python.sh's torch run) a missing torch fails instead of skipping."""

import os

import numpy as np
import pytest

import irid
import irid.autodiff

STACK = irid.Stack(ambient=1.0, layers=[(1.45, 120.0), (2.3 + 0.05j, 80.0), (1.38, 95.0)], substrate=1.52)
WAVELENGTHS = np.linspace(400.0, 800.0, 41)
ANGLES = [0.0, 30.0, 60.0]
TARGET_R = 0.5 * (1 + np.cos(WAVELENGTHS / 50.0))[:, None] * np.ones(len(ANGLES)) * 0.3


def loss_numpy(d):
    R, T, _, _ = irid.autodiff.solve_with_gradient(STACK, d, WAVELENGTHS, ANGLES)
    return np.sum((R - TARGET_R) ** 2) + 0.1 * np.sum(T)


def expected_gradient(d):
    R, T, dR, dT = irid.autodiff.solve_with_gradient(STACK, d, WAVELENGTHS, ANGLES)
    return np.einsum("lwa,wa->l", dR, 2 * (R - TARGET_R)) + 0.1 * dT.sum(axis=(1, 2))


def finite_difference(d, h=1e-4):
    out = []
    for j in range(len(d)):
        up, down = d.copy(), d.copy()
        up[j] += h
        down[j] -= h
        out.append((loss_numpy(up) - loss_numpy(down)) / (2 * h))
    return np.array(out)


D0 = np.array([120.0, 80.0, 95.0])


def test_thickness_replacement_and_bad_length():
    s = irid.autodiff.with_thicknesses(STACK, [1.0, 2.0, 3.0])
    assert [d for _, d in s.layers] == [1.0, 2.0, 3.0]
    with pytest.raises(ValueError, match="thicknesses_nm"):
        irid.autodiff.with_thicknesses(STACK, [1.0, 2.0])


def test_jax():
    jax = pytest.importorskip("jax")
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    f = irid.autodiff.jax_solve(STACK, WAVELENGTHS, ANGLES)

    def loss(d):
        R, T = f(d)
        return jnp.sum((R - TARGET_R) ** 2) + 0.1 * jnp.sum(T)

    d = jnp.asarray(D0)
    assert float(loss(d)) == pytest.approx(loss_numpy(D0), rel=1e-14)
    g = np.asarray(jax.grad(loss)(d))
    np.testing.assert_allclose(g, expected_gradient(D0), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(g, finite_difference(D0), rtol=1e-6, atol=1e-9)
    # Under jit too.
    np.testing.assert_allclose(np.asarray(jax.jit(jax.grad(loss))(d)), g, rtol=1e-14)


def test_torch():
    if os.environ.get("IRID_REQUIRE_TORCH") == "1":
        import torch
    else:
        torch = pytest.importorskip("torch")
    d = torch.tensor(D0, dtype=torch.float64, requires_grad=True)
    R, T = irid.autodiff.torch_solve(STACK, d, WAVELENGTHS, ANGLES)
    loss = torch.sum((R - torch.from_numpy(TARGET_R)) ** 2) + 0.1 * torch.sum(T)
    loss.backward()
    np.testing.assert_allclose(d.grad.numpy(), expected_gradient(D0), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(d.grad.numpy(), finite_difference(D0), rtol=1e-6, atol=1e-9)
