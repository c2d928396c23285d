"""``moorjax simulate``: output columns, held and prescribed coupled points, --stats,
and bad input (exit code 2 with a message naming what is wrong).

Runs are short (1 s) on 6 segments of ``example:taut_polyester`` (one line, id 1,
from anchor point 1 to coupled fairlead point 2). Every run with the same scene
structure reuses one compilation of the integrator; the static solve that starts
each run is the main cost after that.
"""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

from moorjax.cli import main
from moorjax.dynamics import simulate
from moorjax.examples import example_path
from moorjax.io import build_scene, read_deck, read_motion

DECK = "example:taut_polyester"
SEGMENTS = "6"
DURATION = 1.0
COLUMNS = ["t", "L1_tension_a", "L1_tension_b", "P2_Fx", "P2_Fy", "P2_Fz"]
FAIRLEAD = np.array([0.0, 0.0, -5.0])  # point 2 of the deck [m]


def sim_args(out, *extra):
    return ["simulate", DECK, "--duration", str(DURATION), "--segments", SEGMENTS,
            "--out", str(out), *extra]


def read_csv(path):
    with open(path) as f:
        header = f.readline().strip().split(",")
    return header, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def write_motion(path, t, x, velocity=True):
    """Fairlead path x(t) (y = 0, z = -5 m) with exact velocities (x is a sine)."""
    zero = np.zeros_like(t)
    cols = [t, FAIRLEAD[0] + x(t), zero, zero + FAIRLEAD[2]]
    names = ["t", "P2_x", "P2_y", "P2_z"]
    if velocity:
        h = 1e-6
        cols += [(x(t + h) - x(t - h)) / (2 * h), zero, zero]
        names += ["P2_vx", "P2_vy", "P2_vz"]
    np.savetxt(path, np.column_stack(cols), delimiter=",", fmt="%.12g", comments="",
               header=",".join(names))
    return path


def surge(t):
    return 0.5 * np.sin(2 * np.pi * t / 2.0)  # 0.5 m, 2 s period [m]


@pytest.fixture(scope="module")
def held_run(tmp_path_factory):
    """One run with ``--motion none`` (the bundled example's own motion is the
    default), with --stats: (exit code, csv path, stderr)."""
    out = tmp_path_factory.mktemp("held") / "out.csv"
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = main(sim_args(out, "--stats", "--motion", "none"))
    return rc, out, err.getvalue()


@pytest.fixture(scope="module")
def statics_row():
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = main(["statics", DECK, "--segments", SEGMENTS, "--method", "fem", "--json"])
    assert rc == 0
    (row,) = json.loads(out.getvalue())
    return row


# ------------------------------------------------------------------ output


def test_columns_and_times(held_run):
    rc, out, err = held_run
    assert rc == 0, err
    header, data = read_csv(out)
    assert header == COLUMNS
    # default --dt-out 0.05 s: 0 (the initial state) … 1.0 s
    np.testing.assert_allclose(data[:, 0], np.arange(0, 21) * 0.05, atol=1e-12)
    assert np.all(np.isfinite(data))


def test_without_motion_the_fairlead_holds_its_static_tension(held_run, statics_row):
    """No --motion: point 2 stays at its deck position, the line stays in its static
    equilibrium, and the tensions equal ``moorjax statics`` (to 1e-6: the dynamic
    run starts exactly there; measured ~1e-11)."""
    _, out, _ = held_run
    _, data = read_csv(out)
    np.testing.assert_allclose(data[:, 1], statics_row["tension_a"], rtol=1e-6)
    np.testing.assert_allclose(data[:, 2], statics_row["tension_b"], rtol=1e-6)
    # P2 is only line 1's end B: its total force is that end's force
    np.testing.assert_allclose(data[:, 3:6], np.tile(statics_row["force_b"], (len(data), 1)),
                               rtol=1e-6, atol=1e-6 * statics_row["tension_b"])
    np.testing.assert_allclose(np.linalg.norm(data[:, 3:6], axis=1), data[:, 2], rtol=1e-12)


def test_stats_line(held_run):
    _, _, err = held_run
    lines = [ln for ln in err.splitlines() if ln.strip()]
    json_lines = [ln for ln in lines if ln.lstrip().startswith("{")]
    assert len(json_lines) == 1, err
    stats = json.loads(json_lines[0])
    assert {"compile_s", "run_s", "steps", "rejected_steps", "solver"} <= set(stats)
    assert stats["solver"] == "ros34pw2" and stats["solver_requested"] == "auto"
    np.testing.assert_allclose([stats["rtol"], stats["atol"]], [1e-5, 1e-4], rtol=1e-12)
    assert isinstance(stats["steps"], int) and stats["steps"] > 0
    assert isinstance(stats["rejected_steps"], int)
    assert 0 <= stats["rejected_steps"] <= stats["steps"]
    assert np.isfinite(stats["compile_s"]) and stats["run_s"] > 0


@pytest.mark.slow
def test_motion_file_drives_the_fairlead(tmp_path, capsys, statics_row):
    """With --motion (columns t, P2_x, P2_y, P2_z; velocities optional and left out
    here: the spline slopes then come from the positions), point 2 follows the
    file: the CSV equals the Python API run of the same scene, and the tension
    departs from the static value. (Explicit dopri5 here, a cheap compile; the
    held run above uses the default kvaerno5.)"""
    motion = write_motion(tmp_path / "motion.csv", np.linspace(0.0, 1.5, 151), surge,
                          velocity=False)
    out = tmp_path / "out.csv"
    rc = main(sim_args(out, "--motion", str(motion), "--solver", "dopri5"))
    assert rc == 0, capsys.readouterr().err
    header, data = read_csv(out)
    assert header == COLUMNS

    scene = build_scene(read_deck(example_path("taut_polyester")), segments=6,
                        motion=read_motion(motion, [2]))
    res = simulate(scene, DURATION, solver="dopri5")
    np.testing.assert_allclose(data[:, 0], np.asarray(res.ts), atol=1e-12)
    np.testing.assert_allclose(data[:, 1], np.asarray(res.tension_a[:, 0]), rtol=1e-9)
    np.testing.assert_allclose(data[:, 2], np.asarray(res.tension_b[:, 0]), rtol=1e-9)
    np.testing.assert_allclose(data[:, 3:6], np.asarray(res.force_b[:, 0]), rtol=1e-9, atol=1e-3)
    # moving up to 0.5 m away from the anchor stretches this stiff taut line a lot
    assert np.max(data[:, 2]) > 1.5 * statics_row["tension_b"]


# ------------------------------------------------------------------ bad input


def run_bad(capsys, argv, out):
    rc = main(argv)
    captured = capsys.readouterr()
    assert rc == 2
    assert not out.exists()  # nothing written
    return captured.err


@pytest.mark.parametrize(
    "header, rows, expect",
    [
        # missing P2_z: the message names the column and lists what was found
        ("t,P2_x,P2_y", [(0.0, 0.0, 0.0), (1.0, 0.1, 0.0), (2.0, 0.2, 0.0)],
         ["bad_motion.csv:1:", "P2_z", "missing", "found columns"]),
        # times out of order: names the row's time and the previous one
        ("t,P2_x,P2_y,P2_z", [(0.0, 0.0, 0.0, -5.0), (1.0, 0.1, 0.0, -5.0), (0.5, 0.2, 0.0, -5.0)],
         ["bad_motion.csv:4:", "'t' = 0.5", "strictly increasing"]),
        # a non-finite time
        ("t,P2_x,P2_y,P2_z",
         [(0.0, 0.0, 0.0, -5.0), ("nan", 0.1, 0.0, -5.0), (2.0, 0.2, 0.0, -5.0)],
         ["bad_motion.csv:3:", "'t'", "nan", "finite"]),
    ],
    ids=["missing-column", "unsorted-times", "nonfinite-time"],
)
def test_bad_motion_file(tmp_path, capsys, header, rows, expect):
    motion = tmp_path / "bad_motion.csv"
    motion.write_text(header + "\n" + "\n".join(",".join(str(c) for c in r) for r in rows) + "\n")
    out = tmp_path / "out.csv"
    err = run_bad(capsys, sim_args(out, "--motion", str(motion)), out)
    assert "bad_motion.csv" in err, err
    for word in expect:
        assert word in err, (word, err)


def test_missing_motion_file(tmp_path, capsys):
    out = tmp_path / "out.csv"
    err = run_bad(capsys, sim_args(out, "--motion", str(tmp_path / "nowhere.csv")), out)
    assert "nowhere.csv" in err


@pytest.mark.parametrize("duration", ["-1", "0", "nan", "inf"])
def test_bad_duration(tmp_path, capsys, duration):
    out = tmp_path / "out.csv"
    argv = ["simulate", DECK, "--duration", duration, "--segments", SEGMENTS, "--out", str(out)]
    err = run_bad(capsys, argv, out)
    assert "--duration" in err and "must be > 0" in err, err


def test_unknown_solver(tmp_path, capsys):
    out = tmp_path / "out.csv"
    with pytest.raises(SystemExit) as info:
        main(sim_args(out, "--solver", "rk45"))
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "--solver" in err and "rk45" in err and "kvaerno5" in err, err
    assert not out.exists()


@pytest.mark.parametrize(
    "flag, value, expect",
    [
        ("--rtol", "2", "rtol = 2.0"),
        ("--rtol", "0", "rtol = 0.0"),
        ("--atol", "0", "atol = 0.0 m"),
        ("--atol=-1e-4", None, "atol = -0.0001 m"),
        ("--atol-velocity", "100", "atol_velocity = 100.0 m/s"),
    ],
)
def test_tolerance_out_of_range(tmp_path, capsys, flag, value, expect):
    out = tmp_path / "out.csv"
    # (a negative number after a separate flag looks like an option to argparse;
    # "--atol=-1e-4" passes it)
    err = run_bad(capsys, sim_args(out, *([flag] if value is None else [flag, value])), out)
    assert expect in err and "out of range" in err, err


def test_motion_shorter_than_duration_is_refused(tmp_path, capsys):
    """An error naming the file and both time spans (the point is never held still:
    see tests/test_output_times.py)."""
    motion = write_motion(tmp_path / "short.csv", np.linspace(0.0, 0.5, 51), surge)
    out = tmp_path / "out.csv"
    err = run_bad(capsys, sim_args(out, "--motion", str(motion)), out)
    assert "short.csv" in err and "t = 0 to 0.5 s" in err and "t = 0 to 1 s" in err, err
