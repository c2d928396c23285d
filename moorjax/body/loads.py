"""Steady environmental loads on a floating body: wind (Wu et al. Eq. 2) and
current (Eq. 3), and constant (6,) load vectors.

Wu et al. treat wind and current as constant forces ("only constant
components"); :func:`wind_force` and :func:`current_force` give their magnitudes
[N], :func:`directional_load` turns a magnitude into a (6,) force/moment vector
about the body's reference point, and :class:`ConstantLoad` makes it a load with
``force(t)`` for :class:`moorjax.body.RigidBody`.

Eq. 2 as printed, F = ½ v² C_h C_s A, has no air density: OCIMF's wind formula
(which the paper cites) is F = ½ ρ_air C v² A. Here ρ_air is an explicit
argument (default 1.225 kg/m³); pass ``rho_air=1.0`` to reproduce the printed
formula literally (which then gives a force ≈ 1/1.225 of OCIMF's).
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array

from .._checks import check_finite, check_nonnegative, check_positive

#: density of air at 15 °C, sea level [kg/m³]
AIR_DENSITY = 1.225


class AbstractBodyLoad(eqx.Module):
    """An external load on a body: ``force(t)`` → (6,) force and moment about the
    body's reference point, in global axes [N, N·m]."""

    @abc.abstractmethod
    def force(self, t) -> Array:
        """(6,) [N, N·m] at time t [s]."""


class ConstantLoad(AbstractBodyLoad):
    """A load that does not change in time. ``force6``: (6,) [N, N·m]."""

    force6: Array

    def __init__(self, force6):
        f = jnp.asarray(force6, dtype=float)
        if f.shape != (6,):
            raise ValueError(f"constant load needs a (6,) force/moment vector [N, N·m], got shape {f.shape}")
        check_finite(f, "constant load", "N, N·m")
        self.force6 = f

    def force(self, t) -> Array:
        return self.force6


def wind_force(speed, c_h, c_s, area, rho_air=AIR_DENSITY) -> Array:
    """Wind force F = ½ ρ_air v² C_h C_s A [N] (Wu et al. Eq. 2 with OCIMF's ρ_air).

    Args:
        speed: wind speed v [m/s] (≥ 0; the direction goes to :func:`directional_load`).
        c_h: height (and pressure) coefficient C_h [-].
        c_s: shape coefficient C_s [-].
        area: windward area A [m²].
        rho_air: air density [kg/m³] (see the module docstring).
    """
    check_nonnegative(speed, "wind speed", "m/s")
    check_nonnegative(c_h, "wind height coefficient C_h", "-")
    check_nonnegative(c_s, "wind shape coefficient C_s", "-")
    check_nonnegative(area, "windward area", "m²")
    check_positive(rho_air, "air density", "kg/m³")
    return 0.5 * rho_air * jnp.square(speed) * c_h * c_s * area


def current_force(speed, cd, area, rho=1025.0) -> Array:
    """Current force F = ½ ρ C_D u² A [N] (Wu et al. Eq. 3).

    Args:
        speed: current speed u [m/s] (≥ 0).
        cd: drag coefficient C_D [-].
        area: area facing the flow A [m²] (e.g. width × draft).
        rho: water density [kg/m³].
    """
    check_nonnegative(speed, "current speed", "m/s")
    check_nonnegative(cd, "current drag coefficient C_D", "-")
    check_nonnegative(area, "current area", "m²")
    check_positive(rho, "water density", "kg/m³")
    return 0.5 * rho * cd * jnp.square(speed) * area


def directional_load(magnitude, heading, point=None) -> Array:
    """(6,) force/moment [N, N·m] of a horizontal force along ``heading``.

    Args:
        magnitude: force magnitude [N] (≥ 0).
        heading: direction the force points to [rad], from +x towards +y (a wind or
            current "going to" that direction).
        point: optional (3,) point of application relative to the reference point
            [m]; adds the moment r × F. Default: through the reference point.
    """
    check_nonnegative(magnitude, "load magnitude", "N")
    check_finite(heading, "load heading", "rad")
    heading = jnp.asarray(heading, dtype=float)
    f = magnitude * jnp.stack([jnp.cos(heading), jnp.sin(heading), jnp.zeros_like(heading)])
    if point is None:
        m = jnp.zeros(3)
    else:
        check_finite(point, "load application point", "m")
        m = jnp.cross(jnp.asarray(point, dtype=float).reshape(3), f)
    return jnp.concatenate([f, m])
