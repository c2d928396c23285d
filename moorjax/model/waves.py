"""Linear (Airy) waves: one set of components for body loads and line kinematics.

A sea is a set of components (:class:`IrregularWave`): frequencies ω_k [rad/s],
amplitudes a_k [m], phases φ_k [rad] and directions of propagation β_k [rad]
(from +x towards +y), with the elevation

    η(x, y, t) = η̄ + Σ_k a_k cos(ω_k t − k_k (x cos β_k + y sin β_k) + φ_k).

At the origin this is the η(t) = Σ a_k cos(ω_k t + φ_k) that drives a body's wave
excitation (:mod:`moorjax.body.waves`); :class:`AiryWaves` adds the wave numbers
k_k of finite depth h (ω² = g k tanh kh) and gives the water particle velocity
and acceleration under the surface, which load the lines
(:mod:`moorjax.element.linear`). The same components drive both.

Kinematics at a point (x, y, z), with ψ_k the phase above, as MoorDyn v2
computes them (``source/Waves/SpectrumKin.cpp`` and ``WaveGrid.cpp``):

    u_h = Σ a ω cosh k(z'+h)/sinh kh · cos ψ · (cos β, sin β)
    u_z = −Σ a ω sinh k(z'+h)/sinh kh · sin ψ
    a_h = −Σ a ω² cosh k(z'+h)/sinh kh · sin ψ · (cos β, sin β)
    a_z = −Σ a ω² sinh k(z'+h)/sinh kh · cos ψ

**Free surface.** As MoorDyn, the depth is stretched to the instantaneous
surface (Wheeler stretching): the kinematics at z are those of linear theory at
z' = h(z + h)/(η + h) − h, so the surface z = η maps to z' = 0 and the seabed
stays at −h; above the surface z' is held at 0 (MoorDyn: "If the point is above
the water surface, return the values at the water surface"). A node above the
surface thus sees the surface's kinematics; the linear element is wet only
below the surface, as MoorDyn's ``calcSubSeg`` (:mod:`moorjax.element.linear`).

:class:`AbstractWaveKinematics` is what the physics samples; :class:`ExternalWaves`
takes the kinematics from a user's function instead (MoorDyn's ``WaveKin = 1``).

The hyperbolic ratios are evaluated as (e^{kz'} ± e^{−k(z'+2h)})/(1 − e^{−2kh}),
exact at every depth and never overflowing (MoorDyn switches to the deep-water
exponentials for kh > 89.4). Everything is pure JAX and differentiable; the
wave numbers are solved once, at construction.
"""

from __future__ import annotations

import abc
from typing import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array

from .._checks import check_finite, check_nonnegative, check_positive


class IrregularWave(eqx.Module):
    """A set of wave components (a regular wave is one).

    η(t) = Σ_k a_k cos(ω_k t + φ_k) at the global origin; the components travel
    along ``heading`` β (one for all, or one per component).

    Args:
        omega: (n,) frequencies [rad/s] (> 0).
        amplitude: (n,) amplitudes a_k [m] (≥ 0).
        phase: (n,) phases φ_k [rad].
        heading: direction of propagation β [rad], from +x towards +y: a scalar
            or (n,) per component.
    """

    omega: Array
    amplitude: Array
    phase: Array
    heading: Array

    def __init__(self, omega, amplitude, phase, heading=0.0):
        om, a, ph = (jnp.atleast_1d(jnp.asarray(x, dtype=float)) for x in (omega, amplitude, phase))
        if om.ndim != 1 or a.shape != om.shape or ph.shape != om.shape:
            raise ValueError(f"wave components need omega, amplitude and phase of one shape (n,); "
                             f"got {om.shape}, {a.shape}, {ph.shape}")
        heading = jnp.asarray(heading, dtype=float)
        if heading.ndim > 1 or (heading.ndim == 1 and heading.shape != om.shape):
            raise ValueError(f"wave heading must be a scalar or one per component {om.shape}; "
                             f"got shape {heading.shape}")
        check_positive(om, "wave component frequency", "rad/s")
        check_nonnegative(a, "wave component amplitude", "m")
        check_finite(ph, "wave component phase", "rad")
        check_finite(heading, "wave heading", "rad")
        self.omega, self.amplitude, self.phase = om, a, ph
        self.heading = heading

    @property
    def n_components(self) -> int:
        return int(self.omega.shape[0])

    def elevation(self, t) -> Array:
        """η(t) [m] at the origin for times t (…) [s] (memory O(size(t)·n))."""
        t = jnp.asarray(t, dtype=float)
        return jnp.cos(t[..., None] * self.omega + self.phase) @ self.amplitude

    def variance(self) -> Array:
        """Σ a_k²/2 = m0 of the components [m²]."""
        return 0.5 * jnp.sum(self.amplitude**2)


def wave_number(omega, depth, g=9.80665) -> Array:
    """Wave number k [rad/m] of finite depth: ω² = g k tanh(k h).

    ``omega`` (…) [rad/s] > 0, ``depth`` h [m] > 0, ``g`` [m/s²]. Newton on
    x = kh from Fenton & McKee's explicit guess (1.7 %) converges to machine
    precision in six steps; the last step is taken outside ``stop_gradient``,
    so derivatives are those of the implicit function (exact at convergence).
    """
    omega = jnp.asarray(omega, dtype=float)
    c = omega**2 * depth / g  # = x tanh x

    def newton(x, c):
        th = jnp.tanh(x)
        return x - (x * th - c) / (th + x * (1.0 - th * th))

    cs = jax.lax.stop_gradient(c)
    x = cs / jnp.tanh(cs**0.75) ** (2.0 / 3.0)
    for _ in range(6):
        x = newton(x, cs)
    return newton(jax.lax.stop_gradient(x), c) / depth


class AbstractWaveKinematics(eqx.Module):
    """The water's motion under a free surface, as the lines, points and bodies
    sample it: the surface elevation above a point, the water velocity and
    acceleration at it (:meth:`kinematics`), and the height at which the
    current is read there (:meth:`current_height`).

    :class:`AiryWaves` (wave components) and :class:`ExternalWaves` (a user's
    function: MoorDyn's ``WaveKin = 1``) implement it; subclass it for any other
    field (its array fields are then differentiable parameters).
    """

    @abc.abstractmethod
    def kinematics(self, r, t) -> tuple[Array, Array, Array]:
        """(η (…) [m], u (…, 3) [m/s], a (…, 3) [m/s²]) at positions r (…, 3) [m], time t [s]."""

    def current_height(self, r, eta) -> Array:
        """The height [m] at which the current is sampled at the points r (…, 3):
        their own (MoorDyn's ``WaveKin = 7`` adds the current at the node)."""
        del eta
        return r[..., 2]


class ExternalWaves(AbstractWaveKinematics):
    """Water kinematics from a user's function: MoorDyn's ``WaveKin = 1``.

    MoorDyn's external wave kinematics are set through its API at run time
    (``MoorDyn_ExternalWaveKinGetCoordinates`` gives the node positions,
    ``MoorDyn_ExternalWaveKinSet`` their velocity and acceleration, held until
    the next call; the surface elevation is not set and stays 0). moorjax takes
    the function itself and evaluates it at every node, point and body reference
    point at every stage of the solver, so there is no sample-and-hold.

    Args:
        velocity_acceleration: ``f(r, t) -> (u, a)``, with r (…, 3) positions
            [m], t a time [s], u and a (…, 3) the water velocity [m/s] and
            acceleration [m/s²]. It must be a pure JAX function (it is traced and
            differentiated); a current given separately
            (:class:`~moorjax.model.environment.Environment`'s ``current``) is
            added to u, as MoorDyn adds its current to external waves.
        elevation: optional ``g(x, y, t) -> η`` [m], the free surface above
            (x, y) (…); default: the still-water level 0, as MoorDyn's.

    A plain function is kept as static structure (a new function object
    recompiles); to differentiate with respect to the field's parameters,
    subclass :class:`AbstractWaveKinematics` with them as array fields.
    """

    velocity_acceleration: Callable = eqx.field(static=True)
    elevation: Callable | None = eqx.field(static=True, default=None)

    def __init__(self, velocity_acceleration: Callable, elevation: Callable | None = None):
        if not callable(velocity_acceleration):
            raise ValueError("ExternalWaves needs a function f(r, t) -> (velocity, acceleration), got "
                             f"{type(velocity_acceleration).__name__}")
        if elevation is not None and not callable(elevation):
            raise ValueError(f"ExternalWaves: elevation must be a function g(x, y, t) -> η or None, got "
                             f"{type(elevation).__name__}")
        self.velocity_acceleration = velocity_acceleration
        self.elevation = elevation

    def kinematics(self, r, t):
        r = jnp.asarray(r, dtype=float)
        u, a = self.velocity_acceleration(r, t)
        u = jnp.broadcast_to(jnp.asarray(u, dtype=float), r.shape)
        a = jnp.broadcast_to(jnp.asarray(a, dtype=float), r.shape)
        if self.elevation is None:
            eta = jnp.zeros(r.shape[:-1])
        else:
            eta = jnp.broadcast_to(jnp.asarray(self.elevation(r[..., 0], r[..., 1], t), dtype=float),
                                   r.shape[:-1])
        return eta, u, a


class AiryWaves(AbstractWaveKinematics):
    """Linear wave kinematics of finite depth under a set of components.

    Fields: ``wave`` (the :class:`IrregularWave`), ``depth`` h [m], ``k`` (n,)
    wave numbers [rad/m], ``mean_level`` η̄ [m] (a constant offset of the surface,
    MoorDyn's zero-frequency component; it moves the stretching, not the flow).
    See the module docstring for the formulas and the free surface.

    ``k`` is solved when the model is built: gradients with respect to the
    amplitudes and phases flow through the fields, but to differentiate with
    respect to ω or h build the model inside the differentiated function (the
    dispersion solve is differentiable, :func:`wave_number`).

    Args:
        wave: the components.
        depth: water depth h [m] (> 0), the seabed at z = −h.
        g: gravity [m/s²] (> 0).
        mean_level: η̄ [m].
    """

    wave: IrregularWave
    depth: Array
    k: Array
    mean_level: Array

    def __init__(self, wave: IrregularWave, depth, g=9.80665, mean_level=0.0):
        check_positive(depth, "water depth", "m")
        check_positive(g, "gravity", "m/s²")
        check_finite(mean_level, "mean wave level", "m")
        self.wave = wave
        self.depth = jnp.asarray(depth, dtype=float)
        self.k = wave_number(wave.omega, self.depth, g)
        self.mean_level = jnp.asarray(mean_level, dtype=float)

    def _phase(self, x, y, t):
        """ψ_k (…, n) and the unit directions (n,) for points x, y (…)."""
        beta = jnp.broadcast_to(self.wave.heading, self.wave.omega.shape)
        cb, sb = jnp.cos(beta), jnp.sin(beta)
        dist = x[..., None] * cb + y[..., None] * sb
        t = jnp.asarray(t, dtype=float)[..., None]
        psi = self.wave.omega * t - self.k * dist + self.wave.phase
        return psi, cb, sb

    def elevation(self, x, y, t) -> Array:
        """Surface elevation η [m] at horizontal positions x, y (…) [m] and times t
        [s] (any shape broadcasting with x, y)."""
        x, y = jnp.asarray(x, dtype=float), jnp.asarray(y, dtype=float)
        psi, _, _ = self._phase(x, y, t)
        return self.mean_level + jnp.cos(psi) @ self.wave.amplitude

    def stretched_height(self, r, eta) -> Array:
        """The height z' [m] (…) whose linear kinematics act at the points r (…, 3)
        under the surface η (…): h(z + h)/(η + h) − h, held at 0 above the surface."""
        h = self.depth
        return jnp.minimum(h * (r[..., 2] + h) / (eta + h) - h, 0.0)

    def kinematics(self, r, t) -> tuple[Array, Array, Array]:
        """Elevation above each point, water velocity and acceleration.

        Args:
            r: (…, 3) positions [m]; t: time [s].

        Returns:
            (η (…) [m], u (…, 3) [m/s], a (…, 3) [m/s²]).
        """
        r = jnp.asarray(r, dtype=float)
        psi, cb, sb = self._phase(r[..., 0], r[..., 1], t)
        amp = self.wave.amplitude
        cos, sin = jnp.cos(psi), jnp.sin(psi)
        eta = self.mean_level + cos @ amp
        h = self.depth
        zs = self.stretched_height(r, eta)[..., None]  # Wheeler, clipped at the surface
        k = self.k
        grow, decay = jnp.exp(k * zs), jnp.exp(-k * (zs + 2.0 * h))
        den = -jnp.expm1(-2.0 * k * h)
        ch, sh = (grow + decay) / den, (grow - decay) / den  # cosh k(z'+h)/sinh kh, sinh/sinh
        aw = amp * self.wave.omega
        aww = aw * self.wave.omega
        uh = (aw * ch * cos)
        ah = -(aww * ch * sin)
        u = jnp.stack([uh @ cb, uh @ sb, -jnp.sum(aw * sh * sin, axis=-1)], axis=-1)
        a = jnp.stack([ah @ cb, ah @ sb, -jnp.sum(aww * sh * cos, axis=-1)], axis=-1)
        return eta, u, a


class GridAiryWaves(AiryWaves):
    """:class:`AiryWaves` as MoorDyn v2 applies its wave grids (``WaveKin`` 2, 3).

    The same kinematics; the difference is the current. With
    ``UnifyCurrentGrid = 1`` (MoorDyn's default) MoorDyn adds the current into the
    wave grid, which it reads at the stretched height z' (``Waves::setup`` and
    ``WaveGrid::getWaveKin``), so the current too is taken at z' (and at the
    surface's value above it) rather than at the node's own height.
    """

    def current_height(self, r, eta) -> Array:
        return self.stretched_height(r, eta)
