"""No two batched LAPACK calls of a compiled program may run at once
(:mod:`moorjax.linalg.ordering`: jaxlib 0.10's batched kernels deadlock XLA:CPU's
thread pool when as many run at once as it has threads).

The check reads the optimised HLO of the compiled programs
(:mod:`hlo_concurrency`): the system statics' Newton linearisation
(``_newton_parts``) and the compiled equilibrium iteration that starts a
simulation (``_body_equilibrium``), for a point on three lines of each element,
and the time integration of a point on Hermite lines. Before
:func:`~moorjax.linalg.ordering.after` ordered them, the line statics'
minimum-norm derivative solve (:class:`~moorjax.linalg.undetermined.MinimumNorm`)
ran its LU and its SVD side by side: the pair gdb found in the hung test run.
"""

from __future__ import annotations

import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import moorjax as mj
from moorjax.body import ConnectionPoint
from moorjax.dynamics.initial import _body_equilibrium
from moorjax.element import HermiteElement
from moorjax.statics.system import _newton_parts, line_statics_at

from hlo_concurrency import concurrent_lapack

LT = mj.LineType(0.08, 30.0, 2.0e8)
ENV = mj.Environment(200.0, seabed=None)
ANCHORS = [np.array([300 * np.cos(a), 300 * np.sin(a), -200.0]) for a in (0, 2 * np.pi / 3, 4 * np.pi / 3)]


def point_scene(element, segments=(6, 6, 6)):
    """A buoyant point on three lines from anchors 300 m away (``segments``:
    each line's element count; unequal counts are separate line groups)."""
    point = ConnectionPoint(2e4, [0, 0, -40.0], volume=60.0)
    lines = [mj.Line(LT, 330.0, n, mj.FixedEnd(a), mj.BodyEnd(0, [0, 0, 0]), element=element,
                     label=str(i + 1))
             for i, (n, a) in enumerate(zip(segments, ANCHORS))]
    return mj.Scene(lines, ENV, bodies=[point])


def test_analyser_finds_independent_batched_kernels():
    """The analyser is not blind: an LU solve and a pseudo-inverse of the same
    batch of matrices, neither waiting for the other, are reported; ordered
    with ``after``, they are not."""
    from moorjax.linalg.ordering import after

    def both(a, b):
        x = jnp.linalg.solve(a, b)
        return x + jnp.linalg.pinv(a) @ b

    def ordered(a, b):
        x = jnp.linalg.solve(a, b)
        return x + jnp.linalg.pinv(after(a, x)) @ b

    a = jnp.ones((4, 6, 6)) + 3 * jnp.eye(6)
    b = jnp.ones((4, 6))
    text = lambda f: jax.jit(jax.vmap(f)).lower(a, b).compile().as_text()  # noqa: E731
    assert concurrent_lapack(text(both))
    assert not concurrent_lapack(text(ordered))
    np.testing.assert_allclose(jax.vmap(ordered)(a, b), jax.vmap(both)(a, b))


def test_after_changes_no_value_and_no_derivative():
    """``after`` is the identity on x's values and derivatives, passes a
    derivative of zero to its dependencies, keeps non-float leaves, and a
    non-finite dependency (a failed solve) does not leak into x."""
    from moorjax.linalg.ordering import after

    x = {"a": jnp.array([1.0, -2.0, -0.0]), "n": jnp.array([3, 4]), "s": None}
    deps = (jnp.array([jnp.nan, 1.0]), jnp.array(jnp.inf), jnp.array([1, 2]))
    out = after(x, *deps)
    np.testing.assert_array_equal(out["a"], x["a"])
    np.testing.assert_array_equal(np.signbit(out["a"]), np.signbit(x["a"]))  # −0 stays −0
    assert out["n"].dtype == x["n"].dtype and out["s"] is None

    f = lambda a, d: jnp.sum(after(a, d) ** 2)  # noqa: E731
    ga, gd = jax.grad(f, argnums=(0, 1))(jnp.array([1.0, 2.0]), jnp.array([5.0, 6.0]))
    np.testing.assert_array_equal(ga, [2.0, 4.0])
    np.testing.assert_array_equal(gd, [0.0, 0.0])
    _, tangent = jax.jvp(lambda a, d: after(a, d), (jnp.ones(2), jnp.ones(2)), (jnp.ones(2), jnp.ones(2)))
    np.testing.assert_array_equal(tangent, [1.0, 1.0])


@pytest.mark.parametrize("element", [None, HermiteElement()], ids=["linear", "hermite"])
def test_body_statics_run_one_batched_lapack_call_at_a_time(element):
    scene = point_scene(element)
    poses = jnp.zeros((1, 6))
    t = jnp.asarray(0.0)
    methods = ("fem",) * len(scene.lines)
    inits = tuple(s.state() for s in line_statics_at(scene, poses, t, None, methods))
    compiled = lambda program, *args: program.lower(*args).compile().compiled.as_text()  # noqa: E731
    programs = {
        "_newton_parts": compiled(_newton_parts, scene, poses, t, True, inits, methods),
        "_body_equilibrium": compiled(_body_equilibrium.jitted, scene, t, True, 1e-6, 50),
    }
    for name, text in programs.items():
        assert "lapack" in text, name  # the programs do factorise batches
        assert concurrent_lapack(text) == [], name


@pytest.mark.slow
@pytest.mark.parametrize("lines", [(6, 6, 6), (4, 6, 6)], ids=["one-structure", "two-structures"])
def test_hermite_point_dynamics_run_one_batched_lapack_call_at_a_time(lines):
    """The time integration of a point on three Hermite lines (the default stage
    solve: each line's mass-form factors, the point's exact block beside them):
    its vector field factors each line's consistent mass and solves its tension
    field; the stage matrix factors the lines' blocks and differentiates the
    vector field for the point's block. Lines of two structures are two vmapped
    groups, each with its own factorisations. Before the ordering, the step loop
    of one structure held dozens of independent pairs (the consistent mass's
    Cholesky in the vector field beside the one in its derivative, their
    triangular solves, the stage factors' 6×6 inverses). The pairs before the
    loop, in a branch a run never takes, are left (see the end)."""
    from moorjax.dynamics.initial import catenary_state
    from moorjax.dynamics.simulate import _integrate, plan
    from moorjax.dynamics.vector_field import pack

    scene = point_scene(HermiteElement(), lines)
    settings = plan(1.0, scene=scene)
    y0 = pack(catenary_state(scene).state)
    text = _integrate.jitted.lower(scene, y0, settings, count=False).compile().compiled.as_text()
    assert "lapack_dpotrf" in text
    entry = re.search(r"^ENTRY %?([\w.\-]+)", text, re.M).group(1)
    pairs = concurrent_lapack(text)
    # every step (the loops' bodies): one batched call at a time
    assert [p for p in pairs if p[0] != entry] == []
    # left: before the loop, diffrax's branch for t1 == t0 (save the outputs
    # without stepping; a conditional on t0 == t1, checked in the HLO) is
    # independent of the first vector-field evaluation. A run never takes it:
    # plan() requires the last output time after t0
    assert all("cond" in p[1] or "cond" in p[2] for p in pairs), pairs
    assert len(pairs) <= 3, pairs
