"""Clamped ends (:class:`~moorjax.ClampedEnd`): cantilevers against beam theory and the elastica.

A horizontal beam of length L clamped at end A and free at end B, loaded by its
wet weight q [N/m] and a tip load P [N] (downwards). Beam theory (small
deflection): tip deflection qL⁴/(8EI) + PL³/(3EI), tip slope qL³/(6EI) +
PL²/(2EI). For large deflection the inextensible elastica,

    EI·θ'' = −(q·(L − s) + P)·cos θ,   θ(0) = 0,   θ'(L) = 0,

solved by collocation (``scipy.integrate.solve_bvp``; EA = 1.5e9 N stretches
the beam by under 1e-6, far below the tolerances here).

moorjax lines have two held ends, so the free tip is found by shooting: end B
is a fixed point moved (Newton, finite-difference Jacobian, load stepping for
the large deflection) until the line's force on it balances the tip load. The
clamp is the element's: the Hermite element fixes the direction of the end
slope (its length stays free), the linear element adds MoorDyn's end curvature
(the turning from the clamp's direction to the first segment over half a
segment) to the beam energy.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_bvp

import moorjax as mj
from moorjax.element import HermiteElement, LinearElement
from moorjax.element.hermite import HermiteDofs, static_residual
from moorjax.model.line import LineState
from moorjax.statics.fem import solve_line_statics
from moorjax.statics.hermite import hermite_equilibrium

L, EI, EA = 10.0, 1.0e7, 1.5e9
ENV = mj.Environment(100.0)
CLAMP = mj.ClampedEnd((0.0, 0.0, -50.0), (1.0, 0.0, 0.0))


def line_type(q, ea=EA):
    """A 0.05 m beam of wet weight q [N/m] with ea [N] (in tension and compression) and EI."""
    area = np.pi * 0.05**2 / 4
    return mj.LineType(0.05, q / ENV.g + ENV.rho * area, mj.Bilateral(mj.LinearEA(ea)), ei=EI)


def inextensible(axial, m):
    return 0.0, 1.0


def hermite_rod(axial, m):
    """The Hermite element's continuum: bending energy ½·EI·κ² per unstretched
    length with κ the curvature of the stretched curve, θ'/(1 + ε); then
    θ' = m·(1 + ε)²/EI and EA·ε − m²·(1 + ε)/EI = the axial force."""
    eps = (axial + m**2 / EI) / (EA - m**2 / EI)
    return eps, (1.0 + eps) ** 2


def linear_rod(axial, m):
    """The linear element's continuum: κ = θ' per unstretched length (its
    turning angle over the unstretched segment); θ' = m/EI, EA·ε = the axial force."""
    return axial / EA, 1.0


def elastica(q, P, rod=inextensible):
    """(tip x − x_A, tip z − z_A [m], tip angle [rad]) of the elastica: moment m [N·m] and angle θ
    below the horizontal along the unstretched arc s, with the load beyond s,
    W = q·(L − s) + P, on the tangent (axial force W·sin θ) and across it:

        m' = −(1 + ε)·W·cos θ,   θ' = m·c/EI,   θ(0) = 0,   m(L) = 0,

    ``rod(axial, m) -> (ε, c)`` the extensible model (:func:`inextensible`,
    :func:`hermite_rod`, :func:`linear_rod`)."""
    def f(s, y):
        th, m = y[0], y[1]
        w = q * (L - s) + P
        eps, c = rod(w * np.sin(th), m)
        return np.vstack([m * c / EI, -(1.0 + eps) * w * np.cos(th), (1.0 + eps) * np.cos(th),
                          -(1.0 + eps) * np.sin(th)])

    s = np.linspace(0.0, L, 401)
    y0 = np.zeros((4, s.size))
    y0[2] = s
    sol = solve_bvp(f, lambda a, b: np.array([a[0], b[1], a[2], a[3]]), s, y0, tol=1e-10,
                    max_nodes=100000)
    assert sol.success, sol.message
    return float(sol.sol(L)[2]), float(sol.sol(L)[3]), float(sol.sol(L)[0])


def _solver(n, q, element, ea):
    """A jitted ``(tip, init) -> (force on the tip [N], state, largest free-node
    force imbalance [N])`` for the cantilever."""
    lt = line_type(q, ea)

    def line_to(tip):
        return mj.Line(lt, L, n, CLAMP, mj.FixedEnd(tip), element=element)

    if isinstance(element, HermiteElement):
        def solve(tip, init):
            line = line_to(tip)
            # the start: the last state, bent by the tip's move (linearly along the beam)
            move = tip - init.r[-1]
            s = jnp.linspace(0.0, 1.0, n + 1)[:, None]
            init = HermiteDofs(r=init.r + s * move, dr=init.dr + move / L, lam=init.lam)
            dofs, _ = hermite_equilibrium(line, ENV, 0.0, init)
            force, _, _ = static_residual(line, ENV, dofs)
            return force[-1], dofs, jnp.max(jnp.abs(force[1:-1]))
    else:
        def solve(tip, init):
            st = solve_line_statics(line_to(tip), ENV, init=init, throw=False)
            free = st.positions[1:-1]
            return st.force_b, LineState(r=free, v=jnp.zeros_like(free)), st.max_residual
    return eqx.filter_jit(solve)


def cantilever(n, q, P, element=None, load_steps=1, ea=EA, tol=1e-11):
    """Tip position (3,) [m] and the solver's state of the clamped beam whose tip
    carries P [N] downwards: Newton on the tip's force balance."""
    element = LinearElement() if element is None else element
    tip = jnp.array([L, 0.0, -50.0])
    state = None
    if isinstance(element, HermiteElement):  # start straight, unloaded (not the catenary)
        s = jnp.linspace(0.0, L, n + 1)[:, None]
        state = HermiteDofs(r=CLAMP.point + s * CLAMP.unit, dr=jnp.broadcast_to(CLAMP.unit, (n + 1, 3)),
                            lam=jnp.zeros(2 * n + 1))
    for k in range(1, load_steps + 1):
        frac = k / load_steps
        solve = _solver(n, q * frac, element, ea)
        load = jnp.array([0.0, 0.0, -P * frac])
        if k == 1:  # beam theory's tip, on the circle of the beam's length
            dz = min((q * L**4 / (8 * EI) + P * L**3 / (3 * EI)) * frac, 0.5 * L)
            tip = CLAMP.point + jnp.array([np.sqrt(L**2 - dz**2), 0.0, -dz])
        for _ in range(30):
            f, state, res = solve(tip, state)
            assert float(res) < 1e-6 * q * L + 1e-6 * P, float(res)
            r = np.asarray(f + load)
            jac = np.empty((3, 3))
            for i, h in enumerate((1e-7 * EA / ea, 1e-5, 1e-5)):
                jac[:, i] = (np.asarray(solve(tip.at[i].add(h), state)[0]) - np.asarray(f)) / h
            step = -np.linalg.solve(jac, r)
            tip = tip + step
            chord = tip - CLAMP.point  # a bent beam's chord is shorter than the beam
            tip = CLAMP.point + chord * jnp.minimum(1.0, L / jnp.linalg.norm(chord))
            if np.max(np.abs(step)) < tol * L:
                break
    return np.asarray(tip) - np.asarray(CLAMP.point), state


def tip_slope(state):
    """The tip's angle below the horizontal [rad] from the Hermite slope there."""
    d = np.asarray(state.dr[-1])
    return float(np.arctan2(-d[2], d[0]))


@pytest.mark.parametrize("q, P, tol", [(981.0, 0.0, 3e-7), (0.0, 1.0e4, 1e-8)])
def test_hermite_cantilever_against_beam_theory(q, P, tol):
    """Two Hermite elements, small deflection (tip 1.2 % and 3.3 % of L): tip
    deflection and slope within 2e-3 and 3e-3 of beam theory (its geometric
    nonlinearity: the elastica's tip is 1.2e-4 and 1.1e-3 below it), and close
    to the elastica of the same extensible rod: under its weight (a quartic
    deflection) 2.0e-7 (4 elements 3.7e-8, 8: 6.5e-9), under the tip load (a
    cubic, which the element holds exactly) 2e-9. ~7 s each."""
    d, state = cantilever(2, q, P, HermiteElement())
    w, slope = q * L**4 / (8 * EI) + P * L**3 / (3 * EI), q * L**3 / (6 * EI) + P * L**2 / (2 * EI)
    x, z, th = elastica(q, P, hermite_rod)
    assert abs(-d[2] / w - 1) < 2e-3 and abs(tip_slope(state) / slope - 1) < 3e-3
    assert abs(d[2] / z - 1) < tol, d[2] / z - 1
    assert abs(tip_slope(state) / th - 1) < 10 * tol, tip_slope(state) / th - 1
    assert abs(d[0] - x) < tol * L and abs(d[1]) < 1e-12


def test_linear_cantilever_converges_at_order_2():
    """The linear element with MoorDyn's end curvature: tip deflection errors
    1.0e-2 and 2.5e-3 at 10 and 20 segments against its own rod's elastica
    (1.0/n², order 2.00; 40 segments: 6.25e-4). ~50 s."""
    x, z, _ = elastica(981.0, 0.0, linear_rod)
    errs = [abs(cantilever(n, 981.0, 0.0)[0][2] / z - 1) for n in (10, 20)]
    order = np.log2(errs[0] / errs[1])
    assert 0.9e-2 < errs[0] < 1.1e-2 and 1.95 < order < 2.05, (errs, order)


@pytest.mark.slow
def test_large_deflection_cantilever_against_the_elastica():
    """qL³/EI = 24 (beam theory's tip 3.0 m, 30 % of L; the elastica's 2.808 m,
    its tip pulled in 0.462 m): 4 Hermite elements within 2e-5 of the
    extensible elastica (measured 1.35e-5; 2: 1.7e-5, 8: 1.1e-6). ~6–35 s. (The
    linear element: 7.9e-3, 1.9e-3, 4.7e-4 at 10, 20, 40 segments, 70–120 s each.)"""
    q = 2.4e4
    d, _ = cantilever(4, q, 0.0, HermiteElement(), load_steps=6)
    x, z, _ = elastica(q, 0.0, hermite_rod)
    assert abs(d[2] / z - 1) < 2e-5, d[2] / z - 1
    assert abs(d[0] / x - 1) < 2e-5, d[0] / x - 1
    assert d[2] / (-q * L**4 / (8 * EI)) < 0.95  # well outside beam theory


def propped(n, element, clamp_at_b=False):
    """A beam clamped at one end and pinned at the other, its span equal to its
    length, under q = 9.81 N/m (tie effect of the membrane force: ~1e-6)."""
    lt = line_type(9.81)
    far = (L, 0.0, -50.0)
    ends = (CLAMP, mj.FixedEnd(far))
    if clamp_at_b:  # the mirror image: pinned at x = 0, clamped at x = L facing −x
        ends = (mj.FixedEnd(CLAMP.point), mj.ClampedEnd(far, (-1.0, 0.0, 0.0)))
    line = mj.Line(lt, L, n, *ends, element=element)
    st = solve_line_statics(line, ENV)
    return np.asarray(st.positions), st


@pytest.mark.parametrize("element, n, tol", [(HermiteElement(), 4, 2e-4), (LinearElement(), 40, 4e-3)])
def test_propped_cantilever_clamped_at_either_end(element, n, tol):
    """Clamped–pinned: midspan deflection qL⁴/(192EI) (Hermite 4 elements,
    linear 40 segments); clamping end B instead of A gives the mirror image
    (the clamp's direction is the one the line leaves it in). ~20 s."""
    a, st_a = propped(n, element)
    b, st_b = propped(n, element, clamp_at_b=True)
    w = 9.81 * L**4 / (192 * EI)
    sag = -50.0 - a[n // 2, 2]
    assert abs(sag / w - 1) < tol, sag / w - 1
    mirrored = b[::-1].copy()
    mirrored[:, 0] = L - mirrored[:, 0]
    np.testing.assert_allclose(mirrored, a, rtol=0, atol=1e-10)
    # the clamp carries 5/8 of the weight, the pin 3/8 (the line pulls them down)
    for f in (st_a.force_a, st_b.force_b):
        assert abs(float(f[2]) / (9.81 * L) + 5 / 8) < 5e-3, float(f[2]) / (9.81 * L)


def test_clamp_needs_a_direction():
    with pytest.raises(ValueError, match="direction"):
        mj.ClampedEnd((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="clamp direction"):
        mj.ClampedEnd((0.0, 0.0, 0.0), (1.0, float("nan"), 0.0))
    np.testing.assert_allclose(mj.ClampedEnd((0.0, 0.0, 0.0), (3.0, 0.0, -4.0)).direction(0.0),
                               [0.6, 0.0, -0.8])


@pytest.mark.slow
@pytest.mark.parametrize("element, n", [(HermiteElement(), 4), (LinearElement(), 10)])
def test_clamped_beam_held_from_statics_stays_in_equilibrium_in_dynamics(element, n):
    """The clamp acts in the dynamics too (linear element: the end moment is a
    force on the first free node; Hermite: the clamped slope accelerates along
    the clamp's direction only): the propped cantilever started from its static
    state stays there (the clamp's force constant to 1e-6 and equal to the
    statics'). ~10–30 s each."""
    from moorjax.dynamics import simulate

    line = mj.Line(line_type(981.0), L, n, CLAMP, mj.FixedEnd((L, 0.0, -50.0)), element=element)
    res = simulate(mj.Scene((line,), ENV), 0.5, dt_out=0.1)
    fa = np.asarray(res.tension_a[:, 0])
    assert bool(res.succeeded())
    assert np.ptp(fa) < 1e-6 * fa.mean(), fa
    st = solve_line_statics(line, ENV)
    assert abs(fa.mean() / float(st.tension_a) - 1) < 1e-6, (fa.mean(), float(st.tension_a))


_MOORDYN_BEAM = """
import contextlib, io, json, moordyn
with contextlib.redirect_stdout(io.StringIO()):
    s = moordyn.Create({deck!r})
    moordyn.Init(s, [], [])
    ln = moordyn.GetLine(s, 1)
    tip = list(moordyn.GetLineNodePos(ln, moordyn.GetLineN(ln)))
    moordyn.Close(s)
print(json.dumps(tip))
"""


@pytest.mark.slow
def test_moordyn_cantilever_deck(tmp_path):
    """MoorDyn's public ``BeamCantilevered`` deck (tests/data/public): the same
    10 m beam (EI = 1e7 N·m², 981 N/m in air, 19 segments) clamped by a fixed
    rod, its tip a massless free point. MoorDyn's IC solve (400 s, error left
    6.7e-3 m/s²; its dynamics from there blow up at t = 0.65 s, the massless
    tip) puts the tip 0.123046 m down, +3.44e-3 off beam theory's 0.122625;
    moorjax's linear element at 19 segments 0.122950 (+2.65e-3, its 1.0/n²):
    7.9e-4 apart. (The deck reader refuses rods, so the beam is built here.)
    ~70 s."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    pytest.importorskip("moordyn")
    text = (Path(__file__).parent / "data" / "public" / "BeamCantilevered.txt").read_text()
    text = (text.replace("2             writeLog", "0             writeLog")
            .replace("40.0          TmaxIC", "400.0         TmaxIC")
            .replace("1e-5          threshIC", "1e-12         threshIC"))
    deck = tmp_path / "beam.txt"
    deck.write_text(text)
    run = subprocess.run([sys.executable, "-c", _MOORDYN_BEAM.format(deck=str(deck))],
                         capture_output=True, text=True, timeout=400, cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    tip = json.loads(run.stdout.strip().splitlines()[-1])
    md = 10.0 - tip[2]  # the deck's clamp is at z = 10 m
    w = 981.0 * L**4 / (8 * EI)
    ours = -cantilever(19, 981.0, 0.0)[0][2]
    assert abs(md / w - 1) < 5e-3 and abs(ours / w - 1) < 3e-3, (md, ours, w)
    assert abs(ours / md - 1) < 1.5e-3, (ours, md)
