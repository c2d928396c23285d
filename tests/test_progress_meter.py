"""The live step counts of the progress bar: exact, and shown by the CLI's bar."""

from __future__ import annotations

import contextlib
import io

import diffrax
import jax.numpy as jnp

from moorjax._progress import Progress
from moorjax.dynamics.meter import StepMeter


class _Tty(io.StringIO):
    def isatty(self):
        return True


def _stiff_solve(meter):
    def f(t, y, args):
        return -50.0 * (y - jnp.cos(t))

    return diffrax.diffeqsolve(
        diffrax.ODETerm(f), diffrax.Tsit5(), 0.0, 10.0, 0.5, jnp.asarray(1.0),
        stepsize_controller=diffrax.PIDController(rtol=1e-6, atol=1e-8), progress_meter=meter)


def test_meter_counts_equal_the_solver_statistics():
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        sol = _stiff_solve(StepMeter(minimum_increase=0.2))
    lines = [ln.split() for ln in out.getvalue().splitlines()]
    assert lines[0] == ["0.00%", "0", "0"]
    fractions = [float(ln[0][:-1]) for ln in lines]
    assert fractions == sorted(fractions) and fractions[-1] == 100.0
    assert 5 <= len(lines) <= 8  # throttled: about one line per 20 %
    steps, rejected = int(lines[-1][1]), int(lines[-1][2])
    assert steps == int(sol.stats["num_steps"])
    assert rejected == int(sol.stats["num_rejected_steps"]) > 0


def test_bar_shows_steps_and_rejections():
    s = _Tty()
    p = Progress("simulate", True, stream=s)
    with p.meter(0.0, 60.0):
        print("0.00% 0 0")
        print("50.00% 120 7")
    text = s.getvalue()
    assert "t = 30 / 60 s simulated, 120 steps (7 rejected)" in text
