"""Natural frequencies: taut-string and taut-rod modes, a plucked line in time,
and the first symmetric in-plane mode of a sagging cable (Irvine & Caughey 1974).

Method for the eigenvalue checks: the vector field is linearised about the static
equilibrium with ``jax.jacfwd`` (no drag, no internal damping, no seabed, so the
linearisation is the undamped ``ÿ = −M⁻¹K y``) and the eigenvalues of ``−∂a/∂r``
are ω². Modes are told apart by the direction of their eigenvectors.

One jitted Jacobian (:func:`_jacobian`) serves every 60-segment scene here: the
taut line and the sagging cable have the same structure (added mass, no drag, no
seabed, fixed ends), so it compiles once per mass treatment.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

import moorjax as mj
from moorjax.dynamics import simulate
from moorjax.dynamics.vector_field import pack, vector_field
from moorjax.element import ConsistentMass, LinearElement, NodalMass
from moorjax.statics import solve_line_statics

RHO, G = 1025.0, 9.80665
D = 0.1
AREA = np.pi * D**2 / 4  # [m²]
N_MODES = 60  # segments of the eigenvalue scenes

# Taut line: mass per length = ρA, so the wet weight (m − ρA)g is zero and the
# line is exactly straight between its ends at any inclination. Different normal
# and axial added-mass coefficients, so that confusing the two would be caught
# (the transverse and axial inertias then differ by 2ρA vs 1.5ρA: ~15 % in f).
M_TAUT = RHO * AREA  # [kg/m]
EA_TAUT = 1.0e6  # [N]
L0_TAUT = 100.0  # unstretched length [m]
STRAIN_TAUT = 0.01  # pretension T = EA·ε = 10 kN
CA_N, CA_AX = 1.0, 0.5
# a generic direction, so that the added-mass tensor must follow the tangent
TANGENT = np.array([2.0, 1.0, 2.0]) / 3.0
NORMAL = np.array([1.0, 0.0, -1.0]) / np.sqrt(2.0)  # ⟂ TANGENT
END_A = np.array([0.0, 0.0, -200.0])


@eqx.filter_jit
def _jacobian(scene, q):
    """Jacobian of the (only) line's vector field w.r.t. its state (n−1, 6, n−1, 6)."""
    return jax.jacfwd(lambda z: vector_field(0.0, (z,), scene)[0])(q)


def _modes(scene, state):
    """Natural frequencies [Hz] (ascending) and mode shapes (k, n−1, 3) about ``state``."""
    q = pack([state])[0]
    n = q.shape[0]
    jac = np.asarray(_jacobian(scene, q)).reshape(6 * n, 6 * n)
    ir = np.array([6 * i + k for i in range(n) for k in range(3)])
    iv = ir + 3
    # first-order form of an undamped second-order system: ṙ = v exactly, and no
    # velocity dependence of the accelerations (drag and damping are absent)
    np.testing.assert_array_equal(jac[np.ix_(ir, iv)], np.eye(3 * n))
    np.testing.assert_array_equal(jac[np.ix_(ir, ir)], 0.0)
    np.testing.assert_array_equal(jac[np.ix_(iv, iv)], 0.0)
    omega2, vec = np.linalg.eig(-jac[np.ix_(iv, ir)])
    # M⁻¹K of a conservative system about a stable equilibrium: real, positive ω²
    assert np.max(np.abs(omega2.imag)) < 1e-8 * np.max(np.abs(omega2.real))
    assert np.min(omega2.real) > 0
    order = np.argsort(omega2.real)
    freq = np.sqrt(omega2.real[order]) / (2 * np.pi)
    shapes = vec.real[:, order].T.reshape(-1, n, 3)
    return freq, shapes


def taut_scene(n, mass=None):
    lt = mj.LineType(D, M_TAUT, EA_TAUT, 0.0, None, mj.AddedMass(CA_N, CA_AX))
    env = mj.Environment(500.0, RHO, G)  # no seabed, no current
    end_b = END_A + L0_TAUT * (1 + STRAIN_TAUT) * TANGENT
    element = LinearElement(mass=mass if mass is not None else NodalMass())
    line = mj.Line(lt, L0_TAUT, n, mj.FixedEnd(END_A), mj.FixedEnd(end_b), element=element)
    return mj.Scene([line], env)


def taut_frequencies(n_modes=3):
    """Continuum taut-string and taut-rod frequencies [Hz] of modes 1..n_modes.

    Stretched length L = L0(1 + ε), pretension T = EA·ε. Transverse:
    f_n = n/(2L)·√(T/m_t) with m_t the transverse inertia per stretched length,
    m/(1+ε) + ρA·Ca_n; written with totals, f_n = (n/2)·√(T/(L·M_t)),
    M_t = m·L0 + ρA·Ca_n·L (the model puts added mass on the stretched, i.e.
    displaced, length). Axial (a rod of stiffness EA/L0 and mass M_a):
    f_n = (n/2)·√(EA/(L0·M_a)), M_a = m·L0 + ρA·Ca_ax·L — for ε → 0 the README's
    n/(2L)·√(EA/m_a). ε = 1 % changes these by < 0.5 %, but we keep it exact.
    """
    k = np.arange(1, n_modes + 1)
    length = L0_TAUT * (1 + STRAIN_TAUT)
    tension = EA_TAUT * STRAIN_TAUT
    m_t = M_TAUT * L0_TAUT + RHO * AREA * CA_N * length
    m_a = M_TAUT * L0_TAUT + RHO * AREA * CA_AX * length
    return k / 2 * np.sqrt(tension / (length * m_t)), k / 2 * np.sqrt(EA_TAUT / (L0_TAUT * m_a))


@pytest.mark.parametrize("mass", [NodalMass(), ConsistentMass()], ids=["nodal", "consistent"])
def test_taut_line_transverse_and_axial_modes(mass):
    scene = taut_scene(N_MODES, mass)
    state = scene.lines[0].straight_state()
    # the straight line is the equilibrium (zero wet weight): residual accelerations
    # are round-off (10 kN tension on ~13 kg nodes)
    acc = vector_field(0.0, pack([state]), scene)[0][:, 3:]
    assert float(jnp.max(jnp.abs(acc))) < 1e-6

    freq, shapes = _modes(scene, state)
    axial_fraction = np.sum((shapes @ TANGENT) ** 2, axis=1) / np.sum(shapes**2, axis=(1, 2))
    # every mode is purely transverse or purely axial (linearised straight line)
    assert np.all((axial_fraction < 1e-9) | (axial_fraction > 1 - 1e-9))
    f_tr = freq[axial_fraction < 0.5]
    f_ax = freq[axial_fraction > 0.5]
    n_free = N_MODES - 1
    assert len(f_tr) == 2 * n_free and len(f_ax) == n_free
    # transverse modes come in degenerate pairs (two transverse directions)
    np.testing.assert_allclose(f_tr[0::2], f_tr[1::2], rtol=1e-9)

    ft_exact, fa_exact = taut_frequencies(3)
    err_tr = f_tr[0:6:2] / ft_exact - 1
    err_ax = f_ax[:3] / fa_exact - 1
    # Requirement: first three modes within 0.5 %. The discretisation error of a
    # lumped (nodal) chain is −(nπ/N)²/24 (−0.10 % for mode 3 at N = 60); the
    # consistent mass errs the other way by about +(nπ/N)²/24.
    assert np.all(np.abs(err_tr) < 5e-3), err_tr
    assert np.all(np.abs(err_ax) < 5e-3), err_ax

    # Stronger: the measured frequencies are exactly those of the discrete chain
    # (masses μ, springs T/ℓ or EA/l), so the whole deviation is discretisation.
    theta = np.arange(1, 4) * np.pi / N_MODES
    if isinstance(mass, NodalMass):
        dispersion = np.sin(theta / 2) / (theta / 2)  # ω_n = 2√(k/μ)·sin(nπ/2N)
    else:  # μ/6·(4 + 2cos θ) against 2k(1 − cos θ)
        dispersion = np.sqrt(6 * (1 - np.cos(theta)) / (2 + np.cos(theta))) / theta
    np.testing.assert_allclose(f_tr[0:6:2], ft_exact * dispersion, rtol=1e-8)
    np.testing.assert_allclose(f_ax[:3], fa_exact * dispersion, rtol=1e-8)


@pytest.mark.slow
def test_plucked_taut_line_period():
    """Release the line from its first transverse mode shape: the period of a node's
    transverse motion is the analytic 1/f_1 within 0.5 %.

    N = 20 (lumped-mass error of mode 1: (π/20)²/24 = 0.10 %). The amplitude
    (0.1 m on 101 m) raises the mean tension by EA·(πa/2L)² ≈ 0.025 %, i.e. the
    frequency by ~0.012 %: negligible. Tolerances 1e-8 make the time error tiny.
    """
    n = 20
    scene = taut_scene(n)
    st = scene.lines[0].straight_state()
    s = np.arange(1, n)[:, None] / n
    amp = 0.1
    r0 = np.asarray(st.r) + amp * np.sin(np.pi * s) * NORMAL
    init = (mj.LineState(r=jnp.asarray(r0), v=jnp.zeros_like(st.v)),)
    period = 1.0 / taut_frequencies(1)[0][0]  # 8.085 s
    n_periods = 5
    res = simulate(
        scene, n_periods * period, dt_out=period / 100, init=init, save_nodes=True,
        rtol=1e-8, atol=1e-8, atol_velocity=1e-8,
    )
    ts = np.asarray(res.ts)  # from t = 0, the initial state
    mid = np.asarray(res.positions[0])[:, n // 2]
    y = (mid - END_A) @ NORMAL
    i = np.flatnonzero(np.sign(y[:-1]) != np.sign(y[1:]))
    # linear interpolation of the crossings: the sine is straight at a zero crossing
    crossings = ts[i] - y[i] * (ts[i + 1] - ts[i]) / (y[i + 1] - y[i])
    assert len(crossings) == 2 * n_periods
    measured = 2 * (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    err = measured / period - 1  # measured: +0.094 % (the lumped-mass +0.10 %)
    assert abs(err) < 5e-3, err
    # each half period alike (no beating with other modes), and undamped: the
    # amplitude after five periods is the initial one (within 1 %)
    np.testing.assert_allclose(2 * np.diff(crossings), measured, rtol=1e-3)
    assert np.max(np.abs(y[ts > (n_periods - 1) * period])) == pytest.approx(amp, rel=1e-2)


# ------------------------------------------------------------------ sagging cable

# A shallow cable hanging between two points at the same height, 100 m apart:
# sag/span ≈ 0.054 (< 1/8), Irvine's λ² ≈ 67 (well above the crossover 4π²,
# where the symmetric mode has overtaken the antisymmetric one).
SPAN = 100.0
M_SAG, EA_SAG, L0_SAG = 20.0, 1.0e7, 100.5  # [kg/m], [N], [m]
CA_N_SAG = 1.0  # normal added mass only (Irvine's inertia is the normal one)


def _irvine_symmetric(lam2):
    """Root ω̄ of tan(ω̄/2) = ω̄/2 − (4/λ²)(ω̄/2)³ on the first branch (π < ω̄ < 3π)."""
    def f(x):
        return np.tan(x) - x + 4.0 / lam2 * x**3

    return 2.0 * brentq(f, np.pi / 2 + 1e-9, 3 * np.pi / 2 - 1e-9)


def test_sagging_cable_first_symmetric_in_plane_mode_irvine():
    """Irvine & Caughey (1974), *The linear theory of free vibrations of a
    suspended cable*: the symmetric in-plane modes of a shallow cable obey
    tan(ω̄/2) = ω̄/2 − (4/λ²)(ω̄/2)³ with ω̄ = ωL/√(H/m) and
    λ² = (wL/H)²·L/(H·L_e/EA), L_e ≈ L(1 + 8(d/L)²).

    Here L is the span, H the horizontal tension (from our statics), d the sag,
    w the weight per length that shapes the cable — the *wet* weight (m − ρA)g —
    and m the inertia per length for in-plane motion, which is normal to the
    cable: dry mass plus normal added mass, m + ρA·Ca_n. (Weight and inertia
    differ here by 2.6×, so mixing them up fails the test.)

    Tolerance 3 %: Irvine's theory assumes a parabolic profile, ds ≈ dx and no
    longitudinal inertia; the neglected horizontal inertia is of order
    (slope)² ~ (4d/L)² ≈ 5 % at the ends (its first antisymmetric mode, exactly
    2π in the theory, comes out 1.2 % lower here). Discretisation error
    (ω̄/N)²/24 ≈ 0.06 %. Measured: 0.05 %. The check still discriminates: the
    taut-string value π, the antisymmetric 2π and the inextensible limit 8.99
    are 58 %, 16 % and 21 % away from ω̄ ≈ 7.44.
    """
    lt = mj.LineType(D, M_SAG, EA_SAG, 0.0, None, mj.AddedMass(CA_N_SAG, 0.0))
    env = mj.Environment(500.0, RHO, G)
    z = -100.0
    line = mj.Line(lt, L0_SAG, N_MODES, mj.FixedEnd([0.0, 0.0, z]), mj.FixedEnd([SPAN, 0.0, z]))
    scene = mj.Scene([line], env)
    st = solve_line_statics(line, env)

    r = np.asarray(st.positions)
    sag = z - r[:, 2].min()
    assert 0.03 < sag / SPAN < 1 / 8  # shallow, as the theory needs
    chord = np.diff(r, axis=0)
    h_all = np.asarray(st.tensions) * chord[:, 0] / np.linalg.norm(chord, axis=1)
    H = float(np.mean(h_all))
    np.testing.assert_allclose(h_all, H, rtol=1e-8)  # no drag/seabed: H is uniform
    w = float(lt.wet_weight(RHO, G))
    m_inertia = M_SAG + RHO * AREA * CA_N_SAG
    l_e = SPAN * (1 + 8 * (sag / SPAN) ** 2)
    lam2 = (w * SPAN / H) ** 2 * SPAN / (H * l_e / EA_SAG)
    assert 30 < lam2 < 100, lam2  # measured 67.2
    wbar_irvine = _irvine_symmetric(lam2)  # 7.442

    freq, shapes = _modes(scene, st.state())
    wbar = 2 * np.pi * freq * SPAN / np.sqrt(H / m_inertia)
    out_of_plane = np.sum(shapes[:, :, 1] ** 2, axis=1) / np.sum(shapes**2, axis=(1, 2))
    assert np.all((out_of_plane < 1e-9) | (out_of_plane > 1 - 1e-9))
    in_plane = out_of_plane < 0.5
    vz = shapes[:, :, 2]
    scale = np.max(np.abs(vz), axis=1)
    symmetric = np.max(np.abs(vz - vz[:, ::-1]), axis=1) < 1e-6 * scale
    antisymmetric = np.max(np.abs(vz + vz[:, ::-1]), axis=1) < 1e-6 * scale

    first_sym = wbar[in_plane & symmetric][0]
    first_anti = wbar[in_plane & antisymmetric][0]
    first_out = wbar[~in_plane][0]
    assert first_sym == pytest.approx(wbar_irvine, rel=0.03), (first_sym, wbar_irvine)
    # companions from the same theory: antisymmetric in-plane 2π, out-of-plane π
    assert first_anti == pytest.approx(2 * np.pi, rel=0.03)
    assert first_out == pytest.approx(np.pi, rel=0.01)
    # past the crossover the symmetric mode lies above the antisymmetric one
    assert first_anti < first_sym
