"""W of a mooring line in mass form, and its stage matrix factored as 3×3 blocks.

A line of the linear element is a second-order system: rows [r, v] per free
node, ṙ = v, M v̇ = F(r, v). Its Rosenbrock-W matrix is

    W = [[0, I], [M⁻¹K_r, M⁻¹K_v]]

with M the nodal mass tensors (block-diagonal, 3×3 per node) and K_r, K_v the
block-tridiagonal derivatives of the nodal forces in the positions and
velocities (3×3 blocks). Kept in this form, the stage matrix I − cW never needs
its 6×6 blocks: its position rows give x_r = b_r + c·x_v, and its velocity rows
become

    (M − c·K_v − c²·K_r) x_v = M b_v + c·K_r b_r,

one 3×3 block-tridiagonal system (block Thomas, :func:`~moorjax.linalg.block_tridiagonal.factor3`).
Against W's 6×6 band (products M⁻¹K, then the general position elimination of
:class:`~moorjax.linalg.banded_solver.SecondOrderBandSolver`) this skips four
batched 3×3 products per band, the 6×6 assembly and the elimination's
products. The matrix is M times the reduced one of that solver: for a line
held by tension (K_r, K_v negative semi-definite) it is symmetric positive
definite, which suits a factorisation without pivoting.

Layout: rows are free nodes, lines stacked along the row axis (lines do not
couple: a line's first ``lower`` and last ``upper`` blocks are zero).
``lower[i]`` couples row i to row i−1, ``upper[i]`` to row i+1.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array

from . import block_tridiagonal as btd


class MassFormW(eqx.Module):
    """W = [[0, I], [M⁻¹K_r, M⁻¹K_v]] (see the module)."""

    mass: Array  # (rows, 3, 3) nodal mass tensors M
    mass_inv: Array  # (rows, 3, 3) M⁻¹
    k_r: tuple  # (lower, diag, upper), each (rows, 3, 3): ∂F/∂r [N/m]
    k_v: tuple  # (lower, diag, upper), each (rows, 3, 3): ∂F/∂v [N·s/m]

    def bands(self):
        """W's block-tridiagonal band with 6×6 blocks, (lower, diag, upper), as
        :func:`~moorjax.linalg.banded_solver.band_of` lays it out."""
        rows = self.mass.shape[0]
        top = jnp.zeros((rows, 3, 6), dtype=self.mass.dtype)
        eye_top = top.at[:, :, 3:].set(jnp.eye(3, dtype=self.mass.dtype))

        def block(kr, kv, upper_rows):
            bottom = jnp.concatenate([btd.bmm(self.mass_inv, kr), btd.bmm(self.mass_inv, kv)], axis=-1)
            return jnp.concatenate([upper_rows, bottom], axis=1)

        return tuple(block(kr, kv, eye_top if k == 1 else top)
                     for k, (kr, kv) in enumerate(zip(self.k_r, self.k_v)))

    def matvec(self, x: Array) -> Array:
        """W·x for x (rows, 6) [r, v]."""
        force = btd.matvec(*self.k_r, x[:, :3]) + btd.matvec(*self.k_v, x[:, 3:])
        return jnp.concatenate([x[:, 3:], btd.bmv(self.mass_inv, force)], axis=-1)

    def factor(self, c) -> MassFormFactor:
        """I − c·W, factored."""
        (rl, rd, ru), (vl, vd, vu) = self.k_r, self.k_v
        lu = btd.factor3(-c * (vl + c * rl), self.mass - c * (vd + c * rd), -c * (vu + c * ru))
        return MassFormFactor(mass=self.mass, k_r=self.k_r, c=c, lu=lu)


class MassFormFactor(eqx.Module):
    """(I − c·W)⁻¹ of a :class:`MassFormW` (see the module)."""

    mass: Array
    k_r: tuple
    c: Array
    lu: btd.BlockTridiagonalLU

    def solve(self, b: Array) -> Array:
        """x with (I − c·W) x = b, b and x (rows, 6) [r, v]."""
        b_r, b_v = b[:, :3], b[:, 3:]
        x_v = btd.solve(self.lu, btd.bmv(self.mass, b_v) + self.c * btd.matvec(*self.k_r, b_r))
        return jnp.concatenate([b_r + self.c * x_v, x_v], axis=-1)
