"""Tests for moorjax.body.waves (Wu et al. Eq. 4, random seas, wave loads) and
moorjax.body.loads (wind, current, constant loads)."""

from __future__ import annotations

from importlib import resources

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import moorjax  # noqa: F401  (float64)
from moorjax.body.hydro import HydroCoefficients, drift_at, excitation_at, load_hydro
from moorjax.body.loads import (AIR_DENSITY, ConstantLoad, current_force, directional_load,
                                wind_force)
from moorjax.body.waves import (IrregularWave, WaveLoads, loads_for_wave, pm_spectrum,
                                regular_wave, wave_components, wave_loads)

BOX = str(resources.files("moorjax.examples").joinpath("data/wu_box_hydro.npz"))


@pytest.fixture(scope="module")
def box():
    return load_hydro(BOX)


def _moments(hs, tz, lo=1e-3, hi=1e4):
    w = np.geomspace(lo, hi, 400001)
    s = np.asarray(pm_spectrum(w, hs, tz))
    return np.trapezoid(s, w), np.trapezoid(w**2 * s, w)


def _record(wave, t_end, dt, chunk=4000):
    t = np.arange(0.0, t_end, dt)
    return t, np.concatenate([np.asarray(wave.elevation(t[i:i + chunk])) for i in range(0, t.size, chunk)])


# -- spectrum ------------------------------------------------------------------

@pytest.mark.parametrize("hs,tz", [(2.0, 8.0), (2.0, 60.0), (5.5, 11.0)])
def test_pm_spectrum_moments(hs, tz):
    """Eq. 4 has m0 = Hs²/16 and 2π√(m0/m2) = Tz."""
    m0, m2 = _moments(hs, tz)
    assert m0 == pytest.approx(hs**2 / 16, rel=1e-6)
    assert 2 * np.pi * np.sqrt(m0 / m2) == pytest.approx(tz, rel=1e-4)


def test_pm_spectrum_is_eq4_as_printed():
    hs, tz, w = 2.0, 8.0, np.array([0.3, 0.7, 1.5])
    eq4 = (1 / (2 * np.pi)) * hs**2 / (4 * np.pi * tz**4) * (2 * np.pi / w) ** 5 \
        * np.exp(-1 / (np.pi * tz**4) * (2 * np.pi / w) ** 4)
    np.testing.assert_allclose(pm_spectrum(w, hs, tz), eq4, rtol=1e-13)
    assert float(pm_spectrum(0.0, hs, tz)) == 0.0
    assert np.isfinite(jax.grad(lambda h: pm_spectrum(0.5, h, tz))(hs))
    with pytest.raises(ValueError, match="significant wave height Hs = -1.0 m must be > 0"):
        pm_spectrum(w, -1.0, tz)


# -- random components ---------------------------------------------------------

def test_components_are_reproducible_and_equal_area():
    a = wave_components(2.0, 8.0, 100, seed=7, omega_min=0.1, omega_max=3.0)
    b = wave_components(2.0, 8.0, 100, seed=7, omega_min=0.1, omega_max=3.0)
    c = wave_components(2.0, 8.0, 100, seed=8, omega_min=0.1, omega_max=3.0)
    np.testing.assert_array_equal(a.phase, b.phase)
    np.testing.assert_array_equal(a.omega, b.omega)
    assert not np.allclose(a.phase, c.phase)
    om = np.asarray(a.omega)
    assert np.all(np.diff(om) > 0) and om[0] >= 0.1 and om[-1] <= 3.0
    w = np.linspace(0.1, 3.0, 200001)
    m0_trunc = np.trapezoid(np.asarray(pm_spectrum(w, 2.0, 8.0)), w)
    assert float(a.variance()) == pytest.approx(m0_trunc, rel=1e-6)
    assert np.ptp(np.asarray(a.amplitude)) == 0.0


def test_realised_record_reproduces_hs_and_tz():
    """3 h of sea: Hs = 4·std(η) and Tz = duration / up-crossings within 5 %."""
    hs, tz, lo, hi = 2.0, 8.0, 0.05, 4.0
    wave = wave_components(hs, tz, 300, seed=1, omega_min=lo, omega_max=hi, heading=np.radians(60))
    t, eta = _record(wave, 3 * 3600.0, 0.1)
    w = np.linspace(lo, hi, 200001)
    s = np.asarray(pm_spectrum(w, hs, tz))
    tz_trunc = 2 * np.pi * np.sqrt(np.trapezoid(s, w) / np.trapezoid(w**2 * s, w))
    assert 4 * np.std(eta) == pytest.approx(hs, rel=0.05)
    up = np.count_nonzero((eta[:-1] < 0) & (eta[1:] >= 0))
    assert t[-1] / up == pytest.approx(tz_trunc, rel=0.05)
    assert tz_trunc == pytest.approx(tz, rel=0.03)


def test_component_validation():
    with pytest.raises(ValueError, match="omega_max = 0.1 rad/s must exceed omega_min = 0.2 rad/s"):
        wave_components(2.0, 8.0, 10, 0, omega_min=0.2, omega_max=0.1)
    with pytest.raises(ValueError, match="n = 0"):
        wave_components(2.0, 8.0, 0, 0)
    with pytest.raises(ValueError, match="wave component amplitude"):
        IrregularWave([0.5], [-1.0], [0.0])


# -- wave loads ----------------------------------------------------------------

def test_regular_wave_force_amplitude_and_phase(box):
    """One component: F_j(t) = a|X_j| cos(ωt + φ + arg X_j); drift mean a²D, at 2ω."""
    k, a, phi, beta = 20, 1.5, 0.4, np.radians(30.0)
    om = float(box.omega[k])
    ld = loads_for_wave(box, regular_wave(a, om, beta, phi))
    x = np.asarray(excitation_at(box, om, beta))
    t = np.linspace(0.0, 2 * np.pi / om, 2001)
    f = np.asarray(ld.first_order_force(t))
    for j in (0, 1, 2, 3, 4):
        assert np.abs(f[:, j]).max() == pytest.approx(a * np.abs(x[j]), rel=1e-5)
        np.testing.assert_allclose(f[:, j], a * np.abs(x[j]) * np.cos(om * t + phi + np.angle(x[j])),
                                   atol=1e-9 * a * np.abs(x).max())
    np.testing.assert_allclose(np.asarray(ld.wave.elevation(t)), a * np.cos(om * t + phi), atol=1e-12)
    d = np.asarray(drift_at(box, om, beta))
    sd = np.asarray(ld.drift_force(t))
    np.testing.assert_allclose(sd.mean(axis=0), a**2 * d, rtol=1e-3, atol=1e-6)
    np.testing.assert_allclose(sd[:, 0], 2 * a**2 * d[0] * np.cos(om * t + phi) ** 2, rtol=1e-10)
    np.testing.assert_allclose(np.asarray(ld.force(t)), f + sd, rtol=1e-12, atol=1e-6)


def test_slow_drift_mean(box):
    """Mean of Newman's slow drift = Σ a_k² D_k, exactly and over a 3 h record."""
    ld = wave_loads(box, hs=2.0, tz=8.0, heading=np.radians(60.0), n_components=200, seed=3)
    w = ld.wave
    d = np.asarray(drift_at(box, w.omega, w.heading))
    expected = np.sum(np.asarray(w.amplitude)[:, None] ** 2 * d, axis=0)
    np.testing.assert_allclose(np.asarray(ld.mean_drift()), expected, rtol=1e-12)
    assert expected[0] > 0 and expected[1] > 0
    t = np.arange(0.0, 3 * 3600.0, 0.5)
    sd = np.concatenate([np.asarray(ld.drift_force(t[i:i + 4000])) for i in range(0, t.size, 4000)])
    assert sd[:, 0].mean() == pytest.approx(expected[0], rel=0.05)
    assert sd[:, 1].mean() == pytest.approx(expected[1], rel=0.05)
    assert np.all(sd[:, 0] >= 0)  # D ≥ 0: 2(Σ a√D cos)² ≥ 0


def test_sign_preserving_drift(box):
    """Where D < 0 the product form keeps the mean Σ a²D (negative contributions)."""
    raw = {n: np.asarray(getattr(box, n)) for n in
           ("omega", "added_mass", "damping", "added_mass_inf", "headings", "excitation_re",
            "excitation_im", "drift", "hydrostatic", "rho", "g", "volume", "reference_point")}
    drift = raw["drift"].copy()
    drift[:, : drift.shape[1] // 2, 0] *= -5.0  # negative drift at low frequencies
    neg = HydroCoefficients(**{**raw, "drift": drift})
    ld = wave_loads(neg, hs=2.0, tz=8.0, heading=0.0, n_components=60, seed=5)
    d = np.asarray(drift_at(neg, ld.wave.omega, 0.0))[:, 0]
    assert d.min() < 0 < d.max()
    expected = np.sum(np.asarray(ld.wave.amplitude) ** 2 * d)
    assert float(ld.mean_drift()[0]) == pytest.approx(expected, rel=1e-12)
    t = np.arange(0.0, 6 * 3600.0, 0.5)
    sd = np.asarray(ld.drift_force(t))[:, 0]
    scale = np.sum(np.asarray(ld.wave.amplitude) ** 2 * np.abs(d))
    assert abs(sd.mean() - expected) < 0.05 * scale


def test_wave_loads_structure_and_tracing(box):
    ld = wave_loads(box, hs=2.0, tz=8.0, heading=np.radians(60.0), n_components=50, seed=0, drift=False)
    assert isinstance(ld, WaveLoads) and ld.drift is None
    assert float(ld.wave.omega.min()) >= float(box.omega[0])
    assert float(ld.wave.omega.max()) <= float(box.omega[-1])
    f = jax.jit(lambda m, t: m.force(t))(ld, 12.3)  # a pytree of arrays
    assert f.shape == (6,)
    np.testing.assert_allclose(np.asarray(f), np.asarray(ld.force(12.3)), rtol=1e-12)
    np.testing.assert_array_equal(np.asarray(ld.mean_drift()), np.zeros(6))
    g = jax.grad(lambda t: ld.force(t)[0])(5.0)
    assert np.isfinite(g)
    with pytest.raises(ValueError, match="outside the hydrodynamic table's headings"):
        wave_loads(box, hs=2.0, tz=8.0, heading=np.radians(270.0))
    with pytest.raises(ValueError, match="leave the hydrodynamic table's range"):
        wave_loads(box, hs=2.0, tz=8.0, heading=0.0, omega_max=3.0)


# -- steady loads --------------------------------------------------------------

def test_wind_and_current_forces():
    # Wu et al. Table 1: wind 13.8 m/s, current 4 m/s; a 45 m × 7.5 m freeboard, 45 m × 20 m draft
    fw = wind_force(13.8, c_h=1.0, c_s=1.0, area=45 * 7.5)
    assert float(fw) == pytest.approx(0.5 * AIR_DENSITY * 13.8**2 * 45 * 7.5)
    assert float(wind_force(13.8, 1.0, 1.0, 10.0, rho_air=1.0)) == pytest.approx(0.5 * 13.8**2 * 10.0)
    fc = current_force(4.0, cd=1.0, area=45 * 20)
    assert float(fc) == pytest.approx(0.5 * 1025 * 16 * 900)
    assert float(jax.grad(lambda u: current_force(u, 1.0, 900.0))(4.0)) == pytest.approx(1025 * 4 * 900)
    with pytest.raises(ValueError, match="wind speed = -1.0 m/s must be >= 0"):
        wind_force(-1.0, 1.0, 1.0, 10.0)
    with pytest.raises(ValueError, match="current area = -3.0 m² must be >= 0"):
        current_force(1.0, 1.0, -3.0)
    with pytest.raises(ValueError, match="windward area"):
        wind_force(1.0, 1.0, 1.0, -2.0)


def test_directional_and_constant_loads():
    f = directional_load(1000.0, np.radians(60.0))
    np.testing.assert_allclose(f, [500.0, 1000 * np.sqrt(3) / 2, 0, 0, 0, 0], atol=1e-9)
    fm = directional_load(1000.0, 0.0, point=(0.0, 2.0, 5.0))
    np.testing.assert_allclose(fm, [1000.0, 0, 0, 0, 5000.0, -2000.0], atol=1e-9)  # r × F
    ld = ConstantLoad(f + fm)
    np.testing.assert_allclose(jax.jit(lambda m, t: m.force(t))(ld, 3.0), f + fm)
    with pytest.raises(ValueError, match="load magnitude"):
        directional_load(-1.0, 0.0)
    with pytest.raises(ValueError, match=r"\(6,\) force/moment"):
        ConstantLoad(jnp.zeros(3))
