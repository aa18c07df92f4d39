"""irid's solver inside JAX and PyTorch: R and T as differentiable functions
of the layer thicknesses, whose backward pass uses irid's exact derivatives
(``Stack.solve(..., gradient=True)``, docs/inverse.md) instead of tracing
the solver.

    f = irid.autodiff.jax_solve(stack, wavelengths_nm, angles_deg)
    R, T = f(thicknesses)          # jax arrays (wavelengths, angles)
    jax.grad(lambda d: loss(*f(d)))(thicknesses)

    R, T = irid.autodiff.torch_solve(stack, thicknesses, wavelengths_nm, angles_deg)
    loss(R, T).backward()          # thicknesses.grad

Neither framework is a dependency of irid: each adapter imports its own on
first use. Both run on the CPU in float64 (JAX needs
``jax.config.update("jax_enable_x64", True)``; without it the results are
cast to float32).
"""

import numpy as np

from . import Stack


def with_thicknesses(stack, thicknesses_nm):
    """The stack with its layers' thicknesses replaced (top layer first)."""
    thicknesses_nm = np.asarray(thicknesses_nm, dtype=np.float64).reshape(-1)
    layers = stack.layers
    if thicknesses_nm.shape != (len(layers),):
        raise ValueError(
            f"thicknesses_nm: expected {len(layers)} thicknesses (one per layer), "
            f"got {thicknesses_nm.size}"
        )
    return Stack(
        ambient=stack.ambient,
        layers=[(m, float(d), c) for (m, _), d, c in zip(layers, thicknesses_nm, stack.coherent)],
        substrate=stack.substrate,
    )


def solve_with_gradient(stack, thicknesses_nm, wavelengths_nm, angles_deg):
    """R, T (wavelengths, angles) and dR_dd, dT_dd (layers, wavelengths,
    angles) of the stack with the given thicknesses, as numpy arrays."""
    out = with_thicknesses(stack, thicknesses_nm).solve(wavelengths_nm, angles_deg, gradient=True)
    return out["R"], out["T"], out["dR_dd"], out["dT_dd"]


def jax_solve(stack, wavelengths_nm, angles_deg):
    """A JAX function of the layer thicknesses (shape (layers,)) returning
    (R, T), each (wavelengths, angles), with a ``jax.custom_vjp`` whose
    backward pass is irid's exact derivative. It calls irid through
    ``jax.pure_callback``, so it works under ``jax.jit`` and ``jax.grad``
    (not ``jax.vmap`` over stacks: call it per stack)."""
    import jax
    import jax.numpy as jnp

    wavelengths_nm = np.asarray(wavelengths_nm, dtype=np.float64)
    angles_deg = np.asarray(angles_deg, dtype=np.float64)
    layers = len(stack.layers)
    dtype = jnp.zeros(0).dtype  # float64 with x64 enabled, else float32
    grid = (wavelengths_nm.size, angles_deg.size)
    shapes = (
        jax.ShapeDtypeStruct(grid, dtype),
        jax.ShapeDtypeStruct(grid, dtype),
        jax.ShapeDtypeStruct((layers, *grid), dtype),
        jax.ShapeDtypeStruct((layers, *grid), dtype),
    )

    def host(d):
        return tuple(
            np.asarray(x, dtype=dtype)
            for x in solve_with_gradient(stack, np.asarray(d), wavelengths_nm, angles_deg)
        )

    def call(d):
        return jax.pure_callback(host, shapes, d)

    @jax.custom_vjp
    def solve(d):
        R, T, _, _ = call(d)
        return R, T

    def forward(d):
        R, T, dR, dT = call(d)
        return (R, T), (dR, dT)

    def backward(residuals, cotangents):
        dR, dT = residuals
        gR, gT = cotangents
        return (jnp.einsum("lwa,wa->l", dR, gR) + jnp.einsum("lwa,wa->l", dT, gT),)

    solve.defvjp(forward, backward)
    return solve


def _torch_function():
    import torch

    class Solve(torch.autograd.Function):
        """R, T of a stack as a function of its thicknesses (see torch_solve)."""

        @staticmethod
        def forward(ctx, thicknesses, stack, wavelengths_nm, angles_deg):
            d = thicknesses.detach().cpu().numpy()
            R, T, dR, dT = solve_with_gradient(stack, d, wavelengths_nm, angles_deg)
            as_tensor = lambda x: torch.from_numpy(np.ascontiguousarray(x)).to(thicknesses.dtype)  # noqa: E731
            ctx.save_for_backward(as_tensor(dR), as_tensor(dT))
            return as_tensor(R), as_tensor(T)

        @staticmethod
        def backward(ctx, gR, gT):
            dR, dT = ctx.saved_tensors
            grad = torch.einsum("lwa,wa->l", dR, gR) + torch.einsum("lwa,wa->l", dT, gT)
            return grad, None, None, None

    return Solve


def torch_solve(stack, thicknesses, wavelengths_nm, angles_deg):
    """(R, T), each (wavelengths, angles), of the stack with the layer
    thicknesses ``thicknesses`` (a torch tensor of shape (layers,), nm), as a
    ``torch.autograd.Function`` whose backward pass is irid's exact
    derivative. CPU tensors; the dtype follows ``thicknesses``."""
    return _torch_function().apply(thicknesses, stack, wavelengths_nm, angles_deg)
