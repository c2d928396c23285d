"""Dynamics: structured Newton solve, derivative safety, accuracy, bad input."""

import os

import jax
import jax.numpy as jnp
import lineax as lx
import numpy as np
import pytest

import moorjax as mj
from moorjax.dynamics import simulate
from moorjax.dynamics.vector_field import pack, vector_field
from moorjax.linalg.banded_solver import BlockTridiagonalSolver
from moorjax.statics import solve_line_statics
from scenes import case_b_scene

DATA = os.path.join(os.path.dirname(__file__), "data")


@pytest.mark.slow
def test_band_jacobian_equals_dense_jacobian():
    """The coloured-JVP band reproduces the full Jacobian of the vector field."""
    scene = case_b_scene(12)
    y = pack([solve_line_statics(scene.lines[0], scene.env).state()])
    y = (y[0].at[:, 3:].set(0.3),)  # moving nodes: drag terms active
    f = lambda q: vector_field(0.7, (q,), scene)[0]  # noqa: E731
    dense = jax.jacfwd(f)(y[0]).reshape(y[0].size, y[0].size)
    assert np.all(np.isfinite(dense))
    op = lx.JacobianLinearOperator(lambda q, a: f(q), y[0])
    rhs = jnp.asarray(np.random.default_rng(1).normal(size=y[0].shape))
    x = lx.linear_solve(op, rhs, BlockTridiagonalSolver()).value
    np.testing.assert_allclose(dense @ x.ravel(), rhs.ravel(), rtol=1e-8, atol=1e-8)


def test_jacobian_finite_at_rest_and_zero_length_segment():
    scene = case_b_scene(6, end_b=mj.FixedEnd([0, 0, -5.0]))
    line = scene.lines[0]
    q = line.straight_state().r
    q = q.at[1].set(q[0])  # two coincident nodes: a zero-length segment
    y = (jnp.concatenate([q, jnp.zeros_like(q)], axis=-1),)
    jac = jax.jacfwd(lambda q: vector_field(0.0, (q,), scene)[0])(y[0])
    assert np.all(np.isfinite(jac))


@pytest.mark.slow
def test_case_b_against_moordyn_reference():
    """Slack–snap case B: 8 s of fairlead tension within 2 % (RMS/std) at N = 20."""
    scene = case_b_scene(20)
    res = simulate(scene, 8.0, rtol=1e-6, atol=1e-6)
    ref = np.loadtxt(os.path.join(DATA, "ref_B.csv"), delimiter=",", skiprows=1)
    # the first sample is the initial state at t = 0; the reference starts at 0.05 s
    assert float(res.ts[0]) == 0.0
    k = len(res.ts) - 1
    np.testing.assert_allclose(np.asarray(res.ts[1:]), ref[:k, 0], atol=1e-9)
    ref_f = np.linalg.norm(ref[:k, 3:6], axis=1)
    err = np.sqrt(np.mean((np.asarray(res.tension_b[1:, 0]) - ref_f) ** 2)) / np.std(ref[:, 1])
    assert err < 0.02, err
    assert bool(res.succeeded()) and int(res.num_steps) > 0
    assert np.max(np.asarray(res.tension_b)) > 1.5e6  # the snap loads are there


@pytest.mark.slow
def test_held_line_stays_in_equilibrium():
    """Started from statics with the ends held, nothing moves (consistency of the two)."""
    scene = case_b_scene(10, end_b=mj.FixedEnd([0, 0, -5.0]))
    st = solve_line_statics(scene.lines[0], scene.env)
    res = simulate(scene, 2.0, dt_out=0.5)
    np.testing.assert_allclose(np.asarray(res.tension_b[:, 0]), float(st.tension_b), rtol=1e-6)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(duration=-1.0), "duration"),
        (dict(duration=1.0, solver="rk45x"), "unknown solver"),
        (dict(duration=1.0, rtol=1.0), "rtol"),
        (dict(duration=1.0, atol=0.0), "atol"),
        (dict(duration=1.0, dt=-0.1), "dt"),
    ],
)
def test_bad_arguments(kwargs, match):
    scene = case_b_scene(4)
    with pytest.raises(ValueError, match=match):
        simulate(scene, **kwargs)


def test_failure_is_reported_with_time():
    """Explicit Euler with a huge fixed step blows up: a clear error naming the time."""
    scene = case_b_scene(10)
    with pytest.raises(RuntimeError, match=r"failed at t"):
        simulate(scene, 2.0, solver="euler", dt=0.05, dt_out=0.1)
    res = simulate(scene, 2.0, solver="euler", dt=0.05, dt_out=0.1, throw=False)
    assert not np.all(np.isfinite(np.asarray(res.tension_b)))


@pytest.mark.slow
def test_newton_iterations_are_counted():
    """count_newton: ESDIRK stages need at least 2 very-chord iterations each; a
    step evaluates the vector field once more, at the linearisation point of its
    iteration matrix (session 35: no longer also for the explicit first stage's
    identity matrix)."""
    scene = case_b_scene(6)
    res = simulate(scene, 0.5, solver="kvaerno3", count_newton=True)
    steps = int(res.num_steps)
    assert int(res.num_evaluations) == int(res.num_newton_iterations) + steps
    assert int(res.num_newton_iterations) >= 2 * 3 * steps  # 3 implicit stages
    plain = simulate(scene, 0.5, solver="kvaerno3")
    assert plain.num_newton_iterations is None
    np.testing.assert_allclose(np.asarray(plain.tension_b), np.asarray(res.tension_b), rtol=1e-12)
