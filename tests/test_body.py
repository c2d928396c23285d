"""A floating body on mooring lines: statics, stiffness, free decay, energy, bad input.

The body is Wu et al.'s box (45 m × 45 m, draft 20 m, 41,512 t) with simple
hydrodynamics (constant added mass, analytic box hydrostatics) and four taut
synthetic lines, so that every check has a closed-form or independent reference.
"""

from __future__ import annotations

import functools

import jax.numpy as jnp
import numpy as np
import pytest

import moorjax as mj
from moorjax.body import RigidBody
from moorjax.dynamics import simulate
from moorjax.statics import (mooring_stiffness, offset_curve, solve_system_statics,
                             system_stiffness)

pytestmark = pytest.mark.slow  # long physics/compile checks: CI runs them, `-m "not slow"` skips

RHO, G = 1025.0, 9.80665
LB, DRAFT, ZG = 45.0, 20.0, -6.25
VOL = LB * LB * DRAFT
MASS = RHO * VOL
INERTIA = (4.5316e10, 4.2748e10, 4.8877e10)
FAIRLEAD_Z = -DRAFT - ZG  # keel corners, in body axes
DEPTH = 80.0


def box_hydrostatics():
    c = np.zeros((6, 6))
    zb = -DRAFT / 2
    c[2, 2] = RHO * G * LB * LB
    c[3, 3] = c[4, 4] = RHO * G * (LB**4 / 12 + VOL * (zb - ZG))
    return c


ADDED = np.diag([0.6 * MASS, 0.6 * MASS, 1.0 * MASS, 0.2 * INERTIA[0], 0.2 * INERTIA[1], 0.1 * INERTIA[2]])


def box(mass=MASS, **kw):
    inertia = np.asarray(INERTIA) * mass / MASS
    return RigidBody(mass, inertia, added_mass=ADDED * mass / MASS, hydrostatic=box_hydrostatics(),
                     origin=(0.0, 0.0, ZG), half_size=(22.5, 22.5, 13.75), **kw)


def rope(drag=False, added=False):
    return mj.LineType(0.1, 20.0, 5.0e7,
                       drag=mj.MorisonDrag(1.2, 0.2) if drag else None,
                       added_mass=mj.AddedMass(1.0, 0.0) if added else None)


def corners():
    for k, ang in enumerate((45.0, 135.0, 225.0, 315.0)):
        c, s = np.cos(np.radians(ang)), np.sin(np.radians(ang))
        fl = np.array([22.5 * np.sign(c), 22.5 * np.sign(s), FAIRLEAD_Z])
        yield k, c, s, fl


def lines(lt, n=6, radius=75.0, length=95.0, end_of=None):
    out = []
    for k, c, s, fl in corners():
        anchor = np.array([fl[0] + radius * c, fl[1] + radius * s, -DEPTH])
        end = mj.BodyEnd(0, fl) if end_of is None else end_of(fl)
        out.append(mj.Line(lt, length, n, mj.FixedEnd(anchor), end, label=str(k + 1)))
    return out


def scene(body=None, lt=None, **kw):
    env = mj.Environment(DEPTH, RHO, G)
    return mj.Scene(lines(lt or rope(), **kw), env, bodies=[body or box()])


@functools.lru_cache(maxsize=None)
def equilibrium():
    sc = scene()
    return sc, solve_system_statics(sc)


def test_statics_symmetric_and_balanced():
    sc, st = equilibrium()
    assert st.converged
    pose = np.asarray(st.poses[0])
    np.testing.assert_allclose(pose[[0, 1, 3, 4, 5]], 0.0, atol=1e-9)
    # heave: the lines' vertical pull sinks the box by Fz / C33
    fz = float(np.asarray(st.mooring)[0, 2])
    assert fz < 0
    assert pose[2] == pytest.approx(fz / box_hydrostatics()[2, 2], rel=1e-6)
    tb = np.array([float(s.tension_b) for s in st.lines])
    np.testing.assert_allclose(tb, tb[0], rtol=1e-9)
    assert np.max(np.abs(np.asarray(st.residual))) < 1e-3 * tb[0]


def test_offset_slope_equals_ad_stiffness():
    sc, st = equilibrium()
    k = np.asarray(mooring_stiffness(sc, st.poses))
    np.testing.assert_allclose(k, k.T, rtol=1e-6, atol=1e-6 * np.abs(k).max())
    h = 1e-3
    for dof in (0, 2, 4):
        f = np.asarray(offset_curve(sc, [-h, h], dof=dof))
        fd = (f[1] - f[0]) / (2 * h)
        # offset_curve moves one dof from zero; compare with K there
        k0 = np.asarray(mooring_stiffness(sc))[dof, dof]
        assert fd == pytest.approx(k0, rel=1e-5), dof
    assert k[0, 0] > 0 and k[2, 2] > 0


def _periods(t, x):
    x = x - np.mean(x)
    up = np.where((x[:-1] < 0) & (x[1:] >= 0))[0]
    tc = t[up] - x[up] * (t[up + 1] - t[up]) / (x[up + 1] - x[up])
    return np.diff(tc)


def test_free_decay_periods_match_linearised_system():
    sc, st = equilibrium()
    k = np.asarray(system_stiffness(sc, st.poses))
    m = np.asarray(sc.bodies[0].mass_matrix + sc.bodies[0].added_mass)
    lam, _ = np.linalg.eig(np.linalg.solve(m, k))
    expected = np.sort(2 * np.pi / np.sqrt(lam.real))
    heave_T = 2 * np.pi / np.sqrt(k[2, 2] / m[2, 2])
    pitch_T = 2 * np.pi / np.sqrt(k[4, 4] / m[4, 4])
    # heave is uncoupled by symmetry; pitch couples weakly with surge
    assert np.min(np.abs(expected - heave_T)) < 1e-6 * heave_T
    init = st.state() + (sc.bodies[0].rest_state(st.poses[0] + jnp.array([0, 0, 0.2, 0, 0.002, 0])),)
    res = simulate(sc, 3.2 * pitch_T, init=init, dt_out=0.1, rtol=1e-7, atol=1e-6)
    t = np.asarray(res.ts)
    heave = np.asarray(res.body_pose[:, 0, 2])
    pitch = np.asarray(res.body_pose[:, 0, 4])
    th = np.mean(_periods(t, heave))
    tp = np.mean(_periods(t, pitch))
    pitch_exact = expected[np.argmin(np.abs(expected - pitch_T))]
    assert th == pytest.approx(heave_T, rel=0.02)
    assert tp == pytest.approx(pitch_exact, rel=0.02)


def test_energy_conserved_without_dissipation():
    """Body (kinetic with A∞ + hydrostatic) + lines (kinetic, elastic, weight) energy
    stays constant with no drag, no damping, no radiation and no added mass on lines."""
    sc, st = equilibrium()
    body = sc.bodies[0]
    lt = sc.lines[0].line_type
    l = float(sc.lines[0].segment_length)
    w = float(lt.wet_weight(RHO, G))
    ea = 5.0e7
    mu = float(lt.mass_per_length)

    def energy(state):
        z = np.asarray(state[-1])
        pose = z[:6]
        total = float(body.energy(jnp.asarray(z)))
        fl_pos = []
        for line, ls in zip(sc.lines, state[:-1]):
            r, v = np.asarray(ls.r), np.asarray(ls.v)
            a = np.asarray(line.end_a.position(0.0))
            b = np.asarray(body.point_position(jnp.asarray(pose), line.end_b.point))
            nodes = np.vstack([a, r, b])
            strain = np.linalg.norm(np.diff(nodes, axis=0), axis=1) / l - 1
            assert np.all(strain > 0)
            total += 0.5 * ea * l * np.sum(strain**2)
            total += w * l * np.sum(r[:, 2]) + w * l / 2 * b[2]
            total += 0.5 * mu * l * np.sum(v**2)
            fl_pos.append(b)
        return total

    kick = jnp.array([0.05, 0.03, 0.02, 0.0, 0.0, 1e-4])  # η̇ [m/s, rad/s]
    init = st.state() + (body.rest_state(st.poses[0]).at[6:12].set(kick),)
    res = simulate(sc, 20.0, init=init, dt_out=1.0, rtol=1e-9, atol=1e-8)
    e0 = energy(init)
    e1 = energy(res.final_state)
    moving = float(body.energy(init[-1]) - body.energy(body.rest_state(st.poses[0])))
    assert abs(e1 - e0) < 1e-4 * moving, (e0, e1, moving)


def test_held_body_reproduces_standalone_lines():
    """A body too heavy to move gives the same line dynamics as fixed fairleads."""
    heavy = box(mass=MASS * 1e12)
    lt = rope(drag=True, added=True)
    with_body = scene(heavy, lt)
    fixed = mj.Scene(lines(lt, end_of=lambda fl: mj.FixedEnd(np.array([0, 0, ZG]) + fl)),
                     with_body.env)
    init = tuple(ln.straight_state() for ln in fixed.lines)
    # tight tolerances: the two runs take different steps (the body's state is
    # in the error norm), so each must be accurate well below the comparison
    tight = dict(dt_out=0.25, rtol=1e-9, atol=1e-8, solver="kvaerno5")
    a = simulate(fixed, 5.0, init=init, **tight)
    b = simulate(with_body, 5.0, init=init, **tight)
    scale = np.max(np.asarray(a.tension_b))
    np.testing.assert_allclose(np.asarray(b.tension_b), np.asarray(a.tension_b), atol=1e-5 * scale)
    np.testing.assert_allclose(np.asarray(b.tension_a), np.asarray(a.tension_a), atol=1e-5 * scale)
    assert np.max(np.abs(np.asarray(b.body_pose))) < 1e-8


def test_bad_input_names_the_item():
    with pytest.raises(ValueError, match="heave"):
        RigidBody(MASS, INERTIA, hydrostatic=np.zeros((6, 6)))
    with pytest.raises(ValueError, match="6×6"):
        RigidBody(MASS, INERTIA, hydrostatic=np.eye(5))
    with pytest.raises(ValueError, match="outside body"):
        env = mj.Environment(DEPTH)
        ln = mj.Line(rope(), 95.0, 4, mj.FixedEnd([100.0, 0, -80]), mj.BodyEnd(0, [30.0, 0, 0]))
        mj.Scene([ln], env, bodies=[box()])
    with pytest.raises(ValueError, match="body 1"):
        ln = mj.Line(rope(), 95.0, 4, mj.FixedEnd([100.0, 0, -80]), mj.BodyEnd(1, [20.0, 0, 0]))
        mj.Scene([ln], mj.Environment(DEPTH), bodies=[box()])
    far = scene(length=40.0)
    with pytest.raises(ValueError, match="line 1: impossible geometry"):
        solve_system_statics(far)
