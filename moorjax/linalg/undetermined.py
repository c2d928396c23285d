"""A lineax solver for implicit-function derivatives that may be undetermined.

The derivative of a static shape r*(θ) by the implicit function theorem solves
J·ṙ = −∂F/∂θ·θ̇ with J the Jacobian of the node forces at the root. For a slack
line without weight (MoorDyn's ``tests/Mooring/seafloor.txt``: a line as dense
as the water), J is singular: the shape is undetermined, and so is its
derivative; where the polish of the root failed, J is not even finite. lineax
then raises (``linear_solve`` checks its output and its input), which aborts the
whole static solve although the answer itself is sound.

:class:`MinimumNorm` solves by LU where J is regular and takes, where it is
singular, the minimum-norm least-squares tangent ṙ = −J⁺·∂F/∂θ·θ̇ (the
pseudo-inverse), and zero where even that is not finite (a failed polish: J
itself is not finite). The minimum-norm choice moves only what the forces
determine: an end moved on a slack weightless line drags the node next to it
along (its segment's stiffness fixes it) and leaves the undetermined rest, so
the line's end force keeps its true derivative, zero while the line is slack,
which is what the system statics need (a point on slack weightless lines has
no stiffness; see ``moorjax.statics.system._newton_step``). The choice depends
on J only, so the pseudo-inverse is computed only for a singular J, also when
the solve is batched over tangents.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.flatten_util
import jax.lax as lax
import jax.scipy.linalg
import jax.numpy as jnp
import lineax as lx

from .ordering import after


class MinimumNorm(lx.AbstractLinearSolver):
    """LU where the matrix is regular, else the minimum-norm least-squares
    solution (pseudo-inverse), and zeros where that is not finite either.

    The matrix counts as regular when its LU factors are finite and the
    smallest pivot exceeds ``rcond`` times the largest. The choice depends on
    the matrix only, so it stays one branch (``lax.cond``) when the solve is
    batched over right-hand sides (``vmap`` over tangents): the pseudo-inverse
    is computed only for a singular matrix.

    Args:
        rcond: relative pivot (and singular value) threshold.
    """

    rcond: float = 1e-12

    def init(self, operator, options: dict[str, Any]):
        return self._factor(operator.as_matrix(), operator.in_structure())

    def _factor(self, a, structure):
        """(a, the LU factors and pivots of its equilibrated form, the row and
        column scales, whether a counts as regular, structure)."""
        rows, cols = _equilibration(a)
        lu, piv = jax.scipy.linalg.lu_factor(rows[:, None] * a * cols[None, :])
        d = jnp.abs(jnp.diag(lu))
        regular = jnp.all(jnp.isfinite(lu)) & (jnp.min(d) > self.rcond * jnp.max(d))
        return a, lu, piv, (rows, cols), regular, structure

    def compute(self, state, vector, options: dict[str, Any]):
        a, lu, piv, (rows, cols), regular, structure = state
        b, _ = jax.flatten_util.ravel_pytree(vector)

        x_lu = cols * jax.scipy.linalg.lu_solve((lu, piv), rows * b)

        def least_squares():
            # after the LU solve: batched (vmap over lines turns the cond into a
            # select), the SVD and the LU kernels must not run at once (.ordering)
            a_seq = after(a, x_lu)
            safe = jnp.where(jnp.isfinite(a_seq), a_seq, 0.0)
            return jnp.linalg.pinv(safe, rtol=self.rcond) @ b

        x = lax.cond(regular, lambda: x_lu, least_squares)
        x = jnp.where(jnp.all(jnp.isfinite(x)) & jnp.all(jnp.isfinite(a)), x, jnp.zeros_like(x))
        _, unravel = jax.flatten_util.ravel_pytree(_zeros(structure))
        return unravel(x), lx.RESULTS.successful, {}

    def transpose(self, state, options: dict[str, Any]):
        a, *_, structure = state
        return self._factor(a.T, structure), options

    def conj(self, state, options: dict[str, Any]):
        return state, options  # real matrices only

    def assume_full_rank(self) -> bool:
        return False


def _equilibration(a):
    """Row and column scales (powers of two) that bring every row's and column's
    largest magnitude of ``a`` to about one (LAPACK's ``dgeequ``). The unknowns
    of a static solve carry different units (positions, slopes, tensions) and
    element lengths graded a hundredfold apart: unscaled, the pivot ratio of a
    regular Jacobian falls below ``rcond`` and its derivative was taken as
    singular (the minimum-norm tangent, wrong: a graded line of drawn line 47
    in ``tests/test_hermite_statics_property.py``). A zero row or column keeps
    scale one (and stays singular)."""
    def scale(m):
        m = jnp.where(jnp.isfinite(m) & (m > 0.0), m, 1.0)
        return jnp.exp2(-jnp.round(jnp.log2(m)))

    rows = scale(jnp.max(jnp.abs(a), axis=1))
    cols = scale(jnp.max(jnp.abs(rows[:, None] * a), axis=0))
    return rows, cols


def _zeros(structure):
    return jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype), structure)
