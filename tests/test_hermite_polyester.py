"""Wu et al.'s polyester line in dynamics: the diffrax run against the paper's Newmark/Newton stepping.

One line of the moored box (:mod:`moorjax.examples.wu_box`): 110 m of polyester
with Eq. 15's load-dependent stiffness AE = RHOL·(α + β·T/MBL)·10⁶ (α = 2.5,
β = 2.0, MBL 2.7 MN: 2.7e7 N at rest, stiffening with the load), from an anchor
on the 80 m seabed 92.25 m out to a fairlead 20 m below the surface (20 kN
horizontal pretension at rest). The fairlead surges ±4 m with a 10 s period,
starting at rest at its nearest point to the anchor, so the line goes from slack
(part of it on the seabed) to taut. 10 Hermite elements with Wu's tension field
(:class:`MixedTension`, the equations the Newmark reference steps), through
diffrax's Kvaerno5, against ``newmark_hermite`` at dt = 2.5 ms.

Started with the fairlead moving (velocity 2.5 m/s at t = 0, the phase of
``test_hermite_dynamics``' case A) the impulsive start rings the soft line's
axial modes, which Newmark's trapezoidal rule carries with a period error:
the two then differed by 1.3 % RMS and 3.6 % at worst of the range (0.93 %
and 3.7 % at dt = 1.25 ms, 0.89 % and 3.2 % at 0.625 ms), the difference of
two integrations of a ringing line, not of the element.
"""

from __future__ import annotations

import numpy as np
import pytest

import moorjax as mj
from moorjax.dynamics import simulate
from moorjax.dynamics.hermite_newmark import newmark_hermite
from moorjax.element import HermiteElement
from moorjax.element.hermite_motion import MixedTension
from moorjax.examples import wu_box
from moorjax.statics.hermite import hermite_equilibrium

RADIUS = 92.25047399927594  # wu_box.anchor_radius("polyester"): 20 kN horizontal at rest


def polyester_line(n=10):
    lt = wu_box.line_type("polyester")
    path = mj.SinePath([0.0, 0.0, -20.0], [-4.0, 0.0, 0.0], 10.0, phase=-np.pi / 2)
    return mj.Line(lt, wu_box.LINE_LENGTH, n, mj.FixedEnd([RADIUS, 0.0, -wu_box.DEPTH]), path,
                   element=HermiteElement(tension=MixedTension()))


def test_the_anchor_radius_gives_the_pretension():
    """The stored radius is the example's (20 kN horizontal at the fairlead;
    measured 1.4e-5 off, the bisection's tolerance on the radius)."""
    from moorjax.statics.fem import solve_line_statics

    lt = wu_box.line_type("polyester")
    line = mj.Line(lt, wu_box.LINE_LENGTH, 10, mj.FixedEnd([RADIUS, 0.0, -wu_box.DEPTH]),
                   mj.FixedEnd([0.0, 0.0, -20.0]))
    st = solve_line_statics(line, wu_box.environment(current=False))
    assert abs(float(np.hypot(st.force_b[0], st.force_b[1])) / wu_box.PRETENSION_H - 1) < 1e-4


@pytest.mark.slow
def test_polyester_line_follows_the_newmark_reference():
    """5 s, the fairlead from x = +4 m to −4 m (fairlead tension from 4.8 kN
    to 1.12 MN, 41 % of MBL): diffrax at rtol 1e-6 and Newmark at dt = 2.5 ms
    agree to RMS 1.1e-4 and 2.6e-4 at worst of the 1.11 MN range (over the
    first 3 s: 3.5e-4 and 8.2e-4 of 0.35 MN; 3.4e-4 and 6.9e-4 at dt =
    1.25 ms, so what is left is not Newmark's step). ~40 s."""
    line = polyester_line()
    env = wu_box.environment(current=False)
    res = simulate(mj.Scene((line,), env), 5.0, rtol=1e-6, atol=1e-5)
    dofs, _ = hermite_equilibrium(line, env, 0.0)
    ref = newmark_hermite(line, env, dofs, 0.0, 0.0025, 2000)
    assert float(np.max(ref.newton_residual)) < 1e-9
    ts = np.asarray(res.ts)[1:]
    ours = np.asarray(res.tension_b[1:, 0])
    theirs = np.interp(ts, np.asarray(ref.t), np.asarray(ref.tension_b))
    span = np.ptp(theirs)
    err = ours - theirs
    rms, worst = np.sqrt(np.mean(err**2)) / span, np.max(np.abs(err)) / span
    assert span > 1e6 and theirs.max() > 0.35 * 2.7e6
    assert rms < 1e-3 and worst < 3e-3, (rms, worst)
