"""MoorDyn decks with a BODIES section: reading, the body frame, building scenes.

- the body frame is MoorDyn-C v2's (R = Rx(roll)·Ry(pitch)·Rz(yaw), checked
  against an independent intrinsic-rotation construction and, when installed,
  against MoorDyn 2.7.2 itself);
- a ``fixed`` body gives the same statics as the deck written with plain fixed
  points at the transformed positions (``tests/data/body_fixed*.dat``);
- a ``coupled`` body holds its deck pose in statics, and ``moorjax simulate
  --motion`` with its 6-DOF pose columns gives the same run as the deck written
  with coupled points driven along the rigid-body paths;
- a ``free`` body builds a :class:`~moorjax.body.SubmergedBody`;
- coupled-pinned bodies and points on missing bodies are refused
  with messages naming the item.

The CLI statics share one compilation, the two simulations another (3 lines,
6 segments, 1 s in fixed 0.01 s steps).
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import json
import math
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from moorjax.cli import main
from moorjax.io import build_scene, read_deck, read_deck_motion, read_motion
from moorjax.io.deck import DeckBody, parse_deck
from moorjax.io.errors import InputError, InputWarning
from moorjax.io.frames import body_point_positions, body_point_velocities, moordyn_rotation
from moorjax.model import FixedEnd, TabulatedPath

DATA = Path(__file__).parent / "data"
FIXED = DATA / "body_fixed.dat"
FIXED_POINTS = DATA / "body_fixed_points.dat"
COUPLED = DATA / "body_coupled.dat"
FREE = DATA / "body_free.dat"
MISSING = DATA / "body_missing.dat"

BODY_ROW = 12  # line of the BODIES row in the body_*.dat decks
POSE0 = np.array([2.0, -1.0, -4.0, *np.radians([5.0, -8.0, 30.0])])  # body 1 [m, rad]
LOCAL = {4: (6.0, 0.0, -3.0), 5: (-3.0, 5.196, -3.0), 6: (-3.0, -5.196, -3.0)}  # body axes [m]


# ----------------------------------------------------------------------------
# an independent body frame: intrinsic rotations about the turned axes
# ----------------------------------------------------------------------------


def _axis_angle(axis, angle):
    """Rodrigues' rotation by ``angle`` [rad] about the unit vector ``axis``."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def _intrinsic_xyz(roll, pitch, yaw):
    """Roll about x, then pitch about the turned y, then yaw about the twice-turned z."""
    r = _axis_angle([1, 0, 0], roll)
    r = _axis_angle(r @ [0, 1, 0], pitch) @ r
    return _axis_angle(r @ [0, 0, 1], yaw) @ r


def _point(pose, local):
    return np.asarray(pose[:3]) + _intrinsic_xyz(*pose[3:]) @ np.asarray(local)


def test_rotation_is_intrinsic_xyz_and_right_handed():
    rng = np.random.default_rng(1)
    for angles in rng.uniform(-math.pi, math.pi, size=(20, 3)):
        np.testing.assert_allclose(moordyn_rotation(angles), _intrinsic_xyz(*angles), atol=1e-14)
    q = math.pi / 2
    # MoorDyn's NWU description: roll lowers starboard (-y), pitch lowers the bow (+x),
    # yaw turns the bow to port (+y)
    np.testing.assert_allclose(moordyn_rotation([q, 0, 0]) @ [0, -1, 0], [0, 0, -1], atol=1e-15)
    np.testing.assert_allclose(moordyn_rotation([0, q, 0]) @ [1, 0, 0], [0, 0, -1], atol=1e-15)
    np.testing.assert_allclose(moordyn_rotation([0, 0, q]) @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    # vectorised over leading axes
    stack = rng.uniform(-1, 1, size=(4, 5, 3))
    assert moordyn_rotation(stack).shape == (4, 5, 3, 3)


def test_point_velocity_is_the_derivative_of_position():
    rng = np.random.default_rng(2)
    pose, rate, local = rng.normal(size=6), rng.normal(size=6), rng.normal(size=3)
    h = 1e-6
    fd = (body_point_positions(pose + h * rate, local) - body_point_positions(pose - h * rate, local)) / (2 * h)
    np.testing.assert_allclose(body_point_velocities(pose, rate, local), fd, atol=1e-8)


def test_rotation_matches_moordyn(tmp_path):
    """Body points as MoorDyn 2.7.2 places them: a fixed body from the deck's degrees
    and a coupled body from the coupling call's radians."""
    if importlib.util.find_spec("moordyn") is None:  # not imported here (see below)
        pytest.skip("moordyn is not installed")
    text = FIXED.read_text().splitlines()
    body2 = "2   coupled   0.0  0.0  -10.0  0 0 0  0 0 0 0 0 0"
    text[BODY_ROW - 1 : BODY_ROW] = [text[BODY_ROW - 1], body2]
    i = text.index("6  Body1  -3  -5.196  -3  0 0 0 0")
    text[i + 1 : i + 1] = ["7  Body2  1.0  2.0  3.0  0 0 0 0", "8  Fixed  0.0  0.0  -50.0  0 0 0 0"]
    j = text.index("3  chain  3  6  95.0  20  -")
    text[j + 1 : j + 1] = ["4  chain  8  7  45.0  5  -"]
    k = text.index("0          writeLog   no log file")
    text[k + 1 : k + 1] = ["0.0  TmaxIC", "1  disableOutput", "1  disableOutTime", "0.001  dtM"]
    deck_path = tmp_path / "rot.dat"
    deck_path.write_text("\n".join(text) + "\n")

    deck = read_deck(deck_path)  # moorjax reads MoorDyn's test deck too
    pose2 = np.array([1.0, 2.0, -10.0, 0.3, -0.2, 0.7])
    # MoorDyn's C library runs in a child process: loaded into the test process it
    # was followed by a segfault in a later XLA compilation (CI, full suite)
    code = f"""
import contextlib, io, json, moordyn
with contextlib.redirect_stdout(io.StringIO()):
    s = moordyn.Create({str(deck_path)!r})
    moordyn.Init(s, [0.0, 0.0, -10.0, 0.0, 0.0, 0.0], [0.0] * 6)
    moordyn.Step(s, {list(map(float, pose2))!r}, [0.0] * 6, 0.0, 0.001)
    out = {{i: list(moordyn.GetPointPos(moordyn.GetPoint(s, i))) for i in (4, 5, 6, 7)}}
    moordyn.Close(s)
print(json.dumps(out))
"""
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    got = {int(k): np.array(v) for k, v in json.loads(run.stdout.strip().splitlines()[-1]).items()}
    for pid in (4, 5, 6):
        np.testing.assert_allclose(got[pid], deck.point_position(pid), atol=1e-9)
    np.testing.assert_allclose(got[7], body_point_positions(pose2, [1.0, 2.0, 3.0]), atol=1e-9)


# ----------------------------------------------------------------------------
# reading
# ----------------------------------------------------------------------------


def test_read_fixed_body_deck():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a clean deck emits no warning
        deck = read_deck(FIXED)
    assert deck.bodies == {
        1: DeckBody(1, "fixed", (2.0, -1.0, -4.0), (5.0, -8.0, 30.0), 0.0, (0.0, 0.0, 0.0),
                    (0.0, 0.0, 0.0), 0.0, (0.0,) * 6, (0.0,) * 3, BODY_ROW)
    }  # fmt: skip
    np.testing.assert_allclose(deck.bodies[1].pose(), POSE0, rtol=1e-15)
    for pid, local in LOCAL.items():
        p = deck.points[pid]
        assert (p.attachment, p.body, p.position) == ("body", 1, local)
        np.testing.assert_allclose(deck.point_position(pid), _point(POSE0, local), atol=1e-12)
    assert deck.points[1].body is None and deck.point_position(1) == (69.282, 40.0, -50.0)


def test_equivalent_deck_holds_the_transformed_points():
    """body_fixed_points.dat's points 4-6 are body_fixed.dat's, placed by the
    independent intrinsic rotation (to the 12 decimals written)."""
    plain = read_deck(FIXED_POINTS)
    assert plain.bodies == {}
    for pid, local in LOCAL.items():
        np.testing.assert_allclose(plain.points[pid].position, _point(POSE0, local), atol=1e-11)


def test_free_body_row_every_value():
    deck = read_deck(FREE)
    assert deck.bodies[1] == DeckBody(
        1, "free", (2.0, -1.0, -4.0), (5.0, -8.0, 30.0), 2.0e5, (0.0, 0.0, -1.0), (1e6, 1e6, 2e6),
        150.0, (20.0, 20.0, 20.0, 40.0, 40.0, 40.0), (1.0, 1.0, 1.0), BODY_ROW,
    )


def _with_body_row(row: str, kind_header: str = "BODIES") -> str:
    lines = FIXED.read_text().splitlines()
    lines[BODY_ROW - 1] = row
    lines[BODY_ROW - 4] = f"---------------------------- {kind_header} ------------------------"
    return "\n".join(lines) + "\n"


BODY = "1  {kind}  2.0  -1.0  -4.0  5.0  -8.0  30.0  {mass}  {cg}  {i}  {vol}  {cda}  {ca}"
DEFAULTS = dict(kind="fixed", mass="0", cg="0", i="0", vol="0", cda="0", ca="0")


@pytest.mark.parametrize(
    "fields, attr, expected",
    [
        (dict(cg="-2.5"), "cg", (0.0, 0.0, -2.5)),  # one value is z
        (dict(cg="1|2|3"), "cg", (1.0, 2.0, 3.0)),
        (dict(i="7"), "inertia", (7.0, 7.0, 7.0)),
        (dict(i="1|2|3"), "inertia", (1.0, 2.0, 3.0)),
        (dict(cda="5"), "cda", (5.0,) * 6),
        (dict(cda="1|2"), "cda", (1.0, 1.0, 1.0, 2.0, 2.0, 2.0)),  # translation|rotation
        (dict(cda="1|2|3"), "cda", (1.0, 2.0, 3.0, 1.0, 2.0, 3.0)),  # x|y|z for both
        (dict(cda="1|2|3|4|5|6"), "cda", (1.0, 2.0, 3.0, 4.0, 5.0, 6.0)),
        (dict(ca="0.5"), "ca", (0.5, 0.5, 0.5)),
        (dict(ca="0.1|0.2|0.3"), "ca", (0.1, 0.2, 0.3)),
        (dict(kind="Vessel"), "attachment", "coupled"),
        (dict(kind="CPLD"), "attachment", "coupled"),
        (dict(kind="ANCHOR"), "attachment", "fixed"),
        (dict(kind="Free"), "attachment", "free"),
        (dict(kind="coupledPinned"), "attachment", "coupled_pinned"),
        (dict(kind="vespin"), "attachment", "coupled_pinned"),
    ],
)
def test_body_field_forms(fields, attr, expected):
    deck = parse_deck(_with_body_row(BODY.format(**{**DEFAULTS, **fields})))
    assert getattr(deck.bodies[1], attr) == expected


@pytest.mark.parametrize("header", ["BODIES", "Bodies", "BODY LIST", "body properties"])
def test_section_header_spellings(header):
    deck = parse_deck(_with_body_row(BODY.format(**DEFAULTS), header))
    assert deck.bodies[1].attachment == "fixed"


ROW = BODY_ROW
BODY_ERRORS = {
    "too few columns": ("1  fixed  2.0  -1.0  -4.0  5.0  -8.0  30.0  0  0  0  0  0", ROW,
                        ["BODIES row", "13 columns", "expected 14", "missing Ca"]),
    "unknown kind": (BODY.format(**{**DEFAULTS, "kind": "floating"}), ROW,
                     ["BODIES id 1", "Attachment = 'floating'", "Fixed, Coupled (Vessel), Free"]),
    "id not integer": ("x " + BODY.format(**DEFAULTS)[1:], ROW, ["BODIES row", "ID = 'x'", "integer"]),
    "id out of sequence": ("2" + BODY.format(**DEFAULTS)[1:], ROW, ["BODIES", "id 2", "expected 1"]),
    "x0 not a number": (BODY.format(**DEFAULTS).replace("2.0", "two", 1), ROW, ["X0 = 'two'", "not a number", "m"]),
    "r0 nan": (BODY.format(**DEFAULTS).replace("5.0", "nan", 1), ROW, ["r0 = nan deg", "finite"]),
    "negative mass": (BODY.format(**{**DEFAULTS, "mass": "-1"}), ROW, ["Mass = -1 kg", ">= 0"]),
    "negative volume": (BODY.format(**{**DEFAULTS, "vol": "-3"}), ROW, ["Volume = -3 m^3", ">= 0"]),
    "cg two values": (BODY.format(**{**DEFAULTS, "cg": "1|2"}), ROW,
                      ["CG = '1|2' has 2 value(s)", "expected 1 or 3", "in m"]),
    "cg bad part": (BODY.format(**{**DEFAULTS, "cg": "1|x|2"}), ROW, ["CG = '1|x|2'", "'x' is not a number"]),
    "inertia negative part": (BODY.format(**{**DEFAULTS, "i": "1|-2|3"}), ROW,
                              ["I = '1|-2|3'", "-2 kg-m^2", ">= 0"]),
    "inertia inf": (BODY.format(**{**DEFAULTS, "i": "inf"}), ROW, ["I = 'inf'", "finite"]),
    "cda four values": (BODY.format(**{**DEFAULTS, "cda": "1|2|3|4"}), ROW,
                        ["CdA = '1|2|3|4' has 4 value(s)", "expected 1 or 2 or 3 or 6"]),
    "ca two values": (BODY.format(**{**DEFAULTS, "ca": "1|2"}), ROW, ["Ca = '1|2'", "expected 1 or 3"]),
    "ca negative": (BODY.format(**{**DEFAULTS, "ca": "-1"}), ROW, ["Ca = -1 [-]", ">= 0"]),
}  # fmt: skip


@pytest.mark.parametrize("case", list(BODY_ERRORS), ids=list(BODY_ERRORS))
def test_body_row_errors(case):
    row, lineno, fragments = BODY_ERRORS[case]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputWarning)
        with pytest.raises(InputError) as info:
            parse_deck(_with_body_row(row), "deck.dat")
    msg = str(info.value)
    assert msg.startswith(f"deck.dat:{lineno}: "), msg
    for f in fragments:
        assert f in msg, f"{f!r} not in {msg!r}"


def test_point_on_missing_body():
    with pytest.raises(InputError) as info:
        read_deck(MISSING)
    assert str(info.value) == (
        f"{MISSING}:21: POINTS id 6: Attachment = 'Body2': no body with id 2 (known body ids: 1)"
    )


def test_body_point_below_seabed_is_checked_in_global_axes():
    # body-frame z = -3 m, but the body sits 49 m deep: the point is 2 m under the seabed
    text = FIXED.read_text().replace("2.0  -1.0 -4.0  5.0  -8.0  30.0", "2.0  -1.0 -49.0  0.0  0.0  0.0")
    with pytest.raises(InputError, match=r"POINTS id 4: Z = -52.0 m \(global z of a point of body 1"):
        parse_deck(text, "deck.dat")


def test_depth_default_uses_global_body_points():
    lines = [ln for ln in FIXED.read_text().splitlines() if "WtrDpth" not in ln]
    lines = [ln.replace("-50.0  0 0 0 0", "-20.0  0 0 0 0") for ln in lines]  # anchors at 20 m
    text = "\n".join(lines).replace("2.0  -1.0 -4.0  5.0  -8.0  30.0", "0.0  0.0 -30.0  0.0  0.0  0.0")
    from moorjax.io.deck import options_with_defaults

    with pytest.warns(InputWarning, match="WtrDpth not given"):
        deck = parse_deck(text)
    assert options_with_defaults(deck)["WtrDpth"] == 33.0  # the body points, not their local z


def test_unattached_body_warns():
    lines = FIXED.read_text().splitlines()
    lines[BODY_ROW:BODY_ROW] = ["2   coupled   0 0 0 0 0 0 0 0 0 0 0 0"]
    with pytest.warns(InputWarning, match="BODIES id 2: no point is attached"):
        deck = parse_deck("\n".join(lines))
    assert deck.bodies[2].attachment == "coupled"


# ----------------------------------------------------------------------------
# building scenes: what is supported and what is refused
# ----------------------------------------------------------------------------


def test_build_fixed_and_coupled_bodies_place_fixed_ends():
    for path in (FIXED, COUPLED):
        scene = build_scene(read_deck(path), segments=4)
        for line, pid in zip(scene.lines, (4, 5, 6)):
            assert isinstance(line.end_b, FixedEnd)
            np.testing.assert_allclose(line.end_b.point, _point(POSE0, LOCAL[pid]), atol=1e-12)
        assert scene.bodies == ()


def test_free_body_builds_a_submerged_body():
    """Free bodies are built (their physics: ``tests/test_deck_free_body.py``)."""
    from moorjax.body import SubmergedBody
    from moorjax.model import BodyEnd

    scene = build_scene(read_deck(FREE), segments=4)
    (body,) = scene.bodies
    assert isinstance(body, SubmergedBody)
    for line, pid in zip(scene.lines, (4, 5, 6)):
        assert isinstance(line.end_b, BodyEnd) and line.end_b.body == 0
        np.testing.assert_allclose(body.point_position(np.zeros(6), line.end_b.point),
                                   _point(POSE0, LOCAL[pid]), atol=1e-12)


def test_coupled_pinned_body_cli_exit_code(tmp_path):
    path = tmp_path / "d.dat"
    path.write_text(FIXED.read_text().replace("1   fixed     2.0", "1   CoupledPinned 2.0"))
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = main(["statics", str(path), "--json"])
    assert rc == 2
    assert "BODIES id 1: Attachment = coupledpinned" in err.getvalue()


def test_coupled_pinned_body_is_refused():
    deck = parse_deck(FIXED.read_text().replace("1   fixed     2.0", "1   CoupledPinned 2.0"), "d.dat")
    with pytest.raises(InputError, match=r"d\.dat:12: BODIES id 1: Attachment = coupledpinned: .* not supported"):
        build_scene(deck)


def test_motion_without_body_columns_warns_and_holds(tmp_path):
    motion_path = tmp_path / "m.csv"
    motion_path.write_text("t\n0\n1\n")
    motion = read_motion(motion_path, [])  # read without the coupled body
    with pytest.warns(InputWarning, match="BODIES id 1: the motion .* was read without body 1"):
        scene = build_scene(read_deck(COUPLED), segments=4, motion=motion)
    assert all(isinstance(ln.end_b, FixedEnd) for ln in scene.lines)


# ----------------------------------------------------------------------------
# motion files with body columns
# ----------------------------------------------------------------------------

T = np.round(np.arange(0.0, 1.0 + 1e-9, 0.01), 10)
AMP = np.array([0.5, 0.3, 0.1, math.radians(1.0), math.radians(2.0), math.radians(3.0)])  # [m, rad]
PERIOD = 2.0  # [s]


def body_pose(t):
    """(k, 6) pose of body 1, leaving its deck pose from rest, and its rates."""
    w = 2 * math.pi / PERIOD
    s = np.sin(w * np.asarray(t))[:, None]
    c = np.cos(w * np.asarray(t))[:, None]
    return POSE0 + AMP * (1 - c), AMP * w * s


def write_body_motion(path, rates=True):
    pose, rate = body_pose(T)
    names = ["t"] + [f"B1_{c}" for c in ("x", "y", "z", "roll", "pitch", "yaw")]
    cols = [T, *pose.T]
    if rates:
        names += [f"B1_v{c}" for c in ("x", "y", "z", "roll", "pitch", "yaw")]
        cols += list(rate.T)
    np.savetxt(path, np.column_stack(cols), delimiter=",", fmt="%.17g", comments="", header=",".join(names))
    return path


def write_point_motion(path):
    """Points 4-6 along the same rigid motion, by the independent rotation."""
    pose, rate = body_pose(T)
    h = 1e-6
    names, cols = ["t"], [T]
    for pid, local in LOCAL.items():
        r = np.array([_point(p, local) for p in pose])
        v = np.array([(_point(p + h * d, local) - _point(p - h * d, local)) / (2 * h) for p, d in zip(pose, rate)])
        names += [f"P{pid}_{c}" for c in ("x", "y", "z", "vx", "vy", "vz")]
        cols += [*r.T, *v.T]
    np.savetxt(path, np.column_stack(cols), delimiter=",", fmt="%.17g", comments="", header=",".join(names))
    return path


def test_read_body_motion(tmp_path):
    motion = read_deck_motion(write_body_motion(tmp_path / "m.csv"), read_deck(COUPLED))
    pose, rate = body_pose(T)
    np.testing.assert_allclose(motion.body_poses[1], pose, rtol=1e-15)
    np.testing.assert_allclose(motion.body_rates[1], rate, rtol=1e-15)
    assert motion.positions == {}
    without = read_deck_motion(write_body_motion(tmp_path / "n.csv", rates=False), read_deck(COUPLED))
    assert without.body_rates == {1: None}


def test_body_motion_column_errors(tmp_path):
    p = tmp_path / "m.csv"
    p.write_text("t,B1_x,B1_y,B1_z,B1_roll\n0,0,0,0,0\n1,0,0,0,0\n")
    with pytest.raises(InputError, match=r"m\.csv:1: missing column\(s\) B1_pitch, B1_yaw for body id\(s\) 1 "
                                         r"\(x, y, z \[m\] of the reference point; roll, pitch, yaw \[rad\]\)"):
        read_motion(p, [], [1])
    p.write_text("t,B1_x,B1_y,B1_z,B1_roll,B1_pitch,B1_yaw,B1_vx\n0,0,0,0,0,0,0,0\n1,0,0,0,0,0,0,0\n")
    with pytest.raises(InputError, match=r"body 1 has rate column\(s\) B1_vx but not B1_vy, .*B1_vyaw; give all six"):
        read_motion(p, [], [1])


def test_coupled_body_points_follow_the_rigid_motion(tmp_path):
    motion = read_deck_motion(write_body_motion(tmp_path / "m.csv"), read_deck(COUPLED))
    scene = build_scene(read_deck(COUPLED), segments=4, motion=motion)
    pose, rate = body_pose(T)
    for line, pid in zip(scene.lines, (4, 5, 6)):
        end = line.end_b
        assert isinstance(end, TabulatedPath)
        expected = np.array([_point(p, LOCAL[pid]) for p in pose])
        np.testing.assert_allclose(np.asarray(end.r), expected, atol=1e-12)
        h = 1e-6
        fd = np.array([(_point(p + h * d, LOCAL[pid]) - _point(p - h * d, LOCAL[pid])) / (2 * h)
                       for p, d in zip(pose, rate)])
        np.testing.assert_allclose(np.asarray(end.v), fd, atol=1e-8)


# ----------------------------------------------------------------------------
# end to end through the CLI
# ----------------------------------------------------------------------------


def _statics(path):
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = main(["statics", str(path), "--segments", "10", "--json"])
    assert rc == 0
    return json.loads(out.getvalue())


@pytest.mark.slow
def test_statics_fixed_and_coupled_body_equal_plain_points():
    plain = _statics(FIXED_POINTS)
    for path in (FIXED, COUPLED):
        rows = _statics(path)
        assert len(rows) == len(plain) == 3
        for got, want in zip(rows, plain):
            assert got["id"] == want["id"]
            for key in ("tension_a", "tension_b", "grounded_length"):
                assert got[key] == pytest.approx(want[key], rel=1e-8, abs=1e-9), (path.name, key)
            np.testing.assert_allclose(got["force_b"], want["force_b"], rtol=1e-8, atol=1e-6)
            assert want["tension_b"] > want["tension_a"] > 0  # a hanging, loaded line


def _simulate(deck, motion, out):
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = main(["simulate", str(deck), "--motion", str(motion), "--duration", "1.0",
                   "--segments", "6", "--dt", "0.01", "--out", str(out)])
    assert rc == 0, err.getvalue()
    with open(out) as f:
        header = f.readline().strip().split(",")
    return header, np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)


@pytest.mark.slow
def test_simulate_coupled_body_equals_coupled_points(tmp_path):
    """``simulate --motion`` with B1_x..B1_yaw (and rates) runs the same as the deck
    with coupled points 4-6 driven along the independently computed rigid paths;
    the B1_F*/B1_M* columns are the lines' force and moment about the body's
    reference point. Fixed steps, so that both runs take the same steps (adaptive
    ones agree only to the integration tolerance)."""
    points_deck = tmp_path / "points.dat"
    text = FIXED_POINTS.read_text().splitlines()
    text = [ln.replace("  Fixed  ", "  Coupled  ") if ln[:1] in "456" and "  Fixed  " in ln else ln for ln in text]
    points_deck.write_text("\n".join(text) + "\n")

    hb, body = _simulate(COUPLED, write_body_motion(tmp_path / "mb.csv"), tmp_path / "b.csv")
    hp, pts = _simulate(points_deck, write_point_motion(tmp_path / "mp.csv"), tmp_path / "p.csv")

    tension = [f"L{i}_tension_{e}" for i in (1, 2, 3) for e in ("a", "b")]
    assert hb == ["t", *tension, *[f"B1_{c}" for c in ("Fx", "Fy", "Fz", "Mx", "My", "Mz")]]
    assert hp == ["t", *tension, *[f"P{p}_F{c}" for p in (4, 5, 6) for c in "xyz"]]
    np.testing.assert_allclose(body[:, 0], pts[:, 0])
    scale = np.abs(pts[:, 1:7]).max()
    np.testing.assert_allclose(body[:, 1:7], pts[:, 1:7], rtol=0, atol=1e-7 * scale)
    assert np.ptp(pts[:, 2]) > 1e-3 * scale  # the motion does change the tension

    forces = {p: pts[:, 7 + 3 * i: 10 + 3 * i] for i, p in enumerate((4, 5, 6))}
    np.testing.assert_allclose(body[:, 7:10], sum(forces.values()), rtol=0, atol=1e-7 * scale)
    pose, _ = body_pose(body[:, 0])
    moment = sum(np.cross(np.array([_intrinsic_xyz(*p[3:]) @ LOCAL[pid] for p in pose]), f)
                 for pid, f in forces.items())
    np.testing.assert_allclose(body[:, 10:13], moment, rtol=0, atol=1e-7 * scale)
