"""A lineax solver for implicit-function derivatives that may be undetermined.

The derivative of a static shape r*(θ) by the implicit function theorem solves
J·ṙ = −∂F/∂θ·θ̇ with J the Jacobian of the node forces at the root. For a slack
line without weight (MoorDyn's ``tests/Mooring/seafloor.txt``: a line as dense
as the water), J is singular: the shape is undetermined, and so is its
derivative; where the polish of the root failed, J is not even finite. lineax
then raises (``linear_solve`` checks its output and its input), which aborts the
whole static solve although the answer itself is sound.

:class:`MinimumNorm` wraps a solver (LU by default) and, where it fails or
gives a non-finite answer, takes the minimum-norm least-squares tangent
ṙ = −J⁺·∂F/∂θ·θ̇ instead (the pseudo-inverse, singular values below 1e-10 of
the largest dropped), and zero where even that is not finite (a failed polish:
J itself is not finite). The minimum-norm choice moves only what the forces
determine: an end moved on a slack weightless line drags the node next to it
along (its segment's stiffness fixes it) and leaves the undetermined rest, so
the line's end force keeps its true derivative, zero while the line is slack,
which is what the system statics need (a point on slack weightless lines has
no stiffness; see ``moorjax.statics.system._newton_step``). Where the wrapped
solver succeeds the answer is unchanged, and the pseudo-inverse is only
computed where it does not (``lax.cond``).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.flatten_util
import jax.lax as lax
import jax.numpy as jnp
import jax.tree_util as jtu
import lineax as lx


class MinimumNorm(lx.AbstractLinearSolver):
    """``inner``'s solution where it succeeds with finite values, else the
    minimum-norm least-squares solution (pseudo-inverse), else zeros.

    Args:
        inner: the lineax solver to use (default: lineax's automatic choice for
            a square operator, LU).
        rcond: singular values below ``rcond`` times the largest are dropped.
    """

    inner: lx.AbstractLinearSolver = lx.AutoLinearSolver(well_posed=None)
    rcond: float = 1e-10

    def init(self, operator, options: dict[str, Any]):
        return self.inner.init(operator, options), operator

    def compute(self, state, vector, options: dict[str, Any]):
        inner_state, operator = state
        solution, result, stats = self.inner.compute(inner_state, vector, options)
        ok = (result == lx.RESULTS.successful) & _finite(solution) & _finite(vector)
        flat, unravel = jax.flatten_util.ravel_pytree(solution)

        def least_squares():
            a = operator.as_matrix()
            b = jax.flatten_util.ravel_pytree(vector)[0]
            x = jnp.linalg.pinv(a, rtol=self.rcond) @ b
            return jnp.where(jnp.all(jnp.isfinite(x)) & _finite(vector), x, jnp.zeros_like(x))

        flat = lax.cond(ok, lambda: flat, least_squares)
        return unravel(flat), lx.RESULTS.successful, stats

    def transpose(self, state, options: dict[str, Any]):
        inner_state, operator = state
        inner_t, options_t = self.inner.transpose(inner_state, options)
        return (inner_t, operator.transpose()), options_t

    def conj(self, state, options: dict[str, Any]):
        inner_state, operator = state
        inner_c, options_c = self.inner.conj(inner_state, options)
        return (inner_c, lx.conj(operator)), options_c

    def assume_full_rank(self) -> bool:
        return False


def _finite(tree):
    return jnp.all(jnp.stack([jnp.all(jnp.isfinite(x)) for x in jtu.tree_leaves(tree)]))
