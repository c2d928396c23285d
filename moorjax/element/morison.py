"""Morison loads per unit wet length of a line, shared by the elements: drag on
the velocity relative to the water and the water's acceleration (Froude–Krylov
and added mass), each split along and across the line's tangent. The linear
element weights them by half an element's wet length at each node, the Hermite
element by the stretch at each quadrature point.
"""

from __future__ import annotations

import jax.numpy as jnp

from .._numerics import abs_times


def _split(u, tangent):
    """(along, across) the unit ``tangent`` (…, 3)."""
    along = jnp.sum(u * tangent, axis=-1, keepdims=True) * tangent
    return along, u - along


def drag(lt, env, u, tangent):
    """Drag per unit wet length (…, 3) [N/m] on a line moving at ``u`` (…, 3)
    [m/s] relative to the water: −½ρ·(Cd·d·|u_n|u_n + CdAx·πd·|u_t|u_t)."""
    ut, un = _split(u, tangent)
    cn = 0.5 * env.rho * lt.drag.cd_normal * lt.diameter
    ca = 0.5 * env.rho * lt.drag.cd_axial * jnp.pi * lt.diameter
    return -(cn * abs_times(un) + ca * abs_times(ut))


def fluid_inertia(lt, env, a, tangent):
    """Froude–Krylov and added-mass load per unit wet length (…, 3) [N/m] of the
    water's acceleration ``a`` (…, 3) [m/s²]: ρA·[(1+Ca_n)a_n + (1+Ca_ax)a_t]."""
    at, an = _split(a, tangent)
    ca_n = ca_t = 0.0
    if lt.added_mass is not None:
        ca_n, ca_t = lt.added_mass.ca_normal, lt.added_mass.ca_axial
    return env.rho * lt.area * ((1.0 + ca_n) * an + (1.0 + ca_t) * at)
