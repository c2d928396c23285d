"""Implicit derivatives of undetermined static shapes (moorjax.linalg.undetermined).

- the solver gives LU's answer for a regular matrix, the minimum-norm
  least-squares one for a singular matrix, zeros for a non-finite one, and never
  raises (lineax would);
- a slack line as dense as the water (no weight, no stiffness until taut: its
  shape is undetermined) has a finite fairlead stiffness, zero, where the
  derivative once aborted with "a linear solver received non-finite input";
  the same line pulled taut has the stiffness of a straight bar, EA/L along it.
"""

from __future__ import annotations

import jax.numpy as jnp
import lineax as lx
import numpy as np

import moorjax as mj
from moorjax.linalg.undetermined import MinimumNorm
from moorjax.statics import fairlead_stiffness


def _solve(a, b):
    return np.asarray(lx.linear_solve(lx.MatrixLinearOperator(jnp.asarray(a)), jnp.asarray(b), MinimumNorm()).value)


def test_regular_singular_and_nonfinite_matrices():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(5, 5)) + 5 * np.eye(5)
    b = rng.normal(size=5)
    np.testing.assert_allclose(_solve(a, b), np.linalg.solve(a, b), rtol=1e-12)
    s = a.copy()
    s[:, 2] = 0.0
    s[2, :] = 0.0  # a decoupled dof with no stiffness
    np.testing.assert_allclose(_solve(s, b), np.linalg.pinv(s) @ b, rtol=1e-9, atol=1e-12)
    assert abs(_solve(s, b)[2]) < 1e-12
    n = a.copy()
    n[1, 1] = np.nan
    np.testing.assert_array_equal(_solve(n, b), 0.0)


def _weightless(end_x):
    d = 0.1
    lt = mj.LineType(d, 1025.0 * np.pi * d**2 / 4, 1e8)  # as dense as the water
    line = mj.Line(lt, 30.0, 6, mj.FixedEnd((0.0, 0.0, -40.0)), mj.FixedEnd((end_x, 0.0, -40.0)))
    return line, mj.Environment(100.0)


def test_slack_weightless_line_has_zero_fairlead_stiffness():
    line, env = _weightless(20.0)
    k = np.asarray(fairlead_stiffness(line, env))
    assert np.all(np.isfinite(k))
    np.testing.assert_allclose(k, 0.0, atol=1e-6)


def test_taut_weightless_line_is_a_bar():
    line, env = _weightless(30.3)  # stretched by 1 %
    k = np.asarray(fairlead_stiffness(line, env))
    tension = 1e8 * 0.01
    # along the line EA/L, across it T/L (a string's geometric stiffness)
    np.testing.assert_allclose(np.diag(k), [1e8 / 30.0, tension / 30.3, tension / 30.3], rtol=2e-2)
