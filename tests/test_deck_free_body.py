"""Free bodies (``BODIES`` rows with attachment ``free``): :class:`SubmergedBody`.

- the body's rigid dynamics: torque-free rotation follows Euler's equations
  (gyroscopic term, MoorDyn's rotation order), fixed points move as the time
  derivative of their positions, a pendulum's restoring moment is −W·c·sin φ;
- a deck's free body carries the deck's values, its points' and its lines' end
  nodes' inertia (``tests/data/body_free.dat``);
- ``tests/data/free_body_buoy.dat`` (a buoyant body tilted 5°/−8°, held by three
  chains; made for moorjax) against MoorDyn 2.7.2 run here: the static pose
  against MoorDyn's state settled over 200–400 s of dynamics, and 2 s of
  dynamics from MoorDyn's un-relaxed initial state (``Init_NoIC``).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from moorjax.body import SubmergedBody
from moorjax.body.submerged import angular_velocity_map, moordyn_rotation
from moorjax.io import build_scene, read_deck
from moorjax.io.frames import moordyn_rotation as frames_rotation

DATA = Path(__file__).parent / "data"
FREE = DATA / "body_free.dat"
BUOY = DATA / "free_body_buoy.dat"


def _body(**kw):
    args = dict(mass=2.0e3, origin=(1.0, 2.0, -10.0), inertia=(1.0e3, 2.0e3, 3.0e3), rho=1025.0,
                g=9.80665)
    args.update(kw)
    return SubmergedBody(args.pop("mass"), args.pop("origin"), **args)


def test_rotation_is_moordyns():
    angles = np.array([0.3, -0.7, 1.1])
    np.testing.assert_allclose(moordyn_rotation(jnp.asarray(angles)), frames_rotation(angles), atol=1e-14)


@pytest.mark.parametrize("orientation", [(0.0, 0.0, 0.0), (0.4, -0.3, 1.2)])
def test_torque_free_rotation_follows_eulers_equations(orientation):
    body = _body(orientation=orientation, g=0.0)
    omega = jnp.array([0.3, -0.2, 0.5])
    z = body.rest_state().at[9:].set(omega)
    acc = np.asarray(body.rate(0.0, z, jnp.zeros(6)))[9:]
    rot = np.asarray(moordyn_rotation(jnp.asarray(orientation)))
    w_b = rot.T @ np.asarray(omega)
    inertia = np.array([1.0e3, 2.0e3, 3.0e3])
    dw_b = -np.cross(w_b, inertia * w_b) / inertia  # Euler: I·ω̇ = −ω×Iω in body axes
    np.testing.assert_allclose(acc, rot @ dw_b, rtol=1e-12, atol=1e-14)
    assert np.abs(dw_b).max() > 0.01  # the gyroscopic term is not negligible here


def test_fixed_points_move_as_the_derivative_of_their_positions():
    body = _body(orientation=(0.2, 0.5, -0.4))
    pose = jnp.array([0.3, -0.1, 0.2, 0.1, -0.2, 0.3])
    vel = jnp.array([0.5, -0.4, 0.1, 0.2, -0.3, 0.4])  # (v, ω)
    local = jnp.array([[3.0, -1.0, 2.0], [0.0, 0.5, -4.0]])
    rates = body.rate(0.0, jnp.concatenate([pose, vel]), jnp.zeros(6))[:6]
    _, dpos = jax.jvp(lambda p: body.point_position(p, local), (pose,), (rates,))
    np.testing.assert_allclose(dpos, body.point_velocity(pose, vel, local), rtol=1e-12)
    # the angles' rates map back to ω
    e = angular_velocity_map(body.orientation + pose[3:])
    np.testing.assert_allclose(e @ rates[3:], vel[3:], rtol=1e-12)


def test_pendulum_restoring_moment_and_net_weight():
    m, v = 2.0e3, 1.5
    body = _body(mass=m, volume=v, cg=(0.0, 0.0, -1.0))
    w = (m - 1025.0 * v) * 9.80665  # net weight [N], weight and buoyancy at the CG (MoorDyn)
    for phi in (0.0, 0.2, -0.5):
        load = np.asarray(body.mean_load(jnp.array([0.0, 0.0, 0.0, phi, 0.0, 0.0])))
        np.testing.assert_allclose(load, [0, 0, -w, -w * np.sin(phi), 0, 0], atol=1e-9 * w)
    np.testing.assert_allclose(np.asarray(body.hydrostatic)[3, 3], w, rtol=1e-12)


def test_drag_acts_on_velocity_relative_to_the_current_in_body_axes():
    from moorjax.model import UniformCurrent

    cda = np.array([2.0, 5.0, 7.0, 3.0, 4.0, 6.0])
    yaw = np.pi / 2  # body x along global y
    body = _body(orientation=(0.0, 0.0, yaw), cda=cda, current=UniformCurrent([0.0, 0.8, 0.0]))
    f = np.asarray(body.mean_load(jnp.zeros(6)))
    np.testing.assert_allclose(f[:3] + [0, 0, 2.0e3 * 9.80665], [0, 0.5 * 1025 * 2.0 * 0.64, 0], atol=1e-9)
    assert np.asarray(body.mean_load(jnp.zeros(6), loads=False))[1] == 0.0


def test_deck_free_body_values_and_end_node_inertia():
    deck = read_deck(FREE)
    (body,) = build_scene(deck).bodies
    assert isinstance(body, SubmergedBody) and body.label == "B1"
    np.testing.assert_allclose(body.orientation, np.radians([5.0, -8.0, 30.0]))
    np.testing.assert_allclose(body.cg, [0, 0, -1])
    np.testing.assert_allclose(body.inertia, [1e6, 1e6, 2e6])
    np.testing.assert_allclose(body.cda, [20, 20, 20, 40, 40, 40])
    np.testing.assert_allclose(body.ca, [1, 1, 1])
    assert float(body.mass) == 2.0e5 and float(body.volume) == 150.0
    np.testing.assert_allclose(body.cb, body.cg)
    # each point: half of a 95/20 m chain element (40 kg/m) and its added mass
    # ρ·A·(l/2)·Ca_n across the line (CaAx = 0): trace μl/2·3 + ρA(l/2)·Ca_n·2
    half = 95.0 / 20 / 2
    area = np.pi * 0.08**2 / 4
    trace = 40.0 * half * 3 + 1025.0 * area * half * 1.0 * 2
    np.testing.assert_allclose(np.trace(np.asarray(body.fixture_inertia), axis1=1, axis2=2), trace)
    m6 = np.asarray(body.mass_matrix(jnp.zeros(6)))
    np.testing.assert_allclose(m6, m6.T, atol=1e-6)
    # translational mass: body, its added mass ρ·V·Ca and the three end nodes
    assert np.trace(m6[:3, :3]) == pytest.approx(3 * 2.0e5 + 3 * 1025 * 150.0 + 3 * trace, rel=1e-12)


def test_body_without_inertia_is_refused():
    with pytest.raises(ValueError, match=r"body 'B': the 6×6 mass matrix .* is singular"):
        SubmergedBody(0.0, (0, 0, -5), inertia=0.0, volume=2.0, ca=1.0, label="B")


def _moordyn():
    return pytest.importorskip("moordyn")


@pytest.mark.slow
def test_buoy_statics_match_moordyn_settled_state():
    """~70 s (compiling the system statics)."""
    from moorjax.statics import solve_system_statics

    moordyn = _moordyn()
    s = moordyn.Create(str(BUOY))
    moordyn.Init(s, [], [])
    b = moordyn.GetBody(s, 1)
    poses, t = [], 0.0
    for _ in range(400):
        moordyn.Step(s, [], [], t, 1.0)
        t += 1.0
        if t > 200:
            poses.append(np.array(moordyn.GetBodyState(b)[0]))
    moordyn.Close(s)
    settled = np.mean(poses, axis=0)
    spread = np.ptp(poses, axis=0)  # MoorDyn's slowly decaying swing
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = build_scene(read_deck(BUOY))
    st = solve_system_statics(scene)
    (body,) = scene.bodies
    pos = np.asarray(body.origin + st.poses[0, :3])
    ang = np.asarray(body.orientation + st.poses[0, 3:])
    # the body rises 3.4 m and levels from (5°, −8°); MoorDyn swings ±4 mm, ±0.005 rad
    assert spread[2] < 0.01 and spread[3:5].max() < 0.012
    np.testing.assert_allclose(pos, settled[:3], atol=0.005)
    np.testing.assert_allclose(ang, settled[3:], atol=0.003)


@pytest.mark.slow
def test_buoy_dynamics_match_moordyn():
    """2 s of the release from the deck pose; ~60 s (compiling)."""
    from moorjax.dynamics import simulate
    from moorjax.model import LineState

    moordyn = _moordyn()
    s = moordyn.Create(str(BUOY))
    moordyn.Init_NoIC(s, [], [])
    nodes = []
    for i in range(moordyn.GetNumberLines(s)):
        ln = moordyn.GetLine(s, i + 1)
        nodes.append(np.array([moordyn.GetLineNodePos(ln, k) for k in range(moordyn.GetLineN(ln) + 1)]))
    b = moordyn.GetBody(s, 1)
    ts = np.arange(0.0, 2.0 + 1e-9, 0.1)
    hist = [np.array(moordyn.GetBodyState(b)[0])]
    for t in ts[:-1]:
        moordyn.Step(s, [], [], t, 0.1)
        hist.append(np.array(moordyn.GetBodyState(b)[0]))
    moordyn.Close(s)
    hist = np.array(hist)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = build_scene(read_deck(BUOY))
    (body,) = scene.bodies
    init = tuple(LineState(r=jnp.asarray(r[1:-1]), v=jnp.zeros((len(r) - 2, 3))) for r in nodes)
    res = simulate(scene, ts=ts, init=init + (body.rest_state(),))
    pose = np.asarray(res.body_pose)[:, 0]
    pos = pose[:, :3] + np.asarray(body.origin)
    ang = pose[:, 3:] + np.asarray(body.orientation)
    rise = np.ptp(hist[:, 2])
    tilt = np.ptp(hist[:, 3:5], axis=0).max()
    assert rise > 1.0 and tilt > 0.1  # it rises and levels
    assert np.abs(pos - hist[:, :3]).max() < 0.003 * rise, np.abs(pos - hist[:, :3]).max()
    assert np.abs(ang - hist[:, 3:]).max() < 0.02 * tilt, np.abs(ang - hist[:, 3:]).max()


def test_free_point_statics_feel_the_current_drag():
    """A free point's mean load (system statics) holds the current's drag at rest."""
    from moorjax.body import ConnectionPoint
    from moorjax.model import UniformCurrent

    u = np.array([0.6, -0.8, 0.0])
    point = ConnectionPoint(100.0, (0, 0, -10), cda=2.0, current=UniformCurrent(u))
    f = np.asarray(point.mean_load(jnp.zeros(6)))
    np.testing.assert_allclose(f[:2], 0.5 * 1025.0 * 2.0 * np.linalg.norm(u) * u[:2], rtol=1e-12)
    assert np.all(np.asarray(point.mean_load(jnp.zeros(6), loads=False))[:2] == 0.0)


ROTATING = DATA / "public" / "rotatingBody.txt"


def _lowered(text, dz=-10.0, segments=2):
    """MoorDyn's rotatingBody.txt moved ``dz`` [m] (it sits at z = +5 m, in air,
    where MoorDyn drops its lines' added mass, which moorjax does not model) with
    ``segments`` per line (moorjax needs a free node per line)."""
    out, section = [], None
    for row in text.splitlines():
        if row.startswith("---"):
            section = next((s for s in ("BODIES", "POINTS", "LINES") if s in row), None)
        else:
            tok = row.split()
            if tok and tok[0].isdigit():
                if section == "BODIES" or (section == "POINTS" and not tok[1].lower().startswith("body")):
                    tok[4] = repr(float(tok[4]) + dz)
                elif section == "LINES":
                    tok[5] = str(segments)
                row = "  ".join(tok)
        out.append(row)
    return "\n".join(out) + "\n"


@pytest.mark.slow
def test_rotating_body_driven_by_a_line_matches_moordyn(tmp_path):
    """MoorDyn's ``tests/Mooring/body_tests/rotatingBody.txt`` (no gravity; a body
    held at its centre by six taut springs, turned by line 7 whose coupled end
    point 9 swings y = 0.3 sin(2πt) m), lowered under water, 2 segments per line:
    2 s of yaw (±0.35 rad) against MoorDyn 2.7.2. ~2 min (compiling)."""
    from moorjax.dynamics import simulate
    from moorjax.io.build import read_deck_motion
    from moorjax.model import LineState

    moordyn = _moordyn()
    deck_path = tmp_path / "rotatingBody_lowered.txt"
    deck_path.write_text(_lowered(ROTATING.read_text()))
    w = 2 * np.pi

    def path(t):
        return [2.0, 0.3 * np.sin(w * t), -5.0], [0.0, 0.3 * w * np.cos(w * t), 0.0]

    s = moordyn.Create(str(deck_path))
    moordyn.Init_NoIC(s, *path(0.0))
    nodes = []
    for i in range(moordyn.GetNumberLines(s)):
        ln = moordyn.GetLine(s, i + 1)
        nodes.append(np.array([moordyn.GetLineNodePos(ln, k) for k in range(moordyn.GetLineN(ln) + 1)]))
    b = moordyn.GetBody(s, 1)
    dt, t, hist = 0.0005, 0.0, [np.array(moordyn.GetBodyState(b)[0])]
    for k in range(4000):
        moordyn.Step(s, *path(t), t, dt)
        t += dt
        if (k + 1) % 100 == 0:
            hist.append(np.array(moordyn.GetBodyState(b)[0]))
    moordyn.Close(s)
    hist = np.array(hist)
    ts = np.arange(len(hist)) * 0.05

    tm = np.arange(0.0, 2.2, 0.005)
    motion = tmp_path / "motion.csv"
    cols = [tm, 2 + 0 * tm, 0.3 * np.sin(w * tm), -5 + 0 * tm, 0 * tm, 0.3 * w * np.cos(w * tm), 0 * tm]
    np.savetxt(motion, np.column_stack(cols), delimiter=",", comments="", fmt="%.12g",
               header="t,P9_x,P9_y,P9_z,P9_vx,P9_vy,P9_vz")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        deck = read_deck(deck_path)
        scene = build_scene(deck, motion=read_deck_motion(motion, deck))
    (body,) = scene.bodies
    init = tuple(LineState(r=jnp.asarray(r[1:-1]), v=jnp.zeros((len(r) - 2, 3))) for r in nodes)
    res = simulate(scene, ts=ts, init=init + (body.rest_state(),))
    pose = np.asarray(res.body_pose)[:, 0]
    pos = pose[:, :3] + np.asarray(body.origin)
    ang = pose[:, 3:] + np.asarray(body.orientation)
    yaw = np.ptp(hist[:, 5])
    assert yaw > 0.5
    # measured: 0.0095 rad of yaw (1.4 %), 2.4 mm of a 37 mm sway of the centre
    assert np.abs(ang - hist[:, 3:]).max() < 0.025 * yaw
    assert np.abs(pos - hist[:, :3]).max() < 0.1 * np.ptp(hist[:, :3], axis=0).max()


def test_free_motion_conserves_energy():
    """No drag, no added mass, no lines: dE/dt = ∇E·ż = 0 for kinetic plus weight and
    buoyancy potential, at a tumbling state (checks the gyroscopic and centripetal
    terms, the CG/CB arms and the angles' rates together)."""
    fixtures = (np.array([[2.0, -1.0, 0.5], [-1.5, 0.3, 1.0]]), np.array([300.0, 150.0]),
                np.array([0.1, 0.0]), np.zeros((2, 3, 3)))
    body = _body(orientation=(0.3, -0.4, 0.8), cg=(0.2, -0.1, -0.7), cb=(0.0, 0.1, 0.3),
                 volume=1.2, fixtures=fixtures)
    z = jnp.array([0.5, -0.2, 0.3, 0.2, 0.1, -0.3, 0.4, -0.6, 0.2, 0.7, -0.5, 0.9])
    de = jnp.dot(jax.grad(body.energy)(z), body.rate(0.0, z, jnp.zeros(6)))
    scale = float(jnp.abs(jax.grad(body.energy)(z)).max())
    assert abs(float(de)) < 1e-10 * scale, float(de)
    # and it is not trivially zero: an external moment does work ω·τ
    tau = jnp.array([0.0, 0.0, 0.0, 10.0, 0.0, 0.0])
    de = jnp.dot(jax.grad(body.energy)(z), body.rate(0.0, z, tau))
    np.testing.assert_allclose(float(de), 10.0 * 0.7, rtol=1e-9)


def test_gradients_reach_the_body_parameters():
    """The acceleration is differentiable in the deck's coefficients (AD = central FD)."""
    z = jnp.zeros(12).at[6:].set(jnp.array([0.3, -0.1, 0.2, 0.1, 0.2, -0.1]))

    def heave_acc(volume):
        body = _body(volume=volume, cda=(3.0, 3.0, 3.0, 1.0, 1.0, 1.0), ca=(0.5, 0.5, 0.8),
                     cg=(0.0, 0.0, -0.5))
        return body.rate(0.0, z, jnp.zeros(6))[8]

    g = float(jax.grad(heave_acc)(1.5))
    h = 1e-5
    fd = (float(heave_acc(1.5 + h)) - float(heave_acc(1.5 - h))) / (2 * h)
    np.testing.assert_allclose(g, fd, rtol=1e-6)
    assert abs(g) > 1.0


def test_drag_sees_the_wave_velocity_at_the_reference_point():
    from moorjax.model import Environment
    from moorjax.model.waves import AiryWaves, IrregularWave

    waves = AiryWaves(IrregularWave([0.8], [1.5], [0.3]), 50.0)
    env = Environment(50.0, 1025.0, 9.80665, waves=waves)
    body = _body(cda=4.0, g=0.0)  # g = 0: drag alone
    z = body.rest_state()
    t = 1.7
    acc = np.asarray(body.rate(t, z, jnp.zeros(6), env))[6:9]
    _, u, _ = waves.kinematics(body.origin, t)
    drag = 0.5 * 1025.0 * 4.0 * np.linalg.norm(u) * np.asarray(u)
    assert np.linalg.norm(u) > 0.1
    np.testing.assert_allclose(acc * 2.0e3, drag, rtol=1e-10)
    assert np.all(np.asarray(body.rate(t, z, jnp.zeros(6)))[6:9] == 0.0)  # no env: still water


def test_an_unbalanced_body_is_described_by_its_loads():
    """The words of an unconverged body equilibrium (``body_free.dat``: a body
    453.6 kN heavier than the water it displaces, fully submerged, on chains
    from anchors on the bed, has none above the seabed): the force left, its
    vertical split into the body's own loads and its lines', a body sunk through
    the seabed, and a vertical balance nothing can meet."""
    from moorjax.statics.system import SUNK_MARGIN, imbalance_report, sunk_bodies

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = build_scene(read_deck(FREE))
    own = np.asarray(scene.bodies[0].mean_load(jnp.zeros(6), 0.0, scene.env))
    np.testing.assert_allclose(own[2], -(2.0e5 - 1025.0 * 150.0) * 9.80665, rtol=1e-12)
    depth, z0 = float(scene.env.depth), float(scene.bodies[0].origin[2])
    held = np.array([[1.0, -2.0, -40.0, 0.01, 0.02, 0.0]])
    sunk = held.copy()
    sunk[0, 2] = -depth - z0 - SUNK_MARGIN - 0.5
    assert not bool(sunk_bodies(scene, held)[0]) and bool(sunk_bodies(scene, sunk)[0])
    at_bed = held.copy()
    at_bed[0, 2] = -depth - z0 - 0.5 * SUNK_MARGIN  # below the bed, within the margin
    assert not bool(sunk_bodies(scene, at_bed)[0])

    lines = np.array([[0.0, 0.0, 5.8e4, -3.4e5, 0.0, 0.0]])  # the lines hold it up in part
    text = imbalance_report(scene, held, lines + own, lines)
    assert "body B1: force (" in text and f"{own[2]:.4g} N from its own loads" in text
    assert "5.8e+04 N from its lines" in text and "nothing holds" not in text
    down = np.array([[0.0, 0.0, -1.0e4, 0.0, 0.0, 0.0]])  # slack chains hanging from it
    text = imbalance_report(scene, sunk, down + own, down)
    assert "sank through the seabed" in text and "nothing holds it up" in text
    assert f"pull it down by {-own[2]:.4g} N and its lines by 1e+04 N" in text
    up = np.array([[0.0, 0.0, 1.0e4, 0.0, 0.0, 0.0]])  # a buoyant body (own loads upward)
    assert "nothing holds it down" in imbalance_report(scene, held, up - own, up)


@pytest.mark.slow
def test_a_body_with_no_equilibrium_stops_early_and_says_why():
    """``body_free.dat`` settles with a fairlead's line end pressed into the bed
    and 395 kN left: the Newton iteration then crept 7e-7 m per iteration (each
    trying 20 step halvings) for all 200 iterations, 4 minutes. Accepted steps
    that move nothing and lower nothing now stop it (25 iterations here)."""
    import re

    from moorjax.statics.system import STALLS, solve_system_statics

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = build_scene(read_deck(FREE))
    with pytest.raises(RuntimeError, match="from its own loads") as err:
        solve_system_statics(scene)
    its = int(re.search(r"after (\d+) Newton iterations", str(err.value)).group(1))
    assert STALLS < its < 40
    assert "body B1: force (0, 0, -3.95" in str(err.value)
