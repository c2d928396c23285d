"""Irregular long-crested waves (Wu et al. Eq. 4) and the wave loads on a body:
first-order excitation and Newman's slow-drift approximation.

The incident elevation at the global origin (x, y) = (0, 0) is
η(t) = Σ_k a_k cos(ω_k t + φ_k); the waves propagate along the heading β (from
+x towards +y). With the e^{+iωt} convention of :mod:`moorjax.body.hydro`, a
component excites F_k(t) = Re[X(ω_k, β) a_k e^{i(ω_k t + φ_k)}].

Slow drift (Newman): with D_k = D(ω_k, β) the mean drift per unit amplitude
squared, per DOF,

    F_sd(t) = 2 [Σ_k a_k s_k √|D_k| cos(ω_k t + φ_k)] · [Σ_k a_k √|D_k| cos(ω_k t + φ_k)],

s_k = sign(D_k). Where every D_k ≥ 0 this is the standard 2(Σ a_k √D_k cos)²;
the sign-preserving product keeps the correct mean Σ_k a_k² D_k when D changes
sign with frequency. Like the standard form it also contains (spurious)
sum-frequency terms at ~2ω, which a large moored body filters out.

The components are :class:`moorjax.model.waves.IrregularWave`, the wave model
the lines share: ``AiryWaves(wave, depth)`` turns the same components into the
water kinematics at the line nodes (``Environment(..., waves=...)``).

Everything is a pure function of t (JAX-traceable); the random phases are drawn
once, at construction, with NumPy.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._checks import check_positive
from ..model.waves import IrregularWave
from .hydro import HydroCoefficients, drift_at, excitation_at
from .loads import AbstractBodyLoad


def pm_spectrum(omega, hs, tz) -> Array:
    """Pierson–Moskowitz spectrum of Wu et al. Eq. 4, S(ω) [m²·s/rad]:

        S(ω) = (1/2π) · Hs²/(4π Tz⁴) · (2π/ω)⁵ · exp[−(2π/ω)⁴/(π Tz⁴)]

    with significant wave height ``hs`` = 4√m0 [m] and mean zero-crossing period
    ``tz`` = 2π√(m0/m2) [s]; S(ω ≤ 0) = 0.
    """
    check_positive(hs, "significant wave height Hs", "m")
    check_positive(tz, "zero-crossing period Tz", "s")
    om = jnp.asarray(omega, dtype=float)
    pos = om > 0
    x = 2 * jnp.pi / jnp.where(pos, om, 1.0)
    s = hs**2 / (8 * jnp.pi**2 * tz**4) * x**5 * jnp.exp(-(x**4) / (jnp.pi * tz**4))
    return jnp.where(pos, s, 0.0)


def _pm_energy(omega, hs, tz):
    """∫₀^ω S dω' = m0·exp(−B/ω⁴) with m0 = Hs²/16, B = (2π)⁴/(π Tz⁴)."""
    return hs**2 / 16 * np.exp(-((2 * np.pi) ** 4) / (np.pi * tz**4) / np.asarray(omega, float) ** 4)


def _pm_frequency(energy, hs, tz):
    """Inverse of :func:`_pm_energy`."""
    return ((2 * np.pi) ** 4 / (np.pi * tz**4) / -np.log(energy / (hs**2 / 16))) ** 0.25


def regular_wave(amplitude, omega, heading=0.0, phase=0.0) -> IrregularWave:
    """η(t) = a cos(ωt + φ): amplitude [m], omega [rad/s], heading, phase [rad]."""
    return IrregularWave(omega, amplitude, phase, heading)


def wave_components(hs, tz, n, seed, omega_min=0.05, omega_max=3.0, heading=0.0) -> IrregularWave:
    """Random-phase components of the Pierson–Moskowitz sea :func:`pm_spectrum`.

    Equal-area discretisation: [omega_min, omega_max] [rad/s] is cut into ``n`` bins
    holding equal energy m0_bin = (1/n)∫S dω, every component has a = √(2·m0_bin)
    and sits at a uniformly random energy level within its bin (so E[Σ a²ω²/2] is
    exactly m2 of the truncated spectrum), with a uniform random phase. The
    frequencies are incommensurate, so the record does not repeat (equal steps
    would repeat every 2π/Δω). ``seed`` feeds ``numpy.random.default_rng``: the
    same seed gives the same sea.

    Energy outside [omega_min, omega_max] is left out: the record's Hs and Tz are
    those of the truncated spectrum (for Tz = 8 s and omega_max = 2 rad/s, m0
    loses 0.8 % and m2 ~10 %).
    """
    check_positive(hs, "significant wave height Hs", "m")
    check_positive(tz, "zero-crossing period Tz", "s")
    check_positive(omega_min, "lowest wave frequency omega_min", "rad/s")
    if not omega_max > omega_min:
        raise ValueError(f"omega_max = {omega_max} rad/s must exceed omega_min = {omega_min} rad/s")
    if int(n) != n or n < 1:
        raise ValueError(f"number of wave components n = {n} must be a positive integer")
    n = int(n)
    hs, tz = float(hs), float(tz)
    e_lo, e_hi = _pm_energy(omega_min, hs, tz), _pm_energy(omega_max, hs, tz)
    if not e_hi > e_lo:
        raise ValueError(f"the spectrum (Hs = {hs} m, Tz = {tz} s) has no energy between "
                         f"{omega_min} and {omega_max} rad/s")
    rng = np.random.default_rng(seed)
    level = rng.uniform(size=n)
    phase = rng.uniform(0.0, 2 * np.pi, size=n)
    d_e = (e_hi - e_lo) / n
    omega = _pm_frequency(e_lo + (np.arange(n) + level) * d_e, hs, tz)
    return IrregularWave(omega, np.full(n, np.sqrt(2 * d_e)), phase, heading)


class NewmanDrift(eqx.Module):
    """Slow-drift coefficients of :class:`WaveLoads`: a_k√|D_kj| and a_k s_kj√|D_kj|
    (n, 6) [√N]."""

    root: Array
    signed_root: Array


class WaveLoads(AbstractBodyLoad):
    """First-order wave excitation plus optional Newman slow drift, (6,) [N, N·m].

    Fields: ``wave`` (the components), ``excitation_re``/``excitation_im`` (n, 6)
    a_k·X(ω_k, β) [N, N·m], ``drift`` (:class:`NewmanDrift` or ``None``: no drift
    term is traced). Build it with :func:`wave_loads` or :func:`loads_for_wave`.
    """

    wave: IrregularWave
    excitation_re: Array
    excitation_im: Array
    drift: NewmanDrift | None

    def _cos_sin(self, t):
        arg = jnp.asarray(t, dtype=float)[..., None] * self.wave.omega + self.wave.phase
        return jnp.cos(arg), jnp.sin(arg)

    def first_order_force(self, t) -> Array:
        """Σ_k Re[a_k X_k e^{i(ω_k t + φ_k)}], (…, 6) for t (…) [s]."""
        c, s = self._cos_sin(t)
        return c @ self.excitation_re - s @ self.excitation_im

    def drift_force(self, t) -> Array:
        """Newman slow-drift force (…, 6) (zeros without drift)."""
        if self.drift is None:
            return jnp.zeros(jnp.shape(t) + (6,))
        c, _ = self._cos_sin(t)
        return 2.0 * (c @ self.drift.signed_root) * (c @ self.drift.root)

    def force(self, t) -> Array:
        c, s = self._cos_sin(t)
        f = c @ self.excitation_re - s @ self.excitation_im
        if self.drift is not None:
            f = f + 2.0 * (c @ self.drift.signed_root) * (c @ self.drift.root)
        return f

    def mean_drift(self) -> Array:
        """Mean of the slow-drift force Σ_k a_k² D_k (6,) [N, N·m]."""
        if self.drift is None:
            return jnp.zeros(6)
        return jnp.sum(self.drift.signed_root * self.drift.root, axis=0)


def loads_for_wave(coeffs: HydroCoefficients, wave: IrregularWave, drift: bool = True) -> WaveLoads:
    """:class:`WaveLoads` of ``wave`` on the body of ``coeffs`` (X and D interpolated
    linearly in heading and ω; every component must lie within the table). The
    wave must have one heading (a long-crested sea)."""
    if jnp.ndim(wave.heading) != 0:
        raise ValueError(f"body wave loads need one wave heading [rad] for all components (a long-crested "
                         f"sea); got {jnp.shape(wave.heading)} headings: build one WaveLoads per direction")
    x = excitation_at(coeffs, wave.omega, wave.heading)
    a = wave.amplitude[:, None]
    newman = None
    if drift:
        d = drift_at(coeffs, wave.omega, wave.heading)
        mag = jnp.abs(d)
        nz = mag > 0
        root = a * jnp.where(nz, jnp.sqrt(jnp.where(nz, mag, 1.0)), 0.0)  # finite gradient at D = 0
        newman = NewmanDrift(root=root, signed_root=jnp.sign(d) * root)
    return WaveLoads(wave=wave, excitation_re=a * jnp.real(x), excitation_im=a * jnp.imag(x), drift=newman)


def wave_loads(coeffs: HydroCoefficients, hs, tz, heading, n_components: int = 200, seed: int = 0,
               drift: bool = True, omega_min=None, omega_max=None) -> WaveLoads:
    """Wave loads of a random Pierson–Moskowitz sea (Wu et al. Eq. 4) on a body.

    Args:
        coeffs: the body's :class:`HydroCoefficients`.
        hs: significant wave height [m]; tz: zero-crossing period [s].
        heading: direction of propagation [rad] (must lie within the table's headings).
        n_components: number of wave components; seed: random seed (same seed, same sea).
        drift: include Newman's slow drift (needs the table's ``drift``).
        omega_min, omega_max: frequency range [rad/s]; default (and limit) the
            table's range (see :func:`wave_components` for the truncated energy).
    """
    lo, hi = float(coeffs.omega[0]), float(coeffs.omega[-1])
    omega_min = lo if omega_min is None else omega_min
    omega_max = hi if omega_max is None else omega_max
    wave = wave_components(hs, tz, n_components, seed, omega_min, omega_max, heading)
    return loads_for_wave(coeffs, wave, drift=drift)
