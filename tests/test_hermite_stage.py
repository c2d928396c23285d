"""The Hermite element's stage matrix in mass form (:mod:`moorjax.element.hermite_stage`).

Newton's linear solve of an implicit stage, (I − c·J)·δ = r, is done by a
block-tridiagonal factorisation of M − c·C − c²·K instead of a dense LU of the
vector field's Jacobian. Checked against that dense solve on moving states (in
water with a seabed, with bending stiffness, on a graded mesh), and in whole
runs against the dense Newton.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import moorjax as mj
from moorjax.dynamics import simulate
from moorjax.dynamics.initial import equilibrium_state
from moorjax.dynamics.newton import StageFactorSolver
from moorjax.dynamics.settings import plan
from moorjax.dynamics.vector_field import has_stage_factors, pack
from moorjax.element import HermiteElement, LinearElement
from moorjax.element.hermite_motion import (MixedTension, ProjectedTension, StrainTension,
                                            state_rate)
from moorjax.element.hermite_stage import stage_factor
from scenes import hermite_case_a
from test_hermite_bodies import body_scene, point_scene

case_a = hermite_case_a


def _moving_state(scene, seed):
    """The static state with drawn node velocities and displaced nodes and slopes."""
    q = pack(equilibrium_state(scene, 0.0).state)[0]
    rng = np.random.default_rng(seed)
    return q + jnp.asarray(rng.normal(size=q.shape) * np.array([0.05] * 3 + [0.5] * 3))


CLAMP_A = mj.ClampedEnd((-853.87, 0.0, -320.0), (1.0, 0.0, 0.0))  # case A's anchor, along the bed


@pytest.mark.parametrize("variant", ["plain", "strain", "bending", "graded", "clamped"])
def test_the_factored_stage_solve_equals_the_dense_one(variant):
    """δ from the mass-form factor equals the dense solve of (I − c·J)·δ = r
    (J the vector field's Jacobian by forward differentiation) to 1e-9 of δ, for
    drawn states of case A's chain (seabed contact, drag, added mass), for
    several c = γ·h from 1 ms to 1 s; with bending stiffness, on a graded mesh,
    and clamped at the anchor (the clamped slope's held components projected
    out; the drawn state moves them too, which the exact J sees). Element-local
    closures: the per-element projected field, and the strain closure."""
    local = ProjectedTension(continuous=False)  # element-local: the factor is exact
    if variant == "graded":
        element = HermiteElement(mesh=np.array([1.0, 2.0, 3.0, 2.0, 1.5, 1.0]), tension=local)
    else:
        element = HermiteElement(tension=StrainTension() if variant == "strain" else local)
    scene = case_a(6, element=element)
    if variant == "bending":
        scene = eqx.tree_at(lambda s: s.lines[0].line_type.ei, scene, 5.0e6,
                            is_leaf=lambda x: x is None)
    if variant == "clamped":
        scene = eqx.tree_at(lambda s: s.lines[0].end_a, scene, CLAMP_A)
    line, env = scene.lines[0], scene.env
    jacobian = jax.jit(jax.jacfwd(lambda q, t: state_rate(line, env, t, q)))
    factored = jax.jit(lambda q, t, c, r: stage_factor(line, env, t, q, c).solve(r))
    for seed, c in enumerate([1e-3, 2e-2, 1.0]):
        q = _moving_state(scene, seed)
        t = 1.3 + seed
        a = np.eye(q.size) - c * np.asarray(jacobian(q, t)).reshape(q.size, q.size)
        r = np.random.default_rng(10 + seed).normal(size=q.shape)
        want = np.linalg.solve(a, r.ravel()).reshape(q.shape)
        got = np.asarray(factored(q, t, c, jnp.asarray(r)))
        assert np.max(np.abs(got - want)) < 1e-9 * np.max(np.abs(want)), (variant, c)


def test_the_continuous_field_s_stages_use_the_per_element_field_s_matrix():
    """Wu's continuous field (the default closure) couples the line: its stage
    matrix is the per-element field's, which on drawn moving states of case A
    solves (I − c·J)·δ = r with the exact J to a residual well inside one
    (Newton's iteration then contracts); on a straight taut line the two are
    equal (tests/test_hermite_projected_tension.py)."""
    scene = case_a(6)
    assert isinstance(scene.lines[0].element.tension, ProjectedTension)
    assert scene.lines[0].element.tension.continuous
    local = case_a(6, element=HermiteElement(tension=ProjectedTension(continuous=False)))
    line, env = scene.lines[0], scene.env
    jacobian = jax.jit(jax.jacfwd(lambda q, t: state_rate(line, env, t, q)))
    factored = jax.jit(lambda q, t, c, r: stage_factor(line, env, t, q, c).solve(r))
    factored_local = jax.jit(lambda q, t, c, r: stage_factor(local.lines[0], env, t, q, c).solve(r))
    worst = 0.0
    for seed, c in enumerate([1e-3, 2e-2, 1.0]):
        q = _moving_state(scene, seed)
        t = 1.3 + seed
        r = jnp.asarray(np.random.default_rng(10 + seed).normal(size=q.shape))
        got = np.asarray(factored(q, t, c, r))
        # the same matrix, taken at the accelerations of each closure (M·a in K)
        np.testing.assert_allclose(got, np.asarray(factored_local(q, t, c, r)), rtol=0,
                                   atol=1e-4 * np.abs(got).max())
        a = np.eye(q.size) - c * np.asarray(jacobian(q, t)).reshape(q.size, q.size)
        residual = a @ got.ravel() - np.asarray(r).ravel()
        worst = max(worst, np.linalg.norm(residual) / np.linalg.norm(np.asarray(r)))
    print(f"\nrelative residual of the per-element matrix's solve: {worst:.3g}")
    assert worst < 0.5, worst


def test_plan_factors_hermite_lines_and_keeps_the_dense_solve_where_it_cannot():
    hermite = case_a(4)
    assert has_stage_factors(hermite)
    root = plan(1.0, solver="kvaerno5", scene=hermite).solver.root_finder
    assert isinstance(root.linear_solver, StageFactorSolver)
    assert plan(1.0, solver="ros34pw2", scene=hermite).solver.factors is not None
    # a clamped end: its slope's held components are projected out of the band
    clamped = eqx.tree_at(lambda s: s.lines[0].end_a, hermite, CLAMP_A)
    assert has_stage_factors(clamped)
    root = plan(1.0, solver="kvaerno5", scene=clamped).solver.root_finder
    assert isinstance(root.linear_solver, StageFactorSolver)
    # Wu's mixed field couples each element's tension to the whole line: dense
    mixed = case_a(4, element=HermiteElement(tension=MixedTension()))
    assert not has_stage_factors(mixed)
    root = plan(1.0, solver="kvaerno5", scene=mixed).solver.root_finder
    assert not isinstance(root.linear_solver, StageFactorSolver)
    # with bodies: the lines' factors beside each body's exact block (Kvaerno);
    # ROS34PW2 takes the dense matrix there (its W must be the whole Jacobian)
    moored = body_scene(2, HermiteElement())
    assert has_stage_factors(moored)
    root = plan(1.0, solver="kvaerno5", scene=moored).solver.root_finder
    assert isinstance(root.linear_solver, StageFactorSolver)
    assert plan(1.0, solver="ros34pw2", scene=moored).solver.factors is None
    # asked for where no element factors its stage matrix
    with pytest.raises(ValueError, match="linear_solver='element'"):
        plan(1.0, solver="kvaerno5", scene=case_a(4, element=LinearElement()),
             linear_solver="element")
    with pytest.raises(ValueError, match="linear_solver='element'"):
        plan(1.0, solver="kvaerno5", scene=mixed, linear_solver="element")


@pytest.mark.parametrize("closure", ["per-element", "continuous"])
def test_runs_with_the_factored_stages_follow_the_dense_newton(closure):
    """Case A at 4 elements over 3 s (the first surge): the fairlead force with the
    mass-form stage solve and with the dense LU agree within the run's tolerance,
    and ROS34PW2 on the factored stage matrix follows them at a tenth of the
    tolerances (within 0.5 % of the force's range: another method's error,
    measured 0.24 %). The per-element field's matrix is exact: both Newton
    iterations converge to the same stages (measured 2e-10 of the range apart).
    Wu's continuous field (the default) iterates on that matrix: its stages
    stop within Newton's tolerance of the dense ones (1.25e-3 of the range
    apart), inside the run's own time error (both 4.1e-3 from a run at 1e-8/1e-7),
    in 26 steps against 31."""
    element = (HermiteElement() if closure == "continuous"
               else HermiteElement(tension=ProjectedTension(continuous=False)))
    scene = case_a(4, element=element)
    fast = simulate(scene, 3.0, solver="kvaerno5")
    dense = simulate(scene, 3.0, solver="kvaerno5", linear_solver="dense")
    ros = simulate(scene, 3.0, solver="ros34pw2", rtol=1e-6, atol=1e-5)
    f_dense, f_fast, f_ros = (np.linalg.norm(np.asarray(run.force_b[:, 0]), axis=-1)
                              for run in (dense, fast, ros))
    assert np.max(np.abs(f_ros - f_dense)) < 5e-3 * np.ptp(f_dense)
    assert int(fast.num_steps) <= 1.2 * int(dense.num_steps)
    if closure == "per-element":
        assert np.max(np.abs(f_fast - f_dense)) < 2e-4 * np.ptp(f_dense)
        return
    assert np.max(np.abs(f_fast - f_dense)) < 2e-3 * np.ptp(f_dense)
    tight = simulate(scene, 3.0, solver="kvaerno5", rtol=1e-8, atol=1e-7, linear_solver="dense")
    f_tight = np.linalg.norm(np.asarray(tight.force_b[:, 0]), axis=-1)
    assert np.max(np.abs(f_fast - f_tight)) < 1.1 * np.max(np.abs(f_dense - f_tight))


@pytest.mark.slow
def test_body_scene_with_the_lines_factors_follows_the_dense_newton():
    """A buoyant point on three Hermite lines (4 elements) released with 15 m³
    more volume, 2 s: the block-Jacobi stage matrix (each line's mass form with
    its fairlead where the point is, the point's exact block, their coupling
    left to the iteration) gives the dense Newton's run within the run's
    tolerance: measured 5.1e-5 m of 1.28 m travel, 167 N of the 1.44e5 N
    fairlead tension range (1.2e-3: the stiff lines' axial ringing), 28 steps
    against 27. (A rigid body on the same lines, 8 elements, 10 s: 0.57 s
    against 4.1 s dense, same 25 steps.) ~2 min."""
    from moorjax.dynamics.initial import equilibrium_state

    eq = equilibrium_state(point_scene(4, HermiteElement()))
    scene = point_scene(4, HermiteElement(), volume=75.0)
    runs = [simulate(scene, 2.0, init=eq.state, dt_out=0.1, solver="kvaerno5", linear_solver=ls)
            for ls in ("element", "dense")]
    assert all(bool(r.succeeded()) for r in runs)
    (pa, ta), (pb, tb) = ((np.asarray(r.body_pose[:, 0]), np.asarray(r.tension_b))
                          for r in runs)
    travel = np.ptp(pb, axis=0).max()
    assert travel > 0.5  # the point moves
    assert np.abs(pa - pb).max() < 1.5e-4 * travel
    assert np.abs(ta - tb).max() < 3e-3 * np.ptp(tb)
    assert int(runs[0].num_steps) <= 1.2 * int(runs[1].num_steps)
