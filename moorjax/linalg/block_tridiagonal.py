"""Block-tridiagonal LU factorisation and solve (block Thomas algorithm).

A system of n block rows with b×b blocks costs O(n·b³) to factor and O(n·b²) to
solve, against O((n·b)³) for a dense LU. Pure JAX (``lax.scan``): jit-able,
vmap-able and differentiable.

Conventions: ``lower[i]`` multiplies x[i−1] in row i (``lower[0]`` unused),
``diag[i]`` multiplies x[i], ``upper[i]`` multiplies x[i+1] (``upper[-1]`` unused).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array


#: widest block whose products :func:`bmv` and :func:`bmm` write out term by term
UNROLLED_WIDTH = 8


def bmv(a: Array, x: Array) -> Array:
    """Batched small matrix–vector products ``a @ x`` over leading axes, written
    elementwise: XLA on CPU runs each ``dot`` as its own thunk, which for 3×3 and
    6×6 blocks costs more than the arithmetic, while products and sums fuse with
    their neighbours. Blocks wider than :data:`UNROLLED_WIDTH` use ``einsum``."""
    a, x = jnp.asarray(a), jnp.asarray(x)
    if a.shape[-1] > UNROLLED_WIDTH:
        return jnp.einsum("...ij,...j->...i", a, x)
    out = a[..., :, 0] * x[..., None, 0]
    for k in range(1, a.shape[-1]):
        out = out + a[..., :, k] * x[..., None, k]
    return out


def bmm(a: Array, b: Array) -> Array:
    """Batched small matrix products ``a @ b`` written elementwise (see :func:`bmv`)."""
    a, b = jnp.asarray(a), jnp.asarray(b)
    if a.shape[-1] > UNROLLED_WIDTH:
        return a @ b
    out = a[..., :, 0, None] * b[..., None, 0, :]
    for k in range(1, a.shape[-1]):
        out = out + a[..., :, k, None] * b[..., None, k, :]
    return out


class BlockTridiagonalLU(eqx.Module):
    """Factors of a block-tridiagonal matrix: pivot inverses and multipliers."""

    pivot_inv: Array  # (n, b, b) inverses of the Schur-complement pivots
    multiplier: Array  # (n, b, b) L_i = A_i · pivot_inv[i-1]  (row 0 unused)
    upper: Array  # (n, b, b)


def factor(lower: Array, diag: Array, upper: Array) -> BlockTridiagonalLU:
    """Block LU without pivoting between blocks (each pivot block is inverted by LU)."""
    d0_inv = jnp.linalg.inv(diag[0])

    def step(prev_inv, xs):
        a_i, d_i, c_prev = xs
        m_i = a_i @ prev_inv
        piv_inv = jnp.linalg.inv(d_i - m_i @ c_prev)
        return piv_inv, (piv_inv, m_i)

    _, (pinv, mult) = jax.lax.scan(step, d0_inv, (lower[1:], diag[1:], upper[:-1]))
    pivot_inv = jnp.concatenate([d0_inv[None], pinv], axis=0)
    multiplier = jnp.concatenate([jnp.zeros_like(diag[:1]), mult], axis=0)
    return BlockTridiagonalLU(pivot_inv=pivot_inv, multiplier=multiplier, upper=upper)


def solve(lu: BlockTridiagonalLU, rhs: Array) -> Array:
    """Solve ``A x = rhs`` for rhs of shape (n, b)."""

    def forward(y_prev, xs):
        m_i, b_i = xs
        y_i = b_i - bmv(m_i, y_prev)
        return y_i, y_i

    _, y_rest = jax.lax.scan(forward, rhs[0], (lu.multiplier[1:], rhs[1:]))
    y = jnp.concatenate([rhs[:1], y_rest], axis=0)
    x_last = bmv(lu.pivot_inv[-1], y[-1])

    def backward(x_next, xs):
        pinv_i, c_i, y_i = xs
        x_i = bmv(pinv_i, y_i - bmv(c_i, x_next))
        return x_i, x_i

    _, x_rest = jax.lax.scan(
        backward, x_last, (lu.pivot_inv[:-1], lu.upper[:-1], y[:-1]), reverse=True
    )
    return jnp.concatenate([x_rest, x_last[None]], axis=0)


def matvec(lower: Array, diag: Array, upper: Array, x: Array) -> Array:
    """``A x`` for a block-tridiagonal A and x of shape (n, b)."""
    out = bmv(diag, x)
    out = out.at[1:].add(bmv(lower[1:], x[:-1]))
    out = out.at[:-1].add(bmv(upper[:-1], x[1:]))
    return out


#: iterations of :func:`factor3`'s scan per loop trip: XLA runs the loop body as
#: separate thunks (~13 per node, dispatch-bound on CPU), and unrolling lets it
#: fuse across iterations. ROS34PW2, µs per step (best of 5, idle 2-core
#: machine, same step counts): case A N = 40 87 → 80.5, N = 80 136–139 → 122;
#: case B N = 10 36–50 → 33, N = 40 85 → 79; the first call's compile unchanged
#: (6.1–7.2 s). In a standalone jitted factorisation 2 was best and 8–16 worse.
FACTOR_UNROLL = 4


def inv3(m: Array) -> Array:
    """Inverse of a batch of 3×3 matrices (..., 3, 3) by cofactors.

    Elementwise arithmetic only (no LAPACK call), so XLA fuses it; used for the
    3×3 pivots of the reduced Newton systems, which are well conditioned (mass-like).
    """
    a, b, c = m[..., 0, :], m[..., 1, :], m[..., 2, :]
    cof = jnp.stack([jnp.cross(b, c), jnp.cross(c, a), jnp.cross(a, b)], axis=-1)
    det = jnp.sum(a * cof[..., :, 0], axis=-1)
    return cof / det[..., None, None]


def factor3(lower: Array, diag: Array, upper: Array) -> BlockTridiagonalLU:
    """:func:`factor` for 3×3 blocks, with cofactor pivot inverses (faster on CPU)."""
    d0_inv = inv3(diag[0])

    def step(prev_inv, xs):
        a_i, d_i, c_prev = xs
        m_i = bmm(a_i, prev_inv)
        piv_inv = inv3(d_i - bmm(m_i, c_prev))
        return piv_inv, (piv_inv, m_i)

    _, (pinv, mult) = jax.lax.scan(step, d0_inv, (lower[1:], diag[1:], upper[:-1]),
                                   unroll=FACTOR_UNROLL)
    pivot_inv = jnp.concatenate([d0_inv[None], pinv], axis=0)
    multiplier = jnp.concatenate([jnp.zeros_like(diag[:1]), mult], axis=0)
    return BlockTridiagonalLU(pivot_inv=pivot_inv, multiplier=multiplier, upper=upper)
