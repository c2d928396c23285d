"""A free connection point joining two lines behaves like the node it replaces.

Two lines in series through a ConnectionPoint carrying the node mass μ·l (the two
adjacent half-elements) are the same discrete system as one line with a node
there (nodal mass, no added mass): statics and dynamics must agree.
"""

from __future__ import annotations

import numpy as np
import pytest

import moorjax as mj
from moorjax.body import ConnectionPoint
from moorjax.dynamics import simulate
from moorjax.statics import solve_line_statics, solve_system_statics

pytestmark = pytest.mark.slow  # long physics/compile checks: CI runs them, `-m "not slow"` skips

LT = mj.LineType(0.08, 30.0, 2.0e8, drag=mj.MorisonDrag(1.2, 0.2))  # no added mass
ENV = mj.Environment(200.0, seabed=None)
A, B = np.array([-300.0, 0.0, -200.0]), np.array([0.0, 0.0, -20.0])
N1, N2, L_SEG = 6, 4, 40.0


def single():
    line = mj.Line(LT, (N1 + N2) * L_SEG, N1 + N2, mj.FixedEnd(A), mj.FixedEnd(B), label="1")
    return mj.Scene([line], ENV)


def series(guess):
    # the lines' end forces already carry the half-elements' wet weight, not their
    # inertia: the point gets their mass μ·l, with neutral buoyancy
    m = float(LT.mass_per_length) * L_SEG
    point = ConnectionPoint(m, guess, volume=m / 1025.0, rho=1025.0, g=9.80665)
    l1 = mj.Line(LT, N1 * L_SEG, N1, mj.FixedEnd(A), mj.BodyEnd(0, [0, 0, 0]), label="1")
    l2 = mj.Line(LT, N2 * L_SEG, N2, mj.BodyEnd(0, [0, 0, 0]), mj.FixedEnd(B), label="2")
    return mj.Scene([l1, l2], ENV, bodies=[point])


def test_series_statics_and_dynamics_equal_single_line():
    one = single()
    st1 = solve_line_statics(one.lines[0], ENV)
    node = np.asarray(st1.positions[N1])
    two = series(node + np.array([3.0, 0.0, 2.0]))  # start the point off its equilibrium
    st2 = solve_system_statics(two)
    point = np.asarray(two.bodies[0].origin + st2.poses[0, :3])
    np.testing.assert_allclose(point, node, atol=1e-6)
    assert abs(float(st2.lines[1].tension_b) - float(st1.tension_b)) < 1e-6 * float(st1.tension_b)

    # dynamics from a disturbed state: the same motion
    two = series(node)
    s1 = st1.state()
    kick = np.zeros_like(np.asarray(s1.v))
    kick[:, 2] = 1.0
    init1 = (mj.LineState(r=s1.r, v=kick),)
    init2 = (mj.LineState(r=s1.r[:N1 - 1], v=kick[:N1 - 1]),
             mj.LineState(r=s1.r[N1:], v=kick[N1:]),
             two.bodies[0].rest_state().at[8].set(1.0))
    # an explicit solver: no Newton approximations in either run (the response to
    # large kicks is very sensitive: snap loads; integrators differ after a few s)
    tight = dict(dt_out=0.25, rtol=1e-10, atol=1e-9, solver="dopri8")
    r1 = simulate(one, 3.0, init=init1, **tight)
    r2 = simulate(two, 3.0, init=init2, **tight)
    swing = float(np.ptp(np.asarray(r1.tension_b)))
    scale = float(np.max(np.asarray(r1.tension_b)))
    assert swing > 0.05 * scale
    np.testing.assert_allclose(np.asarray(r2.tension_b[:, 1]), np.asarray(r1.tension_b[:, 0]),
                               atol=1e-3 * swing)
    np.testing.assert_allclose(np.asarray(r2.tension_a[:, 0]), np.asarray(r1.tension_a[:, 0]),
                               atol=1e-3 * swing)


def test_start_on_lines_piled_on_the_bed():
    """A buoyant point on three 1037 m chains from anchors 672 m out on a 197 m
    bed: each line is longer than its anchor's L-shaped path to the fairlead
    (854 m), so 180 m pile up on the bed (zero anchor tension). At 80 segments
    a line's descent needs 438–656 steps to settle such a pile (drawn scenes of
    session 40), more than its limit was (500), and the start in one program
    (``equilibrium_state``) failed where the host loop (``solve_system_statics``)
    converged. Now the two agree on the pose within 1e-3 m (measured
    z = −0.9146 m)."""
    from moorjax.dynamics import equilibrium_state

    chain = mj.LineType(0.09, 77.7066, 384.243e6)
    bed = mj.Environment(depth=196.911, seabed=mj.Seabed(stiffness=3e6, damping=3e5))
    anchors = [671.916 * np.array([np.cos(a), np.sin(a), 0.0]) + [0, 0, -196.911]
               for a in (0.0, 2 * np.pi / 3, -2 * np.pi / 3)]
    lines = [mj.Line(chain, 1037.035, 80, mj.FixedEnd(a), mj.BodyEnd(0, [0, 0, 0]), label=f"L{i + 1}")
             for i, a in enumerate(anchors)]
    scene = mj.Scene(lines, bed, bodies=[ConnectionPoint(2e4, [0, 0, -14.486], volume=57.514)])
    eq = equilibrium_state(scene)
    host = solve_system_statics(scene)
    assert bool(eq.converged) and host.converged, eq.lines_converged
    assert np.allclose(np.asarray(eq.poses), np.asarray(host.poses), atol=1e-3), (eq.poses, host.poses)
    assert abs(float(eq.poses[0, 2])) > 0.5  # it moved off the deck position
