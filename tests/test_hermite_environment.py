"""Hermite lines over a bathymetry and in waves (issue 13: everything the linear
element has).

Checked: a flat bathymetry grid gives the flat seabed's statics; a line resting
on a sloped seabed converges to MoorPy's inclined catenary as the elements
refine; a line at rest on the slope stays at rest in the dynamics (the contact
of the dynamics is the statics'); a line in a regular Airy wave follows the fine
linear element.
"""

from __future__ import annotations

import numpy as np
import pytest

import moorjax as mj
from moorjax.element import HermiteElement
from moorjax.model.environment import Bathymetry, Seabed
from moorjax.statics import solve_line_statics

SLOPE, W, D = 0.1, 500.0, 0.1
#: a seabed rising 0.1 m per m along x, at z = -50 m under the anchor
SLOPED = Bathymetry([-100.0, 300.0], [-10.0, 10.0], [[-60.0, -60.0], [-20.0, -20.0]])
LT_BED = mj.LineType(D, W / 9.80665 + 1025.0 * np.pi * D**2 / 4, 1e9)


def _sloped_line(n, element=None):
    return mj.Line(LT_BED, 100.0, n, mj.FixedEnd((0.0, 0.0, -50.0)), mj.FixedEnd((80.0, 0.0, -5.0)),
                   element=element)


def test_flat_grid_equals_the_flat_seabed():
    """A bathymetry grid at -depth everywhere: the same statics as the flat bed
    (the Hermite statics then start from the linear element's equilibrium)."""
    friction = mj.SeabedFriction(0.5)
    flat = mj.Environment(50.0, seabed=Seabed(3e6, 3e5, friction))
    grid = Bathymetry([-100.0, 0.0, 200.0], [-10.0, 10.0], np.full((3, 2), -50.0))
    gridded = mj.Environment(50.0, seabed=Seabed(3e6, 3e5, friction, grid))
    line = mj.Line(LT_BED, 120.0, 8, mj.FixedEnd((0.0, 0.0, -50.0)), mj.FixedEnd((90.0, 0.0, -10.0)),
                   element=HermiteElement())
    a, b = solve_line_statics(line, flat), solve_line_statics(line, gridded)
    assert float(a.grounded_length) > 20.0
    for name in ("tension_a", "tension_b", "grounded_length"):
        np.testing.assert_allclose(float(getattr(b, name)), float(getattr(a, name)), rtol=1e-7)
    np.testing.assert_allclose(np.asarray(b.positions), np.asarray(a.positions), atol=1e-7)


@pytest.mark.slow
def test_line_on_a_sloped_seabed_converges_to_moorpy():
    """MoorPy's catenary with a seabed incline atan(0.1) (stiff bed, kBot = 3e8
    Pa/m; a third of the line on the slope): Hermite statics at 10 and 40
    elements (measured 2.8e-3 / 1.3e-3 at 10, 3.8e-4 / 1.7e-4 at 40 for the
    anchor / fairlead tension; the touchdown kink limits the order)."""
    from moorpy.Catenary import catenary

    env = mj.Environment(70.0, seabed=Seabed(3e8, 0.0, None, SLOPED))
    fah, fav, fbh, fbv, info = catenary(80.0, 45.0, 100.0, 1e9, W, CB=0,
                                        alpha=np.degrees(np.arctan(SLOPE)))
    assert info["LBot"] > 30
    errors = {}
    for n in (10, 40):
        st = solve_line_statics(_sloped_line(n, HermiteElement()), env)
        errors[n] = np.array([float(st.tension_a) / np.hypot(fah, fav) - 1,
                              float(st.tension_b) / np.hypot(fbh, fbv) - 1])
        assert abs(float(st.grounded_length) - info["LBot"]) < 0.05 * info["LBot"], (n, float(st.grounded_length))
    print(errors)
    assert np.all(np.abs(errors[40]) < 1e-3), errors
    assert np.all(np.abs(errors[40]) < 0.25 * np.abs(errors[10])), errors


@pytest.mark.slow
def test_line_at_rest_on_the_slope_stays_at_rest():
    """From its static equilibrium on the sloped seabed (with damping and
    friction) the dynamics of a Hermite line have nothing to do: the contact of
    the dynamics is the statics' contact."""
    from moorjax.dynamics import simulate
    from moorjax.dynamics.initial import equilibrium_state

    env = mj.Environment(70.0, seabed=Seabed(3e8, 3e5, mj.SeabedFriction(0.5), SLOPED))
    scene = mj.Scene([_sloped_line(10, HermiteElement())], env)
    eq = equilibrium_state(scene)
    assert bool(eq.converged)
    res = simulate(scene, 2.0, init=eq.state, dt_out=0.5, save_nodes=True)
    drift = np.abs(np.asarray(res.positions[0]) - np.asarray(res.positions[0][0])).max()
    tension = np.asarray(res.tension_b[:, 0])
    assert drift < 1e-5, drift
    assert np.ptp(tension) < 1e-5 * tension.mean(), tension


@pytest.mark.slow
def test_line_in_waves_follows_the_fine_linear_element():
    """A line hung between fixed points 40 m and 5 m deep in a 3 m, 6 s Airy wave,
    12 s from the still-water equilibrium: its middle moves 0.23 m. Hermite lines
    at 10 elements against linear ones at 80 (measured against linear-160:
    Hermite-10 5.7 mm, Hermite-20 1.2 mm, linear-80 2.1 mm, linear-40 8.8 mm).
    The fairlead tension carries the line's lightly damped axial mode (≈ 3.4 Hz,
    excited by the waves' sudden start), which no discretisation resolves alike;
    averaged over 0.6 s (two of its periods) it agrees (measured against
    linear-160: Hermite-10 2.5 %, Hermite-20 1.2 %, linear-80 1.6 % RMS of its
    standard deviation)."""
    from moorjax.dynamics import simulate
    from moorjax.model.waves import AiryWaves, IrregularWave

    lt = mj.LineType(0.08, 30.0, 2.0e7, drag=mj.MorisonDrag(1.2, 0.2),
                     added_mass=mj.AddedMass(1.0, 0.0))
    env = mj.Environment(100.0, seabed=None,
                         waves=AiryWaves(IrregularWave(2 * np.pi / 6.0, 3.0, 0.0), 100.0))
    out = {}
    for n, element in ((10, HermiteElement()), (80, None)):
        line = mj.Line(lt, 110.0, n, mj.FixedEnd((0.0, 0.0, -40.0)), mj.FixedEnd((90.0, 0.0, -5.0)),
                       element=element)
        res = simulate(mj.Scene([line], env), 12.0, dt_out=0.05, rtol=1e-8, atol=1e-7,
                       save_nodes=True)
        out[n] = np.asarray(res.positions[0][:, n // 2]), np.asarray(res.tension_b[:, 0])
    (mh, th), (ml, tl) = out[10], out[80]
    travel = np.ptp(ml, axis=0).max()
    assert travel > 0.15  # the waves move the line
    assert np.abs(mh - ml).max() < 0.04 * travel, (np.abs(mh - ml).max(), travel)

    def smooth(x):
        return np.convolve(x, np.ones(12) / 12, mode="valid")

    dt = smooth(th) - smooth(tl)
    assert np.sqrt(np.mean(dt**2)) < 0.05 * np.std(smooth(tl)), np.sqrt(np.mean(dt**2)) / np.std(smooth(tl))


def test_gradient_of_a_grounded_line_through_the_new_start():
    """d T_B / d(EA, fairlead x) of a grounded Hermite line: with a seabed the
    solve starts from the linear equilibrium and damps Newton's steps (values
    only); the implicit function theorem still gives the derivative (central
    differences)."""
    import equinox as eqx
    import jax.numpy as jnp
    from test_hermite_statics import assert_gradient_matches_central_differences

    env = mj.Environment(50.0, seabed=Seabed(3e6, 3e5))

    def tb(p):
        lt = eqx.tree_at(lambda t: t.axial.ea, LT_BED, p[0] * 1e8)
        line = mj.Line(lt, 120.0, 6, mj.FixedEnd((0.0, 0.0, -50.0)),
                       mj.FixedEnd(jnp.stack([p[1], 0.0, -10.0])), element=HermiteElement())
        return solve_line_statics(line, env).tension_b

    assert_gradient_matches_central_differences(tb, jnp.array([10.0, 95.0]), (1e-3, 1e-3), 1e-4)
