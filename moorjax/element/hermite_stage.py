"""The implicit stages' Newton matrix of a Hermite line, block-tridiagonal in mass form.

An implicit Runge–Kutta stage solves, per Newton iteration, (I − c·J)·δ = r
with J = ∂(dq/dt)/∂q and c = γ·h (the tableau's diagonal times the step). For a
Hermite line q holds the unknowns' positions U and rates V (node positions and
slopes, :mod:`~moorjax.element.hermite_motion`) and dq/dt = [V, M(U)⁻¹·g(U, V)]:
the consistent mass M couples the whole line, so J is dense, and a dense
Jacobian cost 6(n+1)·2 forward derivatives of the whole vector field, each
through the mass solve (10 ms of a 14 ms step at 10 elements).

Multiplied by M, the velocity rows are element-local again. With
K = ∂(g − M·a)/∂U at the current accelerations a, and C = ∂g/∂V,

    δ_U − c·δ_V = r_U,   δ_V − c·M⁻¹(K·δ_U + C·δ_V) = r_V
    ⇒ (M − c·C − c²·K)·δ_V = M·r_V + c·K·r_U,   δ_U = r_U + c·δ_V,

where M, C and K couple only the unknowns of one element: ordered by node
[r_k, h̄·r'_k] they are block-tridiagonal with 6×6 blocks. Nodes k, k+3, … never
share an element, so K and C come from 2·3·6 = 36 forward derivatives of the
element forces (no mass solve in them), M from the element blocks, and the
matrix is factored by the block Thomas algorithm in O(n). The prescribed end
positions are no unknowns: their rows and columns are the identity.

A clamped end slope accelerates along its clamp's direction d only
(:func:`~moorjax.element.hermite_motion._clamped_solve`: a = B·a_r with
Bᵀ·M·B·a_r = Bᵀ·g). With P the node-block projector onto what may move (the
identity, d·dᵀ on a clamped slope, zero on a prescribed position) and
A = M − c·C − c²·K, the stage solve is

    δ_p = (I − P)·r_V   (the held components: their rate never changes)
    (P·A·P + I − P)·z = P·(M·r_V + c·K·r_U − A·δ_p),   δ_V = z + δ_p,

still block-tridiagonal (P is block-diagonal).

The matrix is exact for the element-local closures (the strain closure
:class:`~moorjax.element.hermite_motion.StrainTension` and the per-element
projected field). Wu's continuous field, projected
(:class:`~moorjax.element.hermite_motion.ProjectedTension`, the default),
couples each element's tension to the whole line: its stages use the
per-element field's matrix (``stage_closure``), exact where the two agree and
close elsewhere, and Newton's iteration converges on the exact residual. Wu's
field solved from Eq. 27 (:class:`~moorjax.element.hermite_motion.MixedTension`)
keeps the dense Newton solve.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array

from ..linalg import block_tridiagonal as btd
from ..linalg.banded_solver import band_of
from .hermite import clamped_slopes
from .hermite_motion import _mass_apply, _nodes, dynamics, forces_and_mass


def provides_stage_factor(line) -> bool:
    """Whether :func:`stage_factor` gives ``line``'s stages their Newton matrix
    (structure): its tension closure names an element-local one for it
    (``stage_closure``; Wu's field from Eq. 27 does not)."""
    return line.element.tension.stage_closure() is not None


class HermiteStageFactor(eqx.Module):
    """The factored stage matrix of one Hermite line (see the module notes).

    Attributes:
        mass: M's node blocks (lower, diag, upper), each (n+1, 6, 6) [kg].
        stiffness: K's node blocks [N/m].
        lu: block LU of P·(M − c·C − c²·K)·P + I − P.
        c: γ·h [s].
        held: I − P's node blocks (n+1, 6, 6) and A = M − c·C − c²·K's blocks,
            for a line with a clamped slope; ``None`` without (then I − P holds
            only the ends' positions, which are no unknowns).
    """

    mass: tuple
    stiffness: tuple
    lu: btd.BlockTridiagonalLU
    c: Array
    held: tuple | None = None

    def solve(self, r):
        """δ (2n, 6) with (I − c·J)·δ = r, both in the packed state layout."""
        n = self.mass[1].shape[0] - 1
        r_u, r_v = _by_node(r[:, :3], n), _by_node(r[:, 3:], n)
        rhs = btd.matvec(*self.mass, r_v) + self.c * btd.matvec(*self.stiffness, r_u)
        if self.held is None:
            d_v = btd.solve(self.lu, rhs * _free(n))
        else:
            held, band = self.held
            d_p = btd.bmv(held, r_v)
            rhs = rhs - btd.matvec(*band, d_p)
            d_v = btd.solve(self.lu, rhs - btd.bmv(held, rhs)) + d_p
        d_u = r_u + self.c * d_v
        return jnp.concatenate([_packed(d_u, n), _packed(d_v, n)], axis=-1)


def stage_factor(line, env, t, q, c) -> HermiteStageFactor:
    """The factored stage matrix I − c·J of ``line`` at its packed state q (2n, 6)
    and time t [s], c = γ·h [s]: exact for an element-local closure, else that of
    the closure's ``stage_closure``."""
    n = line.n_segments
    a = lax.stop_gradient(dynamics(line, env, t, q)[0]).reshape(-1, 1)
    closure = line.element.tension.stage_closure()
    if closure is not line.element.tension:
        line = eqx.tree_at(lambda ln: ln.element.tension, line, closure,
                           is_leaf=lambda x: x is line.element.tension)
    u, ud = _nodes(line, t, q)

    def residual(du, dud):  # g − M·a at fixed a: its derivative is M·∂(dv/dt)
        f, me, _, _ = forces_and_mass(line, env, t, u + du, ud + dud)
        return (f.reshape(-1, 1) - _mass_apply(me, a)).reshape(n + 1, 6)

    zero = jnp.zeros_like(u)
    _, me, _, _ = forces_and_mass(line, env, t, u, ud)
    _, tangent = jax.linearize(residual, zero, zero)
    by_node = jax.ShapeDtypeStruct((n + 1, 6), u.dtype)
    k_band = band_of(lambda x: tangent(x.reshape(u.shape), zero), by_node)[:3]
    c_band = band_of(lambda x: tangent(zero, x.reshape(u.shape)), by_node)[:3]
    m_band = _mass_band(me)
    band = tuple(m - c * cc - c * c * k for m, cc, k in zip(m_band, c_band, k_band))
    if clamped_slopes(line, t):
        keep = _projector(line, t)  # P's node blocks (n+1, 6, 6)
        lower = btd.bmm(btd.bmm(keep, band[0]), jnp.roll(keep, 1, axis=0))  # row k, column k − 1
        diag = btd.bmm(btd.bmm(keep, band[1]), keep) + (jnp.eye(6) - keep)
        upper = btd.bmm(btd.bmm(keep, band[2]), jnp.roll(keep, -1, axis=0))
        held = (jnp.eye(6) - keep, band)
    else:  # P is diagonal (0 on the ends' positions): rows and columns masked
        free_np = _free(n)
        free = jnp.asarray(free_np)
        lower = free[:, :, None] * band[0] * jnp.roll(free, 1, axis=0)[:, None, :]
        diag = free[:, :, None] * band[1] * free[:, None, :] + jnp.asarray(
            np.eye(6) * (1.0 - free_np)[:, None, :])  # I − P
        upper = free[:, :, None] * band[2] * jnp.roll(free, -1, axis=0)[:, None, :]
        held = None
    lu = btd.factor(lower, diag, upper)
    return HermiteStageFactor(mass=m_band, stiffness=k_band, lu=lu, c=jnp.asarray(c), held=held)


def _projector(line, t):
    """P's node blocks (n+1, 6, 6) on [r_k, d_k]: the identity on what may move,
    zero on the ends' positions, d·dᵀ on a slope clamped along d."""
    n = line.n_segments
    keep = jnp.asarray(np.broadcast_to(np.eye(6), (n + 1, 6, 6)) * _free(n)[:, None, :])
    for node, d in clamped_slopes(line, t):
        keep = keep.at[node, 3:, 3:].set(jnp.outer(d, d))
    return keep


def _free(n):
    """(n+1, 6) 1 for the unknowns of each node [r_k, d_k], 0 for the ends' positions."""
    free = np.ones((n + 1, 6))
    free[[0, n], :3] = 0.0
    return free


def _by_node(x, n):
    """Packed rows (2n, 3) (free positions, then slopes) → node order (n+1, 6)
    [r_k, d_k], the ends' positions zero."""
    out = jnp.zeros((n + 1, 6), x.dtype)
    return out.at[1:n, :3].set(x[:n - 1]).at[:, 3:].set(x[n - 1:])


def _packed(x, n):
    """Node order (n+1, 6) → packed rows (2n, 3)."""
    return jnp.concatenate([x[1:n, :3], x[:, 3:]], axis=0)


def _mass_band(me):
    """M's node blocks from the element masses (n, 4, 4, 3, 3) on (r_e, d_e, r_e+1, d_e+1)."""
    n = me.shape[0]
    e = jnp.transpose(me, (0, 1, 3, 2, 4)).reshape(n, 12, 12)
    z = jnp.zeros((n + 1, 6, 6), me.dtype)
    diag = z.at[:n].add(e[:, :6, :6]).at[1:].add(e[:, 6:, 6:])
    return z.at[1:].set(e[:, 6:, :6]), diag, z.at[:n].set(e[:, :6, 6:])
