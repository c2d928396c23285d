"""MoorDyn's 4-D current grid (``Currents = 5``, ``current_profile_4d.txt``).

- the file is read as MoorDyn v2 documents it (``docs/waterkinematics.rst``,
  "Currents = 5 (4D Current Grid)"): grid sizes, the x, y, z, t values, then
  one ``x y z t ux uy uz`` row per grid point, matched to the grid by value;
  missing, repeated and off-grid rows are named by file and line;
- :class:`~moorjax.model.GridCurrent` is quadrilinear and held at the grid's
  edges: on MoorDyn's public file (``tests/data/public/wavekin_4``, made by
  MoorDyn's ``make_4d_currents.py`` with ux = 0.1·x + 0.1·t, uy = uz = 0)
  it reproduces that linear field exactly inside the grid;
- the same field is what MoorDyn 2 returns (``GetWavesKin``, run here) at
  points and times inside the grid;
- the drag of a free point and of a line acts on the velocity relative to the
  current at the node's own x (lines side by side feel different currents);
- dynamics of MoorDyn's ``tests/Mooring/wavekin_4/hanging_lines.txt`` (ten
  10 m chains hanging from fixed points at x = -50 … 40 m to massless free
  points) with the chain's normal drag coefficient set to 1 (the deck has
  Cd = 0, so its current would load nothing): 3 s from the deck's layout
  against MoorDyn 2, the top tension of every line and the free points' paths.
"""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from moorjax.body import ConnectionPoint
from moorjax.io import build_scene, read_deck
from moorjax.io.currents import read_current_grid_4d
from moorjax.io.errors import InputError
from moorjax.model import GridCurrent, LineState

PUBLIC = Path(__file__).parent / "data" / "public" / "wavekin_4"
GRID = PUBLIC / "current_profile_4d.txt"
DECK = PUBLIC / "hanging_lines.txt"


def _generator(p, t):
    """MoorDyn's make_4d_currents.py: ux = 0.1 x + 0.1 t (x clamped to the grid)."""
    p = np.atleast_2d(p)
    u = np.zeros_like(p)
    u[:, 0] = 0.1 * np.clip(p[:, 0], -50.0, 50.0) + 0.1 * np.clip(t, 0.0, 15.0)
    return u


# ----------------------------------------------------------------------------
# file
# ----------------------------------------------------------------------------


def test_public_grid_file_is_read_whole():
    cur = read_current_grid_4d(GRID)
    assert cur.mode == 5
    np.testing.assert_array_equal(cur.x, np.linspace(-50, 50, 11))
    np.testing.assert_array_equal(cur.y, [-2.0, 2.0])
    np.testing.assert_array_equal(cur.z, np.linspace(-30, 5, 36))
    np.testing.assert_array_equal(cur.t, [0.0, 15.0])
    assert cur.velocity.shape == (11, 2, 36, 2, 3)
    # every grid point, the first row (line 6) included, holds the generator's value
    xx, tt = np.meshgrid(cur.x, cur.t, indexing="ij")
    want = 0.1 * xx + 0.1 * tt
    np.testing.assert_allclose(cur.velocity[..., 0], np.broadcast_to(want[:, None, None, :], (11, 2, 36, 2)),
                               atol=1e-12)
    np.testing.assert_array_equal(cur.velocity[..., 1:], 0.0)


_SMALL = "2 1 2 2\n-1 1\n0\n-3 0\n0 15\n"
_ROWS = [f"{x} 0 {z} {t} {x * 0.5 + t} {z} 0" for x in (-1, 1) for z in (-3, 0) for t in (0, 15)]


def test_rows_in_any_order_and_spelling_are_matched_by_value(tmp_path):
    f = tmp_path / "current_profile_4d.txt"
    rows = [r.replace("-3 ", "-3.000 ") for r in reversed(_ROWS)]
    f.write_text(_SMALL + "\n".join(rows) + "\n\n")
    cur = read_current_grid_4d(f)
    np.testing.assert_array_equal(cur.velocity[1, 0, 0, 1], [1 * 0.5 + 15, -3, 0])
    np.testing.assert_array_equal(cur.velocity[0, 0, 1, 0], [-0.5, 0, 0])


@pytest.mark.parametrize("edit, msg", [
    (lambda rows: rows[:-1], r"1 of the 8 grid points have no row, the first \(x, y, z, t\) = \(1.0, 0.0, 0.0, "
                             r"15.0\)"),
    (lambda rows: rows + [rows[2]], r":14: grid point .* is given again \(first on line 8\)"),
    (lambda rows: [rows[0].replace("-1 0", "-2 0", 1)] + rows[1:], r":6: x = -2.0 m is not one of the grid's x"),
    (lambda rows: [rows[0] + " 9"] + rows[1:], r":6: 4-D current row has 8 numbers; expected 7"),
])
def test_grid_file_errors_name_the_line_and_the_fix(tmp_path, edit, msg):
    f = tmp_path / "current_profile_4d.txt"
    f.write_text(_SMALL + "\n".join(edit(list(_ROWS))) + "\n")
    with pytest.raises(InputError, match=msg):
        read_current_grid_4d(f)


def test_grid_header_errors(tmp_path):
    f = tmp_path / "current_profile_4d.txt"
    f.write_text("2 1 2 2\n-1 1\n0\n-3 0 1\n0 15\n" + "\n".join(_ROWS) + "\n")
    with pytest.raises(InputError, match=r":4: grid z row has 3 values; line 1 says nz = 2"):
        read_current_grid_4d(f)
    f.write_text("2 1 2 2\n1 -1\n0\n-3 0\n0 15\n" + "\n".join(_ROWS) + "\n")
    with pytest.raises(InputError, match=r":2: x = -1.0 m is not greater than the previous 1.0 m"):
        read_current_grid_4d(f)


def test_deck_with_currents_5_builds_the_grid_current():
    scene = build_scene(read_deck(DECK))
    assert isinstance(scene.env.current, GridCurrent)
    assert len(scene.bodies) == 10  # the massless free points (CdA = 0: no current term on them)
    assert all(b.current is None for b in scene.bodies)


# ----------------------------------------------------------------------------
# field
# ----------------------------------------------------------------------------


def test_grid_current_is_the_linear_field_and_held_outside():
    c = read_current_grid_4d(GRID)
    cur = GridCurrent(c.x, c.y, c.z, c.t, c.velocity)
    rng = np.random.default_rng(4)
    p = rng.uniform([-70.0, -5.0, -40.0], [70.0, 5.0, 10.0], size=(200, 3))
    for t in (-2.0, 0.0, 6.1, 15.0, 40.0):
        np.testing.assert_allclose(cur.velocity_at(jnp.asarray(p), t), _generator(p, t), atol=1e-12)
    # shapes: one point, and a (2, 5) batch
    assert cur.velocity_at(jnp.zeros(3)).shape == (3,)
    assert cur.velocity_at(jnp.zeros((2, 5, 3)), 1.0).shape == (2, 5, 3)


def test_grid_current_is_quadrilinear_between_grid_values():
    u = np.zeros((2, 2, 2, 2, 3))
    u[1, 1, 1, 1] = [16.0, -16.0, 8.0]  # one corner: the product of the four weights
    cur = GridCurrent([0.0, 1.0], [0.0, 2.0], [-4.0, 0.0], [0.0, 10.0], u)
    w = 0.25 * 0.5 * 0.75 * 0.1
    np.testing.assert_allclose(cur.velocity_at(jnp.array([0.25, 1.0, -1.0]), 1.0), w * u[1, 1, 1, 1],
                               rtol=1e-12)
    with pytest.raises(ValueError, match=r"current grid t \[s\] must be strictly increasing"):
        GridCurrent([0.0, 1.0], [0.0, 2.0], [-4.0, 0.0], [10.0, 0.0], u)
    with pytest.raises(ValueError, match=r"needs x \(nx,\)"):
        GridCurrent([0.0, 1.0], [0.0, 2.0], [-4.0, 0.0], [0.0, 10.0], u[:1])


def test_grid_current_matches_moordyn_kinematics(tmp_path):
    moordyn = pytest.importorskip("moordyn")
    dest = tmp_path / "wavekin_4"
    shutil.copytree(PUBLIC, dest)
    cwd = os.getcwd()
    os.chdir(dest)  # MoorDyn finds current_profile_4d.txt beside the deck
    try:
        s = moordyn.Create(str(dest / "hanging_lines.txt"))
        moordyn.Init(s, [], [])
        waves = moordyn.GetWaves(s)
        cur = build_scene(read_deck(dest / "hanging_lines.txt")).env.current
        # inside the grid, away from its first row's corner (x = -50, y = -2, z = -30 m
        # at t = 0, which MoorDyn's reader skips: see moorjax.io.currents)
        pts = np.array([[-43.0, 0.3, -20.2], [7.5, -1.0, -2.0], [33.3, 1.9, -29.5], [0.0, 0.0, 4.0]])
        t, worst = 0.0, 0.0
        for _ in range(3):
            moordyn.Step(s, [], [], t, 4.1)
            t += 4.1
            for p in pts:
                u, _, _, _ = moordyn.GetWavesKin(waves, *p)
                worst = max(worst, float(np.max(np.abs(np.asarray(u) - cur.velocity_at(jnp.asarray(p), t)))))
                assert abs(u[0]) > 0.2  # the current is there
        moordyn.Close(s)
    finally:
        os.chdir(cwd)
    assert worst < 1e-9, worst


def test_free_point_drag_sees_the_current_at_its_x():
    c = read_current_grid_4d(GRID)
    cur = GridCurrent(c.x, c.y, c.z, c.t, c.velocity)
    acc = []
    for x in (-30.0, 30.0):
        point = ConnectionPoint(100.0, (x, 0.0, -10.0), volume=0.1, cda=2.0, current=cur)
        acc.append(float(point.rate(5.0, point.rest_state(), jnp.zeros(6))[6]))
    u = _generator(np.array([[-30.0, 0, 0], [30.0, 0, 0]]), 5.0)[:, 0]  # -2.5 and 3.5 m/s
    np.testing.assert_allclose(acc, 0.5 * 1025.0 * 2.0 * np.abs(u) * u / 100.0, rtol=1e-12)


# ----------------------------------------------------------------------------
# dynamics against MoorDyn 2
# ----------------------------------------------------------------------------


def _with_drag(dest):
    """The deck with the chain's normal drag coefficient Cd = 1 (the public deck
    has Cd = 0 and CdAx = 0: its current loads nothing) and MoorDyn's initial
    condition solved (TmaxIC = 30 s instead of 0: the lines start hanging in
    still water, as MoorDyn's IC runs without currents, rather than straight and
    unstretched)."""
    text = (dest / "hanging_lines.txt").read_text()
    old = "chain       13.332E-3  1.1        7.51E6     -0.5        0        0.0    0.0      0.0     1.0"
    ic = "0.0       TmaxIC "
    assert old in text and ic in text
    (dest / "hanging_lines.txt").write_text(
        text.replace(old, old.replace("0        0.0    0.0", "0        1.0    0.0")).replace(ic, "30.0      TmaxIC "))
    return dest / "hanging_lines.txt"


@pytest.mark.slow
def test_hanging_lines_in_the_4d_current_match_moordyn(tmp_path):
    """3 s from MoorDyn's still-water state: the free points' paths. (The top
    tensions are compared and printed, not asserted: MoorDyn's ring by ±100 %
    even on the line in still water at x = 0 m, this stiff chain's axial mode
    being near its explicit step, while moorjax's implicit solver damps it.)"""
    moordyn = pytest.importorskip("moordyn")
    from moorjax.dynamics import simulate

    dest = tmp_path / "wavekin_4"
    shutil.copytree(PUBLIC, dest)
    path = _with_drag(dest)
    n_lines, duration = 10, 3.0
    cwd = os.getcwd()
    os.chdir(dest)
    try:
        t0 = time.perf_counter()
        s = moordyn.Create(str(path))
        moordyn.Init(s, [], [])
        lines = [moordyn.GetLine(s, i) for i in range(1, n_lines + 1)]
        r0 = [np.array([moordyn.GetLineNodePos(ln, k) for k in range(11)]) for ln in lines]
        ts, ref, ref_pts = [], [], []
        t, dt = 0.0, 0.05
        while t < duration - 1e-9:
            moordyn.Step(s, [], [], t, dt)
            t += dt
            ts.append(t)
            ref.append([np.linalg.norm(moordyn.GetLineNodeTen(ln, 0)) for ln in lines])
            ref_pts.append([moordyn.GetPointPos(moordyn.GetPoint(s, 2 * i)) for i in range(1, n_lines + 1)])
        t_md = time.perf_counter() - t0
        moordyn.Close(s)
    finally:
        os.chdir(cwd)
    ts, ref, ref_pts = np.asarray(ts), np.asarray(ref), np.asarray(ref_pts)

    scene = build_scene(read_deck(path))
    init = tuple(LineState(r=jnp.asarray(r[1:-1]), v=jnp.zeros((9, 3))) for r in r0) + tuple(
        b.rest_state(jnp.concatenate([jnp.asarray(r[-1]) - b.origin, jnp.zeros(3)]))
        for r, b in zip(r0, scene.bodies))
    t1 = time.perf_counter()
    res = simulate(scene, ts=ts, init=init, rtol=1e-5, atol=1e-4)
    tens = np.asarray(res.tension_a)
    t_first = time.perf_counter() - t1
    t2 = time.perf_counter()
    jax.block_until_ready(simulate(scene, ts=ts, init=init, rtol=1e-5, atol=1e-4).tension_a)
    t_warm = time.perf_counter() - t2
    pts = np.asarray(res.body_pose)[:, :, :3] + np.asarray([b.origin for b in scene.bodies])[None]

    err = np.sqrt(np.mean((tens - ref) ** 2, axis=0))
    std = np.std(ref, axis=0)
    swing = np.linalg.norm(ref_pts[-1] - np.asarray([r[-1] for r in r0]), axis=-1)
    path_err = np.max(np.linalg.norm(pts - ref_pts, axis=-1), axis=0)
    print(f"hanging_lines (Cd = 1), 0-{duration:g} s: free point path error max {np.max(path_err):.3f} m, "
          f"{np.max(path_err / np.maximum(swing, 1.0)):.1%} of the swing (swings {swing.min():.2f}-"
          f"{swing.max():.2f} m); top tension RMS error / MoorDyn std {np.min(err / std):.2f}-"
          f"{np.max(err / std):.2f}; MoorDyn {t_md:.2f} s, moorjax {t_warm:.2f} s (first call with compile "
          f"{t_first:.1f} s)")
    # the lines feel different currents: the x = -50 m line swings far, the x = 0 m one barely
    assert swing[0] > 10.0 and swing[5] < 0.5
    assert np.all(path_err < 0.05 * np.maximum(swing, 1.0)), (path_err, swing)
    # moorjax's line at x = 0 m (current 0.1·t m/s, under 0.03 m/s here) keeps its static tension
    np.testing.assert_allclose(tens[:5, 5], 93.841, rtol=1e-3)
