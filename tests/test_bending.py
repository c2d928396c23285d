"""Bending stiffness EI of the linear element against beam theory.

The beam is MoorDyn's public ``BeamSimplySupported`` deck (tests/data/public): a
10 m pinned–pinned beam whose unstretched length equals its span, so it carries
its weight by bending and by the membrane tension its sag induces (a tie beam).
Beam theory for that case (small slopes, constant axial force N):

    EI·u'''' − N·u'' = q,   u = u'' = 0 at both ends,   N = EA/(2L)·∫u'² dx,

with the closed form u(x) = q/(N k²)·(cosh k(x − L/2)/cosh(kL/2) − 1) + q·x(L − x)/(2N),
k² = N/EI, and N from the scalar compatibility equation.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

import moorjax as mj
from moorjax.element.linear import bending_energy
from moorjax.io import build_scene, read_deck
from moorjax.statics.fem import solve_line_statics

PUBLIC = Path(__file__).parent / "data" / "public"
SOLVE = eqx.filter_jit(solve_line_statics)


def tie_beam(q, L, EI, EA):
    """(midspan deflection [m] downwards, axial force N [N]) of the pinned tie beam."""
    x = np.linspace(0.0, L, 20001)

    def u(N):
        k = np.sqrt(N / EI)
        return q / (N * k**2) * (np.cosh(k * (x - L / 2)) / np.cosh(k * L / 2) - 1) + q * x * (L - x) / (2 * N)

    def mismatch(N):
        du = np.gradient(u(N), x)
        return EA / (2 * L) * np.trapezoid(du**2, x) - N

    N = brentq(mismatch, 1e-9 * EA, 1e-1 * EA, xtol=1e-14 * EA, rtol=1e-14)
    return float(u(N)[len(x) // 2]), N


def deck_beam(segments):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = build_scene(read_deck(PUBLIC / "BeamSimplySupported.txt"), segments=segments)
    (line,) = scene.lines
    return line, scene.env


def midspan_sag(line, env):
    st = SOLVE(line, env)
    assert bool(st.converged)
    z_ends = float(line.end_a.position(0.0)[2])
    return z_ends - float(st.positions[line.n_segments // 2, 2]), st


def test_deck_ei_is_read():
    line, _ = deck_beam(4)
    assert float(line.line_type.ei) == 1e7
    assert not line.banded_jacobian  # bending couples second neighbours


@pytest.mark.slow
@pytest.mark.parametrize("ei", [1e7, 1e6])
def test_simply_supported_beam_against_beam_theory(ei):
    """Bending-dominated (EI = 1e7, the deck's) and mixed bending–membrane (1e6,
    kL ≈ 4) beams; the linear element converges at order 2 in the deflection."""
    errs = []
    for n in (20, 40):
        line, env = deck_beam(n)
        line = eqx.tree_at(lambda ln: ln.line_type.ei, line, jnp.asarray(ei))
        # the deck's beam is 10 m above the water: dry (m·g), as MoorDyn has it
        q = float(line.line_type.mass_per_length * env.g)
        sag_ref, N = tie_beam(q, float(line.length), ei, float(line.line_type.axial.nominal_ea()))
        sag, st = midspan_sag(line, env)
        errs.append(abs(sag / sag_ref - 1))
        # the end force: the membrane force N along the span and half the weight as shear
        assert abs(float(st.force_b[0]) / N + 1) < 5e-3 * (40 / n) ** 2 + 1e-3, (n, float(st.force_b[0]), N)
    assert errs[1] < 1e-3, errs
    if ei == 1e7:  # (at 1e6 the beam theory's own error, ~1e-4, spoils the ratio)
        order = np.log2(errs[0] / errs[1])
        assert 1.8 < order < 2.2, (errs, order)


def test_bending_forces_are_internal_and_vanish_when_straight():
    rng = np.random.default_rng(0)
    r = jnp.asarray(np.cumsum(rng.normal(size=(9, 3)), axis=0))
    f = -jax.grad(bending_energy, argnums=2)(2.0e5, 1.3, r)
    assert np.allclose(np.sum(f, axis=0), 0.0, atol=1e-8 * np.abs(f).max())
    assert np.allclose(np.sum(np.cross(r, f), axis=0), 0.0, atol=1e-8 * np.abs(f).max())
    straight = jnp.linspace(0.0, 1.0, 9)[:, None] * jnp.array([3.0, -1.0, 2.0])
    assert np.abs(-jax.grad(bending_energy, argnums=2)(2.0e5, 1.3, straight)).max() < 1e-6


def test_bending_energy_of_a_circle():
    """A polyline on a circle of radius R: energy → EI·L/(2R²)."""
    R, n, ei = 7.0, 200, 3.0e4
    phi = jnp.linspace(0.0, 1.5, n + 1)
    r = R * jnp.stack([jnp.cos(phi), jnp.sin(phi), 0 * phi], axis=-1)
    l = float(jnp.linalg.norm(r[1] - r[0]))
    exact = ei * (1.5 * R) / (2 * R**2)
    assert abs(float(bending_energy(ei, l, r)) / exact - 1) < 2 / n


def test_no_ei_leaves_the_line_unchanged():
    """EI absent: no bending term, banded Jacobian; EI = 0: the same forces."""
    env = mj.Environment(100.0)
    ends = mj.FixedEnd((0.0, 0.0, -50.0)), mj.FixedEnd((40.0, 0.0, -20.0))
    plain = mj.Line(mj.LineType(0.1, 20.0, 1e8), 60.0, 8, *ends)
    zero = mj.Line(mj.LineType(0.1, 20.0, 1e8, ei=0.0), 60.0, 8, *ends)
    assert plain.line_type.ei is None and plain.banded_jacobian and not zero.banded_jacobian
    rng = np.random.default_rng(1)
    r, _ = plain.nodes(0.0, plain.straight_state())
    r = r + jnp.asarray(rng.normal(size=r.shape))
    v = jnp.zeros_like(r)
    np.testing.assert_array_equal(plain.element.nodal_forces(plain, env, r, v),
                                  zero.element.nodal_forces(zero, env, r, v))


@pytest.mark.slow
def test_gradient_of_sag_wrt_ei_matches_finite_differences():
    """Implicit-function gradients through the dense static solve."""
    line, env = deck_beam(16)

    @eqx.filter_jit
    def sag(ei):
        ln = eqx.tree_at(lambda x: x.line_type.ei, line, ei)
        st = solve_line_statics(ln, env)
        return -st.positions[8, 2]

    ei = jnp.asarray(1e6)
    g = float(jax.grad(sag)(ei))
    h = 1e3
    fd = (float(sag(ei + h)) - float(sag(ei - h))) / (2 * h)
    assert g < 0 and abs(g / fd - 1) < 1e-5, (g, fd)


@pytest.mark.slow
def test_beam_held_from_statics_stays_in_equilibrium_in_dynamics():
    """A line with EI in the dynamics driver (dense Newton: bending couples second
    neighbours): started from its static state with the ends held, it stays there."""
    from moorjax.dynamics.simulate import simulate

    line, env = deck_beam(10)
    scene = mj.Scene((line,), env)
    res = simulate(scene, 0.5, dt_out=0.1)
    tb = np.asarray(res.tension_b[:, 0])
    assert bool(res.succeeded())
    assert np.ptp(tb) < 1e-6 * tb.mean(), tb


def test_negative_or_nonfinite_ei_is_refused():
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="bending stiffness EI"):
            mj.LineType(0.1, 20.0, 1e8, ei=bad)
