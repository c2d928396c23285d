"""Free points (``Free``/``Point``/``Connect``) from MoorDyn decks.

- a deck's free point becomes a :class:`~moorjax.body.ConnectionPoint` in
  ``Scene.bodies``; its lines end on it; its weight, buoyancy, CdA are the
  deck's, and its inertia holds the deck mass, Ca·ρ·V and its lines' end nodes
  (as MoorDyn's point does);
- statics of MoorPy's ``tests/case2.dat`` (a chain and a polyester rope joined
  by a free point) against MoorPy 1.3.0 (computed here: MoorPy is a test
  dependency);
- dynamics of MoorDyn's ``tests/Mooring/wavekin_3/test_dynamic_currents.txt``
  (a chain hanging from a fixed point to a free point, in MoorDyn's
  time-varying current ``current_profile_dynamic.txt``, ``Currents = 2``):
  3 s from MoorDyn 2.7.2's initial state against MoorDyn's history
  (``moordyn_ref.json``, made by ``tests/data/make_moordyn_reference.py``).
"""

from __future__ import annotations

import time

import json
import warnings
from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

from moorjax.body import ConnectionPoint
from moorjax.dynamics import simulate
from moorjax.io import build_scene, parse_deck, read_deck
from moorjax.io.errors import InputError, InputWarning
from moorjax.model import BodyEnd, LineState
from moorjax.statics import solve_system_statics

DATA = Path(__file__).parent / "data"
CASE2 = DATA / "moorpy_case2.dat"
DYN = DATA / "current_dynamic_free" / "test_dynamic_currents.txt"

DECK = """t
---------------------- LINE TYPES -----------------------------------
TypeName   Diam    Mass/m     EA     BA/-zeta    EI   Cd   Ca   CdAx  CaAx
(name)     (m)     (kg/m)     (N)    (N-s/-)     (-)  (-)  (-)  (-)   (-)
rope       0.1     20.0       1e8    -1.0        0    1.2  0.5  0.1   0.0
---------------------- POINTS ---------------------------------------
ID  Attachment  X     Y    Z      Mass  Volume  CdA  Ca
(#) (-)         (m)   (m)  (m)    (kg)  (m^3)   (m2) (-)
1   Fixed       0     0    -50    0     0       0    0
2   {word}      30    0    -30    {mass}  2.0   1.5  0.8
3   Fixed       60    0    -5     0     0       0    0
---------------------- LINES ----------------------------------------
ID  LineType  AttachA  AttachB  UnstrLen  NumSegs  LineOutputs
(#) (name)    (#)      (#)      (m)       (-)      (-)
1   rope      1        2        40        4        -
2   rope      2        3        40        8        -
---------------------- OPTIONS --------------------------------------
50        WtrDpth
----------------------- need this line ------------------------------
"""


@pytest.mark.parametrize("word", ["Free", "free", "Point", "Connect", "Con"])
def test_free_point_words_build_a_connection_point(word):
    deck = parse_deck(DECK.format(word=word, mass=500.0))
    assert deck.points[2].attachment == "free"
    scene = build_scene(deck)
    (point,) = scene.bodies
    assert isinstance(point, ConnectionPoint)
    assert scene.lines[0].end_b == BodyEnd(0, (0, 0, 0), (30.0, 0.0, -30.0))
    assert scene.lines[1].end_a.body == 0
    rho, g = 1025.0, 9.80665
    np.testing.assert_allclose(point.static_force[:3], [0, 0, (rho * 2.0 - 500.0) * g])
    area = np.pi * 0.1**2 / 4
    ends = 20.0 * (10.0 / 2 + 5.0 / 2) + rho * area * 0.5 * (10.0 / 2 + 5.0 / 2)
    np.testing.assert_allclose(float(point.added), 0.8 * rho * 2.0 + ends)
    assert float(point.cda) == 1.5


def test_free_point_without_inertia_is_refused():
    text = DECK.format(word="Free", mass=0.0).replace("2.0   1.5  0.8", "0.0   0.0  0.0")
    text = text.replace("1   rope      1        2 ", "1   rope      1        3 ").replace(
        "2   rope      2        3        40        8", "2   rope      1        3        40        8")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        deck = parse_deck(text)
    with pytest.raises(InputError, match=r"POINTS id 2: a free point with Mass = 0 kg.*no inertia"):
        build_scene(deck)


def test_free_line_end_without_mass_or_volume_is_warned_about():
    """A massless point on one line end (MoorDyn's ``tripod.txt`` has one: the top of
    its float) is named: its equilibrium is degenerate."""
    text = DECK.format(word="Free", mass=0.0).replace("2.0   1.5  0.8", "0.0   0.0  0.0")
    text = text.replace("2   rope      2        3        40        8", "2   rope      1        3        40        8")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        deck = parse_deck(text)
    with pytest.warns(InputWarning, match=r"POINTS id 2: a free point on one line end .* free line end"):
        build_scene(deck)
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputWarning)  # with a mass it is an ordinary point
        build_scene(parse_deck(DECK.format(word="Free", mass=500.0)))


@pytest.mark.slow
def test_moorpy_case2_free_point_statics_match_moorpy():
    """~80 s, nearly all of it compiling the system statics' line solves."""
    import moorpy as mp

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ms = mp.System(file=str(CASE2))
        ms.initialize()
        ms.solveEquilibrium(tol=1e-6, maxIter=1000)
        scene = build_scene(read_deck(CASE2))
    (free,) = [p for p in ms.pointList if p.type == 0]
    st = solve_system_statics(scene)
    pos = np.asarray(scene.bodies[0].origin + st.poses[0, :3])
    # 25 and 15 segments against MoorPy's exact catenaries: 1.8 cm of 226 m
    np.testing.assert_allclose(pos, free.r, atol=0.03)
    for line, s in zip(ms.lineList, st.lines):
        np.testing.assert_allclose(float(s.tension_b), line.TB, rtol=5e-5)
        np.testing.assert_allclose(float(s.tension_a), line.TA, rtol=1e-3)  # anchor end on the seabed


def test_moorpy_case2_reported_statics_is_the_catenary_system():
    """``method="auto"`` (what ``moorjax statics`` reports): both lines are exact
    catenaries, so the free point sits where MoorPy (same g = 9.80665 m/s² as
    MoorDyn) puts it to 1e-6 m and the tensions agree to 1e-6; ~5 s, against ~40 s for
    the FEM system above, whose point is 2 cm off at the deck's 25/15 segments."""
    import moorpy as mp

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ms = mp.System(file=str(CASE2), g=9.80665)
        ms.initialize()
        ms.solveEquilibrium(tol=1e-8, maxIter=5000)
        scene = build_scene(read_deck(CASE2))
    (free,) = [p for p in ms.pointList if p.type == 0]
    st = solve_system_statics(scene, method="auto")
    assert st.converged and st.methods == ("catenary", "catenary")
    pos = np.asarray(scene.bodies[0].origin + st.poses[0, :3])
    np.testing.assert_allclose(pos, free.r, atol=1e-6)
    for line, s in zip(ms.lineList, st.lines):
        np.testing.assert_allclose(float(s.tension_a), line.TA, rtol=1e-6)
        np.testing.assert_allclose(float(s.tension_b), line.TB, rtol=1e-6)
    with pytest.raises(ValueError, match="method must be"):
        solve_system_statics(scene, method="catenary")


def test_point_on_a_slack_weightless_line_settles_at_full_stretch():
    """MoorDyn's ``lifting.txt``: a 1 t point 100 m under a fixed point on a 100.5 m
    weightless line (it starts slack: no stiffness at all, a singular Newton matrix).
    The regularised step moves it along its weight until the line carries it:
    T = m·g, hanging at 100.5·(1 + mg/EA) m."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = build_scene(read_deck(DATA / "public" / "lifting.txt"))
    st = solve_system_statics(scene, method="fem")
    assert st.converged
    weight = 1e3 * 9.80665
    (line,) = st.lines
    np.testing.assert_allclose([float(line.tension_a), float(line.tension_b)], weight, rtol=1e-6)
    z = float(scene.bodies[0].origin[2] + st.poses[0, 2])
    np.testing.assert_allclose(z, -100.5 * (1 + weight / 1e9), atol=1e-6)


@pytest.mark.slow
def test_free_point_in_dynamic_current_matches_moordyn():
    ref = json.loads((DYN.parent / "moordyn_ref.json").read_text())
    scene = build_scene(read_deck(DYN))
    assert scene.env.current is not None and len(scene.bodies) == 1
    r0 = np.asarray(ref["initial"]["lines"][0]["positions"])
    point = scene.bodies[0]
    pose = jnp.concatenate([jnp.asarray(r0[-1]) - point.origin, jnp.zeros(3)])
    init = (LineState(r=jnp.asarray(r0[1:-1]), v=jnp.zeros((len(r0) - 2, 3))), point.rest_state(pose))
    hist = ref["history"]
    ts = np.asarray(hist["t"])[9::10]  # every 0.5 s
    t0 = time.perf_counter()
    res = simulate(scene, ts=ts, init=init)
    p = np.asarray(res.body_pose)[:, 0, :3] + np.asarray(point.origin)
    wall = time.perf_counter() - t0
    p_ref = np.asarray(hist["points"]["2"])[9::10]
    moved = np.linalg.norm(p_ref[-1] - p_ref[0])
    assert moved > 0.1  # the current drags the bottom point along x and y
    err = np.max(np.linalg.norm(p - p_ref, axis=1))
    print(f"free point in a dynamic current, {ts[-1]:g} s: point path error {err:.4f} m of {moved:.3f} m "
          f"travel ({err / moved:.2%}); moorjax {wall:.1f} s with compilation")
    assert err < 0.01 * moved, (err, moved)


def test_free_point_drag_acts_on_velocity_relative_to_the_current():
    from moorjax.model import UniformCurrent

    text = DECK.format(word="Free", mass=500.0)
    deck = parse_deck(text)
    point = build_scene(deck).bodies[0]
    assert point.current is None  # no current in the deck: no current term
    with_current = ConnectionPoint(500.0, (30.0, 0.0, -30.0), volume=2.0, cda=1.5,
                                   current=UniformCurrent([0.8, -0.3, 0.0]))
    z = with_current.rest_state()
    acc = np.asarray(with_current.rate(0.0, z, jnp.zeros(6)))[6:9]
    u = np.array([0.8, -0.3, 0.0])
    drag = 0.5 * 1025.0 * 1.5 * np.linalg.norm(u) * u
    np.testing.assert_allclose(acc[:2], drag[:2] / 500.0, rtol=1e-12)
    # moving with the water: no drag
    z = z.at[6:9].set(jnp.asarray(u))
    acc = np.asarray(with_current.rate(0.0, z, jnp.zeros(6)))[6:9]
    np.testing.assert_allclose(acc[:2], 0.0, atol=1e-12)
