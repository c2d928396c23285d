"""The one integration core: diffrax only in moorjax.dynamics, its one internal
patch pinned to the diffrax version, body weights computed at run time, and an
initial state that vmaps over the parameters of a scene with a body."""

from __future__ import annotations

import inspect
import pathlib
import re

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import moorjax as mj
from moorjax.body import ConnectionPoint
from moorjax.dynamics import adjoint, equilibrium_state
from moorjax.ensemble import equilibrium as ensemble_equilibrium
from moorjax.statics import solve_line_statics

pytestmark = pytest.mark.slow  # long physics/compile checks: CI runs them, `-m "not slow"` skips

ROOT = pathlib.Path(mj.__file__).parent


def test_only_dynamics_imports_diffrax():
    users = sorted(str(p.relative_to(ROOT)) for p in ROOT.rglob("*.py")
                   if re.search(r"^\s*(import|from)\s+diffrax\b", p.read_text(), re.M))
    assert users and all(u.startswith("dynamics/") for u in users), users


def test_structured_gradient_patch_is_pinned_to_diffrax():
    """The structured implicit-function solves replace ``optx`` in two diffrax
    modules (diffrax has no option for it). A diffrax upgrade must fail here, so
    that someone checks the patch (and the gradient tests) against it."""
    assert diffrax.__version__ == adjoint.PATCHED_DIFFRAX
    for name in adjoint.PATCHED_MODULES:
        module = __import__(name, fromlist=["optx"])
        src = inspect.getsource(module)
        # the implicit stages call optimistix's root_find, without an adjoint
        calls = re.findall(r"optx\.root_find\((.*?)\n\s*\)", src, re.S)
        assert calls and all("adjoint" not in c for c in calls), name
        assert hasattr(module, "optx")
    with adjoint.structured_implicit_gradients():
        for name in adjoint.PATCHED_MODULES:
            assert isinstance(__import__(name, fromlist=["optx"]).optx,
                              adjoint._StructuredOptimistix)
        assert adjoint._STRUCTURED.get()
    assert not adjoint._STRUCTURED.get()  # outside, root_find is optimistix's own


# --------------------------------------------------------------------------- bodies

LT = mj.LineType(0.08, 30.0, 2.0e8, drag=mj.MorisonDrag(1.2, 0.2))
ENV = mj.Environment(200.0, seabed=None)
A, B = np.array([-300.0, 0.0, -200.0]), np.array([0.0, 0.0, -20.0])
N1, N2, L_SEG = 3, 2, 80.0
NODE_MASS = float(LT.mass_per_length) * L_SEG


def series(point):
    l1 = mj.Line(LT, N1 * L_SEG, N1, mj.FixedEnd(A), mj.BodyEnd(0, [0, 0, 0]), label="1")
    l2 = mj.Line(LT, N2 * L_SEG, N2, mj.BodyEnd(0, [0, 0, 0]), mj.FixedEnd(B), label="2")
    return mj.Scene([l1, l2], ENV, bodies=[point])


def test_point_weight_follows_its_mass_under_grad():
    """d(acceleration)/d(mass) includes the weight's change: −g/(m + a) − F/(m + a)²."""
    rho, g, vol, added = 1025.0, 9.80665, 0.5, 100.0
    point = ConnectionPoint(800.0, [0, 0, -50.0], volume=vol, added_mass=added, rho=rho, g=g)
    z = point.rest_state()

    def heave_acc(m):
        return eqx.tree_at(lambda p: p.mass, point, m).rate(0.0, z, jnp.zeros(6))[8]

    m = 800.0
    net = (rho * vol - m) * g
    expected = -g / (m + added) - net / (m + added) ** 2
    assert float(jax.grad(heave_acc)(m)) == pytest.approx(expected, rel=1e-12)
    # the statics' mean load too, and the volume's buoyancy
    load = lambda p: p.mean_load(jnp.zeros(6))[2]  # noqa: E731
    grads = eqx.filter_grad(load)(point)
    assert float(grads.mass) == pytest.approx(-g, rel=1e-12)
    assert float(grads.volume) == pytest.approx(rho * g, rel=1e-12)
    # ρ and g may come from the scene's environment instead
    env_point = ConnectionPoint(800.0, [0, 0, -50.0], volume=vol, rho=None, g=None)
    env = mj.Environment(200.0, rho, g, seabed=None)
    assert float(env_point.mean_load(jnp.zeros(6), env=env)[2]) == pytest.approx(net, rel=1e-12)


def test_equilibrium_state_vmaps_over_a_body_parameter():
    """The jittable system statics, vmapped over the point's mass, equals the
    members solved one by one; the point carrying the node mass (neutrally
    buoyant) sits where the single line's node does."""
    single = mj.Line(LT, (N1 + N2) * L_SEG, N1 + N2, mj.FixedEnd(A), mj.FixedEnd(B))
    node = np.asarray(solve_line_statics(single, ENV).positions[N1])

    def scene(mass):
        return series(ConnectionPoint(mass, node + np.array([3.0, 0.0, 2.0]),
                                      volume=NODE_MASS / 1025.0))

    masses = [NODE_MASS, 1.5 * NODE_MASS]
    scenes = [scene(m) for m in masses]
    states, converged = ensemble_equilibrium(scenes)
    assert np.all(np.asarray(converged))
    body_states = np.asarray(states[-1])  # (members, 12)
    for i, sc in enumerate(scenes):
        one = equilibrium_state(sc)
        assert bool(one.converged)
        np.testing.assert_allclose(body_states[i], np.asarray(one.state[-1]), atol=1e-8)
        for a, b in zip(jax.tree_util.tree_leaves(one.state[:2]),
                        jax.tree_util.tree_leaves(states[:2])):
            np.testing.assert_allclose(np.asarray(b[i]), np.asarray(a), atol=1e-8)
    origin = np.asarray(scenes[0].bodies[0].origin)
    np.testing.assert_allclose(origin + body_states[0, :3], node, atol=1e-6)
    assert body_states[1, 2] < body_states[0, 2] - 0.1  # the heavier point sits lower
    # a gradient through the vmapped statics reaches the point's mass
    stacked = mj.ensemble.stack(scenes)
    dz = eqx.filter_vmap(eqx.filter_grad(lambda s: equilibrium_state(s).state[-1][2]))(stacked)
    assert np.all(np.asarray(dz.bodies[0].mass) < 0)


def test_fixed_steps_retry_a_failed_newton_step():
    """Case A's chain landing on the seabed within a 50 ms step: the fixed-step
    run fails with a message naming the time and the remedy; with
    ``retry_failed_steps`` it completes and agrees with an adaptive run."""
    import sys

    sys.path.insert(0, str(ROOT.parent))
    from benchmarks.common import case_scene
    from moorjax.dynamics import simulate

    scene = case_scene("A", 10)
    init = equilibrium_state(scene, 0.0).state
    with pytest.raises(RuntimeError, match=r"failed at t ≈ .* retry_failed_steps=True"):
        simulate(scene, 6.0, init=init, dt=0.05, solver="kvaerno5")
    fixed = simulate(scene, 6.0, init=init, dt=0.05, retry_failed_steps=True, solver="kvaerno5")
    assert int(fixed.num_rejected_steps) > 0  # some steps were retried
    adaptive = simulate(scene, 6.0, init=init)
    tb, ta = np.asarray(fixed.tension_b[:, 0]), np.asarray(adaptive.tension_b[:, 0])
    assert np.sqrt(np.mean((tb - ta) ** 2)) < 0.01 * np.std(ta)


# ------------------------------------------------------------------- outputs


@pytest.mark.parametrize("bodies", [False, True])
def test_outputs_after_the_loop_equal_those_in_the_loop(monkeypatch, bodies):
    """A run whose saved states fit :data:`STATES_AFTER_LOOP` computes its outputs
    after the time loop from the states at the output times; with the limit at 0
    they come from inside the loop, as before session 35. Both give the same
    end forces, node outputs, body motion and final state (to rounding), and the
    same gradient of a fairlead tension with respect to a drag coefficient (the
    line alone)."""
    from moorjax.dynamics import integrate as core
    from moorjax.dynamics import simulate
    from scenes import case_b_scene

    if bodies:
        point = ConnectionPoint(2.0 * NODE_MASS, [-140.0, 0.0, -110.0], volume=NODE_MASS / 1025.0)
        scene = series(point)
    else:
        scene = case_b_scene(n=6)
    init = equilibrium_state(scene, 0.0).state

    def run(save_nodes):
        return simulate(scene, 4.0, init=init, dt_out=0.1, save_nodes=save_nodes)

    from moorjax.dynamics.vector_field import pack

    assert core.outputs_after_loop(pack(init), jnp.zeros(41))
    after = run(True)
    settings = mj.dynamics.plan(2.0, dt_out=0.1, scene=scene)

    def mean_tension(cd):  # the identification's path: no final state, a gradient
        sc = eqx.tree_at(lambda s: s.lines[0].line_type.drag.cd_normal, scene, cd)
        return jnp.mean(core.integrate(sc, pack(init), settings, keep_final=False).tension_b)

    cd = scene.lines[0].line_type.drag.cd_normal
    if not bodies:  # (the body scene's gradient only adds compile time)
        value_after, grad_after = jax.jit(jax.value_and_grad(mean_tension))(cd)
    monkeypatch.setattr(core, "STATES_AFTER_LOOP", 0)
    inside = run(True)
    if not bodies:
        value_inside, grad_inside = jax.jit(jax.value_and_grad(mean_tension))(cd)
        assert float(value_after) == pytest.approx(float(value_inside), rel=1e-12)
        assert float(grad_inside) != 0.0
        assert float(grad_after) == pytest.approx(float(grad_inside), rel=1e-8)
    assert int(after.num_steps) == int(inside.num_steps)
    for name in ("tension_a", "tension_b", "force_a", "force_b", "body_pose", "body_velocity"):
        a, b = getattr(after, name), getattr(inside, name)
        if a is None:
            assert b is None and not (bodies and name.startswith("body"))
            continue
        scale = max(float(np.max(np.abs(np.asarray(b)))), 1.0)
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=0, atol=1e-9 * scale)
    for name in ("positions", "velocities", "segment_tensions"):
        for a, b in zip(getattr(after, name), getattr(inside, name)):
            scale = max(float(np.max(np.abs(np.asarray(b)))), 1.0)
            np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=0, atol=1e-9 * scale)
    for a, b in zip(jax.tree_util.tree_leaves(after.final_state), jax.tree_util.tree_leaves(inside.final_state)):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=0, atol=1e-9 * max(float(np.max(np.abs(b))), 1.0))
