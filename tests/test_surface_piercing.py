"""Lines that reach above the water surface: buoyant only where they are wet.

MoorDyn v2 scales a line element's buoyancy, drag and added mass by the fraction
of its length under the free surface (``Line::calcSubSeg``, ``source/Line.cpp``);
the linear element does the same (:func:`moorjax.element.linear.submerged_fraction`).
The oracle is the continuum: a chain hung between two points 2 m above still
water dips 10 m into it, and its exact (extensible) equilibrium weighs m·g per
metre in air and (m − ρA)·g in water, switching where the line crosses z = 0.
It is found here by shooting on the cable ODE with the crossings located as
events (scipy), independently of moorjax.

``tests/data/surface_dip.dat`` is that line as a MoorDyn deck (16 kg/m, d = 0.1 m,
so water halves its weight; EA = 1e8 N; 30 m between points 20 m apart at
z = +2 m). MoorDyn 2.7.2 does not settle it (the dry part has no drag: after
61 s it still moves 1 cm/s); its state then is H = 484.39 N, V = 1339.26 N,
lowest node −8.027 m, against moorjax's 486.54 N, 1340.62 N, −8.032 m
(40 segments; continuum 486.473 N, 1340.610 N).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

from moorjax.element.linear import submerged_fraction
from moorjax.io import build_scene, read_deck
from moorjax.statics.fem import solve_line_statics

DECK = Path(__file__).parent / "data" / "surface_dip.dat"
RHO, G = 1025.0, 9.80665
MASS, AREA, EA, LENGTH = 16.0, np.pi * 0.05**2, 1.0e8, 30.0
END_A, END_B = np.array([-10.0, 2.0]), np.array([10.0, 2.0])


def continuum(wet_weight_everywhere=False):
    """(H, V_A) [N] of the exact extensible cable whose weight per unstretched metre
    is m·g above z = 0 and (m − ρA)·g below it (or the wet weight everywhere)."""
    w_dry, w_wet = MASS * G, (MASS - RHO * AREA) * G
    if wet_weight_everywhere:
        w_dry = w_wet

    def shoot(p):
        h, va = p

        def rhs(s, y, w):
            t = np.hypot(h, y[2])
            return [(1 + t / EA) * h / t, (1 + t / EA) * y[2] / t, w]

        s, y, wet = 0.0, np.array([END_A[0], END_A[1], va]), False
        for _ in range(10):
            def cross(s, y, w):
                return y[1]

            # the next crossing: downwards when dry, upwards when wet
            cross.terminal, cross.direction = True, (1.0 if wet else -1.0)
            sol = solve_ivp(rhs, (s, LENGTH), y, args=(w_wet if wet else w_dry,),
                            events=cross, rtol=1e-12, atol=1e-12)
            s, y = sol.t[-1], sol.y[:, -1]
            if sol.status != 1:
                return y[:2] - END_B
            wet = not wet
        raise RuntimeError("too many crossings")

    p = fsolve(shoot, (480.0, -1300.0), xtol=1e-13)
    assert np.abs(shoot(p)).max() < 1e-9
    return p


def deck_line(n):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = build_scene(read_deck(DECK), segments=n)
    (line,) = scene.lines
    return line, scene.env


def test_submerged_fraction_follows_moordyn_and_has_derivatives():
    h = jnp.array([-2.0, -1.0, 1.0, 3.0, 3.0, 0.0, 0.0, -0.5])
    f = submerged_fraction(h)
    # below; crossing at mid-element; above; above; touching the surface from
    # above (dry); lying in it (1/2, as MoorDyn); touching it from below (wet)
    np.testing.assert_allclose(f, [1.0, 0.5, 0.0, 0.0, 0.0, 0.5, 1.0], atol=1e-15)
    jac = np.asarray(jax.jacfwd(submerged_fraction)(h))
    assert np.all(np.isfinite(jac))
    # F = −h_a/(h_b − h_a) across: ∂F/∂h_a = −h_b/(h_b − h_a)², ∂F/∂h_b = h_a/(h_b − h_a)²
    np.testing.assert_allclose(jac[1, 1:3], [-0.25, -0.25])
    assert np.all(jac[[0, 2, 3]] == 0.0)


def test_forces_of_a_line_under_water_are_unchanged():
    """Fully under water the forces are the wet weight w·l per node to the last bit
    (the buoyancy lost above the surface is exactly zero)."""
    line, env = deck_line(10)
    r = np.column_stack([np.linspace(-10, 10, 11), np.zeros(11), np.full(11, -5.0)])
    r[:, 0] *= 1.00001  # a taut straight line, no drag (at rest)
    force = np.asarray(line.element.nodal_forces(line, env, jnp.asarray(r), jnp.zeros_like(r)))
    w = (MASS - RHO * AREA) * G
    node_len = np.full(11, 3.0)
    node_len[[0, -1]] = 1.5
    tension = np.asarray(line.element.segment_tensions(line, jnp.asarray(r), jnp.zeros_like(r)))
    expect = np.zeros((11, 3))
    expect[:-1, 0] += tension
    expect[1:, 0] -= tension
    expect[:, 2] = -w * node_len
    np.testing.assert_array_equal(force[:, 2], expect[:, 2])
    np.testing.assert_allclose(force, expect, rtol=1e-14, atol=1e-9)


@pytest.mark.parametrize("n", [40, 80])
def test_chain_dipping_into_the_water_matches_the_continuum(n):
    """Measured: 40 segments H 486.5356 N (1.3e-4 from the continuum's 486.4728),
    V 1340.6155 N (3.7e-6 from 1340.6105); 80 segments 6.7e-5 and 6.1e-6 (first
    order in H: the weight jumps inside the element that crosses the surface and
    its nodes lump it). With the wet weight everywhere (no partial submergence)
    the continuum's V is 12.8 % lower (H 1.2 %): the test tells the two apart."""
    h, va = continuum()
    line, env = deck_line(n)
    st = solve_line_statics(line, env)
    assert bool(st.converged)
    fa = np.asarray(st.force_a)
    err_h, err_v = fa[0] / h - 1, fa[2] / va - 1
    print(f"N = {n}: H {fa[0]:.4f} (continuum {h:.4f}, {err_h:.2e}), V {fa[2]:.4f} ({va:.4f}, {err_v:.2e})")
    assert abs(err_h) < 3e-4 and abs(err_v) < 3e-5, (err_h, err_v)
    _, va_wet = continuum(wet_weight_everywhere=True)
    assert abs(va_wet / va - 1) > 1000 * abs(err_v)
    # the line crosses the surface and the catenary method declines it
    z = np.asarray(st.positions)[:, 2]
    assert z.max() > 0 > z.min()
    auto = solve_line_statics(line, env, method="auto")
    np.testing.assert_allclose(np.asarray(auto.force_a), fa, rtol=1e-9)
    # the dynamics' forces hold it at rest where the statics put it
    r = jnp.asarray(st.positions)
    acc = line.element.accelerations(line, env, 0.0, r, jnp.zeros_like(r))
    assert float(jnp.abs(acc).max()) < 1e-6, float(jnp.abs(acc).max())
