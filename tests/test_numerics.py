"""Derivative-safe norms (moorjax._numerics): finite derivatives where the plain ones are NaN.

The end tensions of a static solve are ``safe_norm`` of the end forces
(``moorjax.statics.fem``), so a slack end (zero force) has tension 0 with a
derivative of 0, not NaN, and a NaN never enters a gradient through them.
"""

import jax
import jax.numpy as jnp
import numpy as np

import moorjax as mj
from moorjax._numerics import abs_times, safe_norm, safe_unit
from moorjax.statics import solve_line_statics


def test_norm_gradient_is_finite_at_zero_force():
    zero = jnp.zeros(3)
    assert np.all(np.isnan(jax.grad(jnp.linalg.norm)(zero)))  # what safe_norm avoids
    np.testing.assert_array_equal(jax.grad(safe_norm)(zero), 0.0)
    assert np.all(np.isfinite(jax.jacfwd(lambda f: safe_unit(f)[0])(zero)))
    np.testing.assert_array_equal(jax.jacfwd(abs_times)(zero), 0.0)
    f = jnp.array([3.0, -4.0, 12.0])  # away from zero: the plain norm and its gradient
    assert float(safe_norm(f)) == 13.0
    np.testing.assert_allclose(jax.grad(safe_norm)(f), f / 13.0, rtol=1e-15)


def test_static_end_tension_and_its_gradient_at_a_zero_end_force():
    """A static line whose end force is exactly zero (weightless, straight,
    unstretched: the start guess is the solution) reports tensions 0, and the
    derivative of that magnitude at the reported force is 0, not NaN. (The whole
    solve cannot be differentiated there: without tension the line has no
    transverse stiffness and the implicit-function Jacobian is singular.)"""
    lt = mj.LineType(0.1, 20.0, 5e7)
    env = mj.Environment(100.0, 1025.0, 0.0)  # g = 0: no weight, no buoyancy
    line = mj.Line(lt, 50.0, 4, mj.FixedEnd([0.0, 0.0, -50.0]), mj.FixedEnd([50.0, 0.0, -50.0]))
    st = solve_line_statics(line, env, throw=False)
    np.testing.assert_array_equal(st.force_a, 0.0)
    assert float(st.tension_a) == 0.0 and float(st.tension_b) == 0.0
    # the magnitude the statics report, differentiated at the reported force
    grad = jax.grad(lambda f: safe_norm(f))(st.force_a)
    np.testing.assert_array_equal(grad, 0.0)


def test_norm_of_a_nan_is_nan_not_zero():
    """A diverged state must not read as a slack line (tension 0): failure checks
    look for non-finite tensions."""
    assert np.isnan(float(safe_norm(jnp.array([jnp.nan, 0.0, 1.0]))))
    assert np.isinf(float(safe_norm(jnp.array([jnp.inf, 0.0, 1.0]))))
    assert float(safe_norm(jnp.zeros(3))) == 0.0
