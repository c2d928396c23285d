"""Output times and the ends of a tabulated motion: no sample is silently wrong.

What went wrong before (issue 11): a run whose duration equalled the last time of
its motion table had wrong last samples (case A at 40 segments: 1674 and 1652 kN
at t = 19.95 and 20 s where a longer table gives 1696 and 1709 kN). Beyond its
last sample the path stopped dead (velocity 0), and Kvaerno5 evaluates its third
stage at 1.23 steps, past the end of the step (Kvaerno4: 1.15): every step whose
stage reached past the motion's end saw a fairlead that had stopped, i.e. a jump
of the line's internal damping force. Now the path's last cubic continues
smoothly, and a run that leaves the motion's time span is refused.

The scene: the bundled taut polyester deck (case B) at 6 segments, fairlead path
x = A·(1 − cos 2πt/P) (from rest at t = 0, so the first sample is the static
state; moving at 1.4 m/s at t = 1 s, the run's end). Every run with its
structure (21 knots, 21 output times, Kvaerno5) shares one compilation, the CLI
run included.
"""

from __future__ import annotations

import contextlib
import io
import warnings

import equinox as eqx
import numpy as np
import pytest

import moorjax as mj
from moorjax.cli import main
from moorjax.dynamics import simulate
from moorjax.dynamics.simulate import plan
from moorjax.examples import example_path
from moorjax.io import build_scene, read_deck, read_motion
from moorjax.statics import solve_line_statics

SEGMENTS = 6
DURATION = 1.0  # [s]
KNOTS = 21  # rows of every motion table here (one structure, one compilation)
FAIRLEAD = np.array([0.0, 0.0, -5.0])  # point 2 of the deck [m]
AMP, PERIOD = 0.1, 1.6  # [m], [s]


def surge(t):
    """Fairlead x offset [m] and velocity [m/s]: from rest at t = 0."""
    w = 2 * np.pi / PERIOD
    return AMP * (1 - np.cos(w * t)), AMP * w * np.sin(w * t)


def table(t):
    """(t, position, velocity) of the fairlead path sampled at t [s]."""
    x, vx = surge(t)
    zero = np.zeros_like(t)
    return t, np.column_stack([FAIRLEAD[0] + x, zero, zero + FAIRLEAD[2]]), np.column_stack([vx, zero, zero])


def write_motion(path, t):
    t, r, v = table(t)
    np.savetxt(path, np.column_stack([t, r, v]), delimiter=",", fmt="%.15g", comments="",
               header="t,P2_x,P2_y,P2_z,P2_vx,P2_vy,P2_vz")
    return path


def deck_scene(path=None):
    deck = read_deck(example_path("taut_polyester"))
    return build_scene(deck, segments=SEGMENTS, motion=None if path is None else read_motion(path, [2]))


def with_path(scene, t, shift=0.0):
    """The scene with its fairlead on the path sampled at t [s], delayed by shift [s]."""
    t, r, v = table(t)
    return eqx.tree_at(lambda s: s.lines[0].end_b, scene, mj.TabulatedPath(t + shift, r, v))


@pytest.fixture(scope="module")
def base():
    return deck_scene()


@pytest.fixture(scope="module")
def ends_on_last_sample(base):
    """Motion table 0 … 1 s (knots every 0.05 s, on every output time), run for 1 s."""
    return simulate(with_path(base, np.linspace(0.0, DURATION, KNOTS)), DURATION)


@pytest.fixture(scope="module")
def longer_motion(base):
    """The same path tabulated 0 … 1.2 s (knots every 0.06 s: between most output
    times), run for 1 s: its end is never near the run."""
    return simulate(with_path(base, np.linspace(0.0, 1.2, KNOTS)), DURATION)


# ------------------------------------------------------------------ the path itself


def test_path_is_smooth_through_its_last_sample():
    """At the knots the path gives the table; past the last knot its last cubic
    continues (position, velocity and acceleration continuous there), so a
    solver stage just past the end sees the path, not a point that stopped."""
    t, r, v = table(np.linspace(0.0, DURATION, KNOTS))
    path = mj.TabulatedPath(t, r, v)
    for k in (0, 7, KNOTS - 1):
        np.testing.assert_allclose(np.asarray(path.position(t[k])), r[k], rtol=0, atol=1e-14)
        np.testing.assert_allclose(np.asarray(path.velocity(t[k])), v[k], rtol=0, atol=1e-13)
    for edge, side in ((t[-1], 1.0), (t[0], -1.0)):
        eps = 1e-9  # [s]: each quantity changes by less than its rate·2eps across
        inside, outside = edge - side * eps, edge + side * eps
        for f, tol in ((path.position, 1e-8), (path.velocity, 1e-7), (path.acceleration, 1e-5)):
            np.testing.assert_allclose(np.asarray(f(outside)), np.asarray(f(inside)), rtol=0, atol=tol)
    # 0.23 of a 0.05 s step past the end (Kvaerno5's third stage): still the path
    late = t[-1] + 0.23 * 0.05
    x, vx = surge(late)
    np.testing.assert_allclose(np.asarray(path.position(late))[0], FAIRLEAD[0] + x, atol=1e-6)
    np.testing.assert_allclose(np.asarray(path.velocity(late))[0], vx, rtol=1e-3)
    assert path.time_span() == (t[0], t[-1])
    assert mj.FixedEnd([0.0, 0.0, 0.0]).time_span() == (-np.inf, np.inf)


# ------------------------------------------------------------------ output times


def test_default_output_times_start_at_t0_and_end_at_the_duration():
    """0, dt_out, … then the duration itself, exactly (0.1·3 = 0.30000000000000004
    would end the run 1 ulp past a motion that ends at 0.3 s)."""
    ts = np.asarray(plan(0.3, dt_out=0.1).ts)
    assert ts[0] == 0.0 and ts[-1] == 0.3 and len(ts) == 4
    ts = np.asarray(plan(1.03, dt_out=0.05).ts)
    assert ts[0] == 0.0 and ts[-1] == 1.03 and len(ts) == 22
    np.testing.assert_allclose(np.diff(ts)[:-1], 0.05, rtol=1e-12)
    ts = np.asarray(plan(1.0, dt_out=0.05, t0=0.7).ts)
    assert ts[0] == 0.7 and ts[-1] == 1.7 and len(ts) == 21
    assert float(plan(ts=[0.0, 0.5]).ts[0]) == 0.0  # t0 itself may be asked for
    with pytest.raises(ValueError, match=">= t0"):
        plan(ts=[0.2, 0.5], t0=0.3)


@pytest.mark.slow
def test_first_sample_is_the_static_state_at_t0(ends_on_last_sample, base):
    """The path starts from rest, so the sample at t0 = 0 is the static solution."""
    res = ends_on_last_sample
    ts = np.asarray(res.ts)
    assert ts[0] == 0.0 and ts[-1] == DURATION and len(ts) == KNOTS
    st = solve_line_statics(base.lines[0], base.env)
    np.testing.assert_allclose(float(res.tension_a[0, 0]), float(st.tension_a), rtol=1e-9)
    np.testing.assert_allclose(float(res.tension_b[0, 0]), float(st.tension_b), rtol=1e-9)
    # and the line then moves: the samples are not all the static value
    assert float(res.tension_b[-1, 0]) > 1.5 * float(st.tension_b)


@pytest.mark.slow
def test_run_ending_on_the_last_motion_sample_equals_a_longer_motion(ends_on_last_sample,
                                                                     longer_motion):
    """Every sample, the last ones included, agrees with a run whose motion goes on
    (samples on knots of one table and between knots of the other). Measured:
    1.8e-5 of the peak tension; before the fix 1.6 % at t = 0.9 s (the steps
    whose third stage fell past t = 1 s)."""
    a = np.asarray(ends_on_last_sample.tension_b[:, 0])
    b = np.asarray(longer_motion.tension_b[:, 0])
    np.testing.assert_allclose(a, b, rtol=0, atol=2e-4 * np.max(b))


def test_run_from_t0_is_the_same_run_delayed(ends_on_last_sample, base):
    """Starting at t0 = 0.7 s with the path delayed by 0.7 s gives the same
    samples, at t = 0.7 … 1.7 s (time invariance; the first is the t0 state).
    Measured: 1e-12 of the peak (the same steps); the bound allows other steps."""
    t0 = 0.7
    res = simulate(with_path(base, np.linspace(0.0, DURATION, KNOTS), shift=t0), DURATION, t0=t0)
    ts = np.asarray(res.ts)
    assert ts[0] == t0 and ts[-1] == t0 + DURATION
    np.testing.assert_allclose(ts - t0, np.asarray(ends_on_last_sample.ts), atol=1e-12)
    ref = np.asarray(ends_on_last_sample.tension_b[:, 0])
    np.testing.assert_allclose(np.asarray(res.tension_b[:, 0]), ref, rtol=0, atol=1e-4 * np.max(ref))


# ------------------------------------------------------------------ motion not covering the run


@pytest.mark.parametrize(
    "times, t0, expect",
    [
        (np.linspace(0.0, 0.99, KNOTS), 0.0, "ends at t = 0.99 s, before the end of the run at 1 s"),
        (np.linspace(0.05, 1.2, KNOTS), 0.0, "starts at t = 0.05 s, after the start of the run t0 = 0 s"),
        (np.linspace(0.0, 1.2, KNOTS), -0.1, "starts at t = 0 s, after the start of the run t0 = -0.1 s"),
    ],
    ids=["ends-early", "starts-late", "t0-before-motion"],
)
def test_motion_not_covering_the_run_is_refused(base, times, t0, expect):
    """Never held still silently: a ValueError naming the line end, both spans."""
    scene = with_path(base, times)
    with pytest.raises(ValueError) as info:
        simulate(scene, DURATION, t0=t0)
    msg = str(info.value)
    assert "line 1 end B" in msg and expect in msg and "must cover the whole run" in msg, msg


@pytest.mark.slow
def test_cli_motion_ending_at_the_duration(tmp_path, base):
    """``moorjax simulate`` with a motion file ending exactly at --duration: no
    warning; the CSV starts with the static state at t = 0 and equals the API."""
    motion = write_motion(tmp_path / "motion.csv", np.linspace(0.0, DURATION, KNOTS))
    out = tmp_path / "out.csv"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rc = main(["simulate", "example:taut_polyester", "--duration", str(DURATION),
                   "--segments", str(SEGMENTS), "--motion", str(motion), "--out", str(out)])
    assert rc == 0
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    res = simulate(deck_scene(motion), DURATION)
    np.testing.assert_allclose(data[:, 0], np.asarray(res.ts), atol=1e-12)
    assert data[0, 0] == 0.0 and data[-1, 0] == DURATION
    np.testing.assert_allclose(data[:, 2], np.asarray(res.tension_b[:, 0]), rtol=1e-9)
    st = solve_line_statics(base.lines[0], base.env)
    np.testing.assert_allclose(data[0, 2], float(st.tension_b), rtol=1e-9)


@pytest.mark.parametrize(
    "times, expect",
    [(np.linspace(0.0, 0.99, KNOTS), "covers t = 0 to 0.99 s"),
     (np.linspace(0.02, 1.0, KNOTS), "covers t = 0.02 to 1 s")],
    ids=["ends-early", "starts-late"],
)
def test_cli_motion_not_covering_the_run_is_refused(tmp_path, times, expect):
    motion = write_motion(tmp_path / "gap.csv", times)
    out = tmp_path / "out.csv"
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = main(["simulate", "example:taut_polyester", "--duration", str(DURATION),
                   "--segments", str(SEGMENTS), "--motion", str(motion), "--out", str(out)])
    msg = err.getvalue()
    assert rc == 2 and not out.exists()
    assert "gap.csv" in msg and expect in msg and "the run needs t = 0 to 1 s" in msg, msg
