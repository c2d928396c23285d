"""A clamp carried along a prescribed path (:class:`~moorjax.MovingClampedEnd`).

The oracle is the statics: a beam whose clamp moves slowly against its first
bending mode follows the static shape with the clamp where it is at that time
(quasi-static), up to (ω/ω₁)² and the small vibration its start leaves.
"""

from __future__ import annotations

import numpy as np
import pytest

import moorjax as mj
from moorjax.dynamics import simulate
from moorjax.element import HermiteElement, LinearElement
from moorjax.statics import solve_line_statics

L, EI = 10.0, 1.0e7
ENV = mj.Environment(100.0)
AREA = np.pi * 0.05**2 / 4
# a 10 m beam of 981 N/m wet weight, stiff in tension and compression
BEAM = mj.LineType(0.05, 981.0 / ENV.g + ENV.rho * AREA, mj.Bilateral(mj.LinearEA(1.5e9)), ei=EI)
CLAMP_AT = np.array([0.0, 0.0, -50.0])
ALONG_X = (1.0, 0.0, 0.0)
FAR = mj.FixedEnd((L, 0.0, -50.0))


def _propped(end_a, element, n):
    return mj.Line(BEAM, L, n, end_a, FAR, element=element)


def test_a_moving_clamp_held_still_is_the_fixed_clamp():
    """On a fixed path the moving clamp is the fixed clamp: same statics and,
    started from them, the same dynamics (Hermite, 4 elements)."""
    held = mj.MovingClampedEnd(mj.FixedEnd(CLAMP_AT), ALONG_X)
    fixed = mj.ClampedEnd(CLAMP_AT, ALONG_X)
    runs = [simulate(mj.Scene((_propped(end, HermiteElement(), 4),), ENV), 0.3, dt_out=0.1,
                     save_nodes=True) for end in (held, fixed)]
    np.testing.assert_allclose(np.asarray(runs[0].positions[0]), np.asarray(runs[1].positions[0]),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.asarray(runs[0].tension_a), np.asarray(runs[1].tension_a),
                               rtol=1e-12)


def test_moving_clamp_refuses_what_it_cannot_model():
    with pytest.raises(ValueError, match="turn with the body"):
        mj.MovingClampedEnd(mj.BodyEnd(0, (1.0, 0.0, 0.0)), ALONG_X)
    with pytest.raises(ValueError, match="direction"):
        mj.MovingClampedEnd(mj.FixedEnd(CLAMP_AT), (0.0, 0.0, 0.0))
    with pytest.raises(TypeError, match="path"):
        mj.MovingClampedEnd(CLAMP_AT, ALONG_X)
    with pytest.raises(ValueError, match="already a clamp"):
        mj.MovingClampedEnd(mj.ClampedEnd(CLAMP_AT, ALONG_X), ALONG_X)
    # a run that leaves the time span of the clamp's tabulated path
    table = mj.TabulatedPath([0.0, 1.0], [CLAMP_AT, CLAMP_AT + [0.0, 0.0, 0.1]])
    line = _propped(mj.MovingClampedEnd(table, ALONG_X), HermiteElement(), 4)
    with pytest.raises(ValueError, match="ends at t = 1 s"):
        simulate(mj.Scene((line,), ENV), 2.0)


@pytest.mark.slow
@pytest.mark.parametrize("element, n, tol", [(HermiteElement(), 4, 2e-3), (LinearElement(), 20, 2e-3)])
def test_a_slowly_moving_clamp_carries_the_static_shape(element, n, tol):
    """The clamp of a propped beam heaves 0.1 m with a 4 s period (starting at
    rest at its lowest point), 20 times slower than the beam's first mode
    (~0.13 s): at each output time the beam's midspan is where the statics with
    the clamp held at that point put it, within ``tol`` of the clamp's 0.2 m
    stroke (the midspan moves 0.136 m; measured at most 1.06e-3 Hermite,
    1.36e-3 linear: the start's undamped vibration and (ω/ω₁)²). ~10 s each."""
    path = mj.SinePath(CLAMP_AT, (0.0, 0.0, 0.1), 4.0, -np.pi / 2)
    line = _propped(mj.MovingClampedEnd(path, ALONG_X), element, n)
    ts = np.arange(0.5, 4.01, 0.5)
    res = simulate(mj.Scene((line,), ENV), ts=ts, save_nodes=True)
    assert bool(res.succeeded())
    mid = np.asarray(res.positions[0])[:, n // 2]
    moved = []
    for k, t in enumerate(ts):
        held = _propped(mj.ClampedEnd(np.asarray(path.position(t)), ALONG_X), element, n)
        static = np.asarray(solve_line_statics(held, ENV).positions)[n // 2]
        moved.append(static[2] - (-50.0))
        assert np.max(np.abs(mid[k] - static)) < tol * 0.2, (t, mid[k], static)
    assert np.ptp(moved) > 0.08  # the midspan did follow the clamp
