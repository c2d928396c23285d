"""Mass treatments of the linear element: nodal 3×3 (Eq. 7) and consistent (Eq. 2).

Both include the line's own mass and, when the line type has ``added_mass``, the
hydrodynamic added mass ρA·(Ca_n·(I − ttᵀ) + Ca_ax·ttᵀ) of each element (t its unit
tangent, weighted by its stretched length as the Galerkin integral ∫(1+e)φφ ds
gives).
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp

from ..linalg import block_tridiagonal as btd


def _segment_mass_tensors(line, env, tangent, stretched):
    """Per-segment (n, 3, 3) mass per unit *unstretched* length times element length.

    Returns the 3×3 tensor μ_j = m·l·I + ρA·ℓ_j·(Ca_n(I − tt) + Ca_ax tt) for each
    element j, i.e. the element's total inertia tensor.
    """
    lt = line.line_type
    eye = jnp.eye(3)
    l = line.segment_length
    mu = lt.mass_per_length * l * jnp.broadcast_to(eye, tangent.shape[:-1] + (3, 3))
    if lt.added_mass is not None:
        tt = tangent[:, :, None] * tangent[:, None, :]
        am = lt.added_mass
        added = env.rho * lt.area * stretched[:, None, None] * (
            am.ca_normal * (eye - tt) + am.ca_axial * tt
        )
        mu = mu + added
    return mu


class AbstractMass(eqx.Module):
    """Solves ``M a = f`` for the free-node accelerations."""

    #: M⁻¹ keeps the Jacobian block-tridiagonal (nodal mass) or not (consistent)
    banded: ClassVar[bool] = True

    @abc.abstractmethod
    def accelerations(self, line, env, t, force, tangent, stretched):
        """Free-node accelerations (n−1, 3) [m/s²] from all-node forces (n+1, 3) [N]."""


class NodalMass(AbstractMass):
    """Aamo & Fossen Eq. 7: each node carries half of each adjacent element.

    The node mass is a 3×3 matrix (added mass is direction dependent); neighbours
    are not coupled, so the solve is a batch of 3×3 solves.
    """

    def accelerations(self, line, env, t, force, tangent, stretched):
        mu = _segment_mass_tensors(line, env, tangent, stretched)
        m_node = 0.5 * (mu[:-1] + mu[1:])  # interior nodes 1..n-1
        # closed-form 3×3 inverse (mass matrices are symmetric positive definite):
        # elementwise, so XLA fuses it, unlike a batched LAPACK solve
        return btd.bmv(btd.inv3(m_node), force[1:-1])


class ConsistentMass(AbstractMass):
    """Aamo & Fossen Eq. 2: the consistent Galerkin mass (ρ₀l/6)(1, 4, 1).

    Each element contributes μ_j/6·[[2, 1], [1, 2]] ⊗ its 3×3 inertia, which
    couples neighbouring nodes. The prescribed end accelerations enter the first
    and last free-node equations. Solved by a block-tridiagonal LU (O(n)).
    M⁻¹ is dense, so the dynamics' Newton solves use a dense LU for such lines.
    """

    banded: ClassVar[bool] = False

    def accelerations(self, line, env, t, force, tangent, stretched):
        mu = _segment_mass_tensors(line, env, tangent, stretched) / 6.0
        diag = 2.0 * (mu[:-1] + mu[1:])  # node k = 1..n-1 : elements k-1 and k
        off = mu[1:-1]  # coupling of node k and k+1 through element k
        rhs = force[1:-1]
        a_a = line.end_a.acceleration(t)
        a_b = line.end_b.acceleration(t)
        rhs = rhs.at[0].add(-mu[0] @ a_a)
        rhs = rhs.at[-1].add(-mu[-1] @ a_b)
        n_free = diag.shape[0]
        zero = jnp.zeros((1, 3, 3))
        lower = jnp.concatenate([zero, off], axis=0)[:n_free]
        upper = jnp.concatenate([off, zero], axis=0)[-n_free:]
        return btd.solve(btd.factor(lower, diag, upper), rhs)
