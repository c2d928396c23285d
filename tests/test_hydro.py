"""Tests for moorjax.body.hydro: the shipped Wu-box database (physics sanity),
file validation, interpolation, and the radiation state-space fit."""

from __future__ import annotations

from importlib import resources

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import moorjax  # noqa: F401  (float64)
from moorjax.body.hydro import (HydroCoefficients, RadiationStateSpace, drift_at, excitation_at,
                                fit_radiation, hydro_metadata, load_hydro, retardation_function,
                                save_hydro)

BOX = str(resources.files("moorjax.examples").joinpath("data/wu_box_hydro.npz"))
RHO, G = 1025.0, 9.81
MASS, INERTIA = 41512e3, np.array([4.5316e10, 4.2748e10, 4.8877e10])


@pytest.fixture(scope="module")
def box():
    return load_hydro(BOX)


@pytest.fixture(scope="module")
def fitted(box):
    return fit_radiation(box)


def _raw():
    with np.load(BOX) as data:
        return {k: np.array(data[k]) for k in data.files}


def _write(tmp_path, **changes):
    raw = _raw()
    raw.update(changes)
    path = tmp_path / "bad.npz"
    np.savez(path, **raw)
    return path


# -- the shipped file ----------------------------------------------------------

def test_shipped_file_shapes_and_metadata(box):
    k, h = box.n_frequencies, box.n_headings
    assert 30 <= k <= 60 and h == 13
    assert box.added_mass.shape == box.damping.shape == (k, 6, 6)
    assert box.excitation_re.shape == box.excitation_im.shape == box.drift.shape == (h, k, 6)
    assert float(box.omega[0]) == pytest.approx(0.05) and float(box.omega[-1]) == pytest.approx(2.0)
    assert np.degrees(np.asarray(box.headings)) == pytest.approx(np.arange(0, 181, 15))
    assert float(box.volume) == pytest.approx(45 * 45 * 20)
    assert np.asarray(box.reference_point) == pytest.approx([0.0, 0.0, -6.25])
    meta = hydro_metadata(BOX)
    assert meta["mass_kg"] == MASS and meta["water_depth_m"] == 80.0


def test_box_hydrostatics_and_natural_periods(box):
    c = np.asarray(box.hydrostatic)
    assert c[2, 2] == pytest.approx(RHO * G * 45 * 45)
    c44 = RHO * G * (45**4 / 12 + 40500 * -10.0) - MASS * G * -6.25  # ρg(I_wp + V z_B) − m g z_G
    assert c[3, 3] == pytest.approx(c44) and c[4, 4] == pytest.approx(c[3, 3])
    assert c44 == pytest.approx(RHO * G * 40500 * (-10.0 + 6.25 + 45**2 / (12 * 20)), rel=1e-4)  # ρgV·GM
    om, am = np.asarray(box.omega), np.asarray(box.added_mass)

    def period(k, m):
        w = np.sqrt(c[k, k] / m)
        for _ in range(50):
            w = np.sqrt(c[k, k] / (m + np.interp(w, om, am[:, k, k])))
        return 2 * np.pi / w

    assert 10.0 < period(2, MASS) < 13.0  # heave ≈ 11.5 s
    assert 28.0 < period(3, INERTIA[0]) < 35.0 and 28.0 < period(4, INERTIA[1]) < 35.0
    # surge added mass is of order ρV at long waves, less at ω = ∞
    assert 0.4 < am[0, 0, 0] / (RHO * 40500) < 1.0
    assert 0.1 < float(box.added_mass_inf[0, 0]) / (RHO * 40500) < am[0, 0, 0] / (RHO * 40500)


def test_box_symmetries(box):
    """Square box: surge ≡ sway, roll ≡ pitch; reciprocity A = Aᵀ, B = Bᵀ (to BEM accuracy);
    head seas on surge ≡ beam seas on sway (the drift only away from the roll/pitch
    resonances near 0.2 rad/s, as Ixx ≠ Iyy)."""
    am, bd = np.asarray(box.added_mass), np.asarray(box.damping)
    assert am[:, 0, 0] == pytest.approx(am[:, 1, 1], rel=1e-3)
    assert am[:, 3, 3] == pytest.approx(am[:, 4, 4], rel=1e-3)
    assert bd[:, 0, 0] == pytest.approx(bd[:, 1, 1], rel=1e-3, abs=1e-3 * bd[:, 0, 0].max())
    for i in range(6):
        for j in range(6):
            scale = np.sqrt(np.abs(bd[:, i, i]).max() * np.abs(bd[:, j, j]).max())
            assert np.abs(bd[:, i, j] - bd[:, j, i]).max() < 0.08 * scale
    for i in (0, 1, 2, 3, 4):  # radiation damping dissipates (lid removes irregular frequencies)
        assert bd[:, i, i].min() > -0.01 * bd[:, i, i].max()
    x = np.asarray(box.excitation_re) + 1j * np.asarray(box.excitation_im)
    i90 = 6
    assert np.abs(x[0, :, 0]) == pytest.approx(np.abs(x[i90, :, 1]), rel=1e-3)
    d = np.asarray(box.drift)
    far = np.asarray(box.omega) >= 0.3
    assert d[0, far, 0] == pytest.approx(d[i90, far, 1], rel=1e-2, abs=1e-3 * d[0, :, 0].max())


def test_excitation_phase_convention(box):
    """e^{+iωt}: in long waves heave follows the elevation (X3 ≈ ρgA_wp, real > 0)
    and surge leads it by 90° (F1 ∝ −∂η/∂x)."""
    x = excitation_at(box, float(box.omega[0]), 0.0)
    assert np.real(x[2]) == pytest.approx(RHO * G * 45 * 45, rel=0.05)
    assert abs(np.angle(x[2])) < np.radians(5)
    assert np.degrees(np.angle(x[0])) == pytest.approx(90.0, abs=10.0)
    assert np.abs(x[1]) < 1e-6 * np.abs(x[0])


def test_drift_force_full_reflection_limit(box):
    """Short waves are reflected by the 45 m face: D → ½ρgB, in the propagation direction."""
    d = np.asarray(box.drift)
    assert 0.75 < d[0, -1, 0] / (0.5 * RHO * G * 45) < 1.05
    assert np.all(d[0, :, 0] > -1e-3 * d[0, :, 0].max())
    assert np.all(d[:, :, 2:5] == 0.0)


# -- file validation -----------------------------------------------------------

def test_save_load_roundtrip(box, tmp_path):
    path = tmp_path / "copy.npz"
    save_hydro(path, box, metadata={"note": "copy"})
    back = load_hydro(path)
    for name in ("omega", "added_mass", "damping", "excitation_im", "drift", "hydrostatic"):
        np.testing.assert_array_equal(np.asarray(getattr(back, name)), np.asarray(getattr(box, name)))
    assert hydro_metadata(path) == {"note": "copy"}


def test_bad_file_wrong_shape(tmp_path):
    raw = _raw()
    k = raw["omega"].shape[0]
    path = _write(tmp_path, added_mass=raw["added_mass"][:, :, :5])
    with pytest.raises(ValueError, match=rf"added_mass has shape \({k}, 6, 5\), expected \(K, 6, 6\) "
                                         rf"with K = len\(omega\) = {k}"):
        load_hydro(path)


def test_bad_file_decreasing_frequencies(tmp_path):
    om = _raw()["omega"].copy()
    om[[3, 4]] = om[[4, 3]]
    with pytest.raises(ValueError, match="omega must be strictly increasing"):
        load_hydro(_write(tmp_path, omega=om))
    om = _raw()["omega"].copy()
    om[0] = 0.0
    with pytest.raises(ValueError, match="omega must be positive"):
        load_hydro(_write(tmp_path, omega=om))


def test_bad_file_negative_heave_stiffness(tmp_path):
    c = _raw()["hydrostatic"].copy()
    c[2, 2] = -1.0
    with pytest.raises(ValueError, match="hydrostatic stiffness in heave must be positive"):
        load_hydro(_write(tmp_path, hydrostatic=c))


def test_bad_file_missing_and_nonfinite(tmp_path):
    raw = _raw()
    del raw["drift"]
    path = tmp_path / "missing.npz"
    np.savez(path, **raw)
    with pytest.raises(ValueError, match="lacks drift"):
        load_hydro(path)
    d = _raw()["damping"].copy()
    d[2, 1, 1] = np.nan
    with pytest.raises(ValueError, match=r"damping \[.*\] has a non-finite value at index \(2, 1, 1\)"):
        load_hydro(_write(tmp_path, damping=d))


# -- interpolation -------------------------------------------------------------

def test_interpolation_nodes_midpoints_and_range(box):
    om, hd = np.asarray(box.omega), np.asarray(box.headings)
    x = np.asarray(box.excitation_re) + 1j * np.asarray(box.excitation_im)
    np.testing.assert_allclose(excitation_at(box, om, hd[2]), x[2], rtol=1e-12, atol=1e-6)
    mid_h = 0.5 * (hd[2] + hd[3])
    np.testing.assert_allclose(drift_at(box, om[5], mid_h), 0.5 * (box.drift[2, 5] + box.drift[3, 5]),
                               rtol=1e-12, atol=1e-9)
    mid_w = 0.5 * (om[5] + om[6])
    np.testing.assert_allclose(excitation_at(box, mid_w, hd[0]), 0.5 * (x[0, 5] + x[0, 6]), rtol=1e-12)
    with pytest.raises(ValueError, match="heading 200°.*outside"):
        excitation_at(box, 0.5, np.radians(200.0))
    with pytest.raises(ValueError, match="leave the hydrodynamic table's range"):
        drift_at(box, 2.5, 0.0)
    # traceable: gradient of the interpolated drift with respect to heading
    g = jax.grad(lambda b: drift_at(box, 1.0, b)[0])(0.3)
    assert np.isfinite(g)


# -- radiation -----------------------------------------------------------------

def test_retardation_function_matches_direct_quadrature(box):
    """Exact piecewise-linear transform against brute-force trapezoid quadrature."""
    t = np.array([0.0, 3.0, 17.0])
    k = retardation_function(box, t, tail_power=3.0)
    om = np.asarray(box.omega)
    w = np.concatenate([np.linspace(0, om[0], 50), np.linspace(om[0], om[-1], 40001)[1:],
                        om[-1] * np.linspace(1, 50, 400001)[1:]])
    b = 0.5 * (np.asarray(box.damping)[:, 2, 2] + np.asarray(box.damping)[:, 2, 2])
    bw = np.where(w <= om[-1], np.interp(w, np.concatenate([[0], om]), np.concatenate([[0], b])),
                  b[-1] * (om[-1] / np.maximum(w, om[-1])) ** 3)
    for ti, ki in zip(t, k[:, 2, 2]):
        ref = 2 / np.pi * np.trapezoid(bw * np.cos(w * ti), w)
        assert ki == pytest.approx(ref, rel=1e-4, abs=1e-6 * abs(k[0, 2, 2]))


def test_radiation_fit_accuracy(fitted):
    ss, rep = fitted
    assert isinstance(ss, RadiationStateSpace)
    assert np.all(np.linalg.eigvals(np.asarray(ss.A)).real < 0)
    for i in range(6):
        assert rep.k_error[(i, i)] < 0.05 and rep.b_error[(i, i)] < 0.05, str(rep)
    for ij in ((0, 4), (4, 0), (1, 3), (3, 1)):  # surge–pitch, sway–roll couplings are kept
        assert ij in rep.order and rep.b_error[ij] < 0.1
    assert (0, 1) in rep.dropped and (2, 4) in rep.dropped
    assert ss.n_states == sum(rep.order.values())


@pytest.mark.parametrize("dof,omega", [(0, 0.5), (0, 0.8), (2, 0.4), (2, 0.6), (4, 0.6)])
def test_state_space_reproduces_frequency_domain_force(box, fitted, dof, omega):
    """ẋ_dof = sin ωt from rest: after the transients −Cξ equals
    −[B(ω)ẋ + (A(ω) − A∞)ẍ] of the table (the driven DOF and its coupled one)."""
    ss, _ = fitted
    om = np.asarray(box.omega)
    k = int(np.argmin(np.abs(om - omega)))
    assert om[k] == pytest.approx(omega)
    dt, n = 0.05, 5000
    e = jnp.zeros(6).at[dof].set(1.0)

    def rate(x, t):
        return ss.rate(x, e * jnp.sin(omega * t))

    def step(x, t):
        k1 = rate(x, t)
        k2 = rate(x + 0.5 * dt * k1, t + 0.5 * dt)
        k3 = rate(x + 0.5 * dt * k2, t + 0.5 * dt)
        k4 = rate(x + dt * k3, t + dt)
        x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return x, ss.force(x)

    ts = jnp.arange(n) * dt
    _, force = jax.lax.scan(step, ss.init(), ts)
    t = np.asarray(ts) + dt
    last = t > t[-1] - 2 * 2 * np.pi / omega
    am, bd, ainf = np.asarray(box.added_mass), np.asarray(box.damping), np.asarray(box.added_mass_inf)
    for i in {dof, {0: 4, 4: 0, 2: 2}[dof]}:
        ref = -(bd[k, i, dof] * np.sin(omega * t[last])
                + (am[k, i, dof] - ainf[i, dof]) * omega * np.cos(omega * t[last]))
        err = np.abs(np.asarray(force)[last, i] - ref).max() / np.abs(ref).max()
        assert err < 0.05, (i, err)


def test_state_space_transfer_is_the_fit(fitted, box):
    ss, rep = fitted
    om = np.asarray(box.omega)
    kh = np.asarray(ss.transfer(om))
    b = 0.5 * (np.asarray(box.damping) + np.swapaxes(np.asarray(box.damping), 1, 2))
    rel = np.linalg.norm(kh.real[:, 2, 2] - b[:, 2, 2]) / np.linalg.norm(b[:, 2, 2])
    assert rel == pytest.approx(rep.b_error[(2, 2)], rel=1e-6)


def test_construction_rejects_bad_input(box):
    kw = {n: np.asarray(getattr(box, n)) for n in
          ("omega", "added_mass", "damping", "added_mass_inf", "headings", "excitation_re",
           "excitation_im", "drift", "hydrostatic", "rho", "g", "volume", "reference_point")}
    HydroCoefficients(**kw)
    with pytest.raises(ValueError, match=r"drift has shape .*expected \(H, K, 6\) "
                                         r"with H = len\(headings\) = 13"):
        HydroCoefficients(**{**kw, "drift": kw["drift"][:-1]})
    with pytest.raises(ValueError, match="volume = -1 m³ must be > 0"):
        HydroCoefficients(**{**kw, "volume": -1.0})
    with pytest.raises(ValueError, match="radiation state space needs"):
        RadiationStateSpace(np.eye(3), np.zeros((3, 5)), np.zeros((6, 3)))
