"""A free connection point: a point mass where lines meet (MoorDyn's free point).

It moves with three translational degrees of freedom under the forces of the
lines ending on it, its weight and buoyancy, and optional drag. It implements
the body interface :class:`~moorjax.body.base.AbstractBody` (lines end on it with
``BodyEnd(k, (0, 0, 0))`` and it sits in ``Scene.bodies``), with the solver-state
layout [η (6), η̇ (6)] whose rotational entries stay zero, so statics, the Newton
solve and the error norm treat it like any body.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array

from .._checks import check_finite, check_nonnegative
from .._numerics import abs_times
from .base import AbstractBody


class ConnectionPoint(AbstractBody):
    """A free point mass at ``origin`` (3,) [m].

    Args:
        mass: [kg] (mass + added_mass > 0). The lines' end forces already include
            the wet weight of their end half-elements but not their inertia: to
            match a line node, give the point their mass and a volume that makes
            that mass neutral (see ``tests/test_connection_point.py``).
        volume: displaced volume [m³] (buoyancy ρVg).
        added_mass: translational added mass [kg] (e.g. Ca·ρV).
        cda: drag area Cd·A [m²]: drag ½ρ·CdA·|v|v.
        rho, g: water density [kg/m³] and gravity [m/s²]; ``None``: the scene's
            environment's, taken when the point is evaluated.
        current: optional :class:`~moorjax.model.environment.AbstractCurrent`:
            the drag then acts on the velocity relative to the water at the
            point's height (MoorDyn's points do the same).

    The net weight (ρV − m)·g is computed from these parameters whenever the
    point is evaluated (:attr:`static_force`), so derivatives with respect to
    the mass, the volume, ρ or g reach it.
    """

    mass: Array
    added: Array
    origin: Array
    volume: Array
    cda: Array
    rho: Array | None
    g: Array | None
    current: object = None
    label: str = eqx.field(static=True, default="point")

    def __init__(self, mass, origin, *, volume=0.0, added_mass=0.0, cda=0.0, rho=1025.0,
                 g=9.80665, label="point", current=None):
        check_nonnegative(mass, "connection point mass", "kg")
        check_nonnegative(added_mass, "connection point added mass", "kg")
        check_nonnegative(volume, "connection point volume", "m³")
        check_nonnegative(cda, "connection point CdA", "m²")
        check_finite(origin, "connection point position", "m")
        if not float(mass) + float(added_mass) > 0:
            raise ValueError(f"connection point {label!r}: mass + added mass must be > 0 kg")
        self.mass = jnp.asarray(mass, dtype=float)
        self.added = jnp.asarray(added_mass, dtype=float)
        self.origin = jnp.asarray(origin, dtype=float).reshape(3)
        self.volume = jnp.asarray(volume, dtype=float)
        self.cda = jnp.asarray(cda, dtype=float)
        self.rho = None if rho is None else jnp.asarray(rho, dtype=float)
        self.g = None if g is None else jnp.asarray(g, dtype=float)
        self.current = current
        self.label = str(label)

    @property
    def half_size(self):
        return None

    def _water(self, env):
        """(ρ, g): the point's own, else the environment's."""
        if (self.rho is None or self.g is None) and env is None:
            raise ValueError(f"connection point {self.label!r} takes ρ and g from the scene's "
                             "environment: pass env")
        rho = env.rho if self.rho is None else self.rho
        g = env.g if self.g is None else self.g
        return rho, g

    def net_weight(self, env=None) -> Array:
        """Buoyancy minus weight (ρV − m)·g [N] (upwards positive)."""
        rho, g = self._water(env)
        return (rho * self.volume - self.mass) * g

    @property
    def static_force(self) -> Array:
        """(6,) constant load [N]: the net weight (needs the point's own ρ and g)."""
        return self._static_force(None)

    def _static_force(self, env):
        return jnp.zeros(6).at[2].set(self.net_weight(env))

    @property
    def hydrostatic(self):
        """No restoring in translation; the (frozen) rotations get a unit stiffness so
        that the system statics stay well posed."""
        return jnp.diag(jnp.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0]))

    @property
    def n_internal(self) -> int:
        return 0

    def rest_state(self, pose=None) -> Array:
        pose = jnp.zeros(6) if pose is None else jnp.asarray(pose, dtype=float).reshape(6)
        return jnp.concatenate([pose.at[3:].set(0.0), jnp.zeros(6)])

    def point_position(self, pose, local) -> Array:
        return self.origin + pose[:3] + local

    def point_velocity(self, pose, velocity, local) -> Array:
        return jnp.broadcast_to(velocity[:3], jnp.shape(local))

    def wrench(self, pose, local, force) -> Array:
        return jnp.concatenate([jnp.sum(force, axis=0), jnp.zeros(3)])

    def rate(self, t, z, mooring, env=None) -> Array:
        pose, vel, _ = self.split(z)
        f = self._static_force(env)[:3] + mooring[:3]
        u = vel[:3]
        pos = self.origin + pose[:3]
        pos_current = pos
        if env is not None and env.waves is not None:  # drag on the wave velocity (MoorDyn's Point)
            eta, u_wave, _ = env.waves.kinematics(pos, t)
            u = u - u_wave
            pos_current = pos.at[2].set(env.waves.current_height(pos, eta))
        if self.current is not None:
            u = u - self.current.velocity_at(pos_current, t)
        rho, _ = self._water(env)
        f = f - 0.5 * rho * self.cda * abs_times(u)
        acc = f / (self.mass + self.added)
        zero = jnp.zeros(3)
        return jnp.concatenate([vel[:3], zero, acc, zero])

    def mean_load(self, pose, t=0.0, env=None, *, loads: bool = True) -> Array:
        """The net weight, the unit rotational stiffness (see :attr:`hydrostatic`) and,
        with ``loads``, the current's drag ½ρ·CdA·|U|U on the point at rest (the
        current at the point's height at time ``t``)."""
        f = -self.hydrostatic @ pose + self._static_force(env)
        if loads and self.current is not None:
            rho, _ = self._water(env)
            u = self.current.velocity_at(self.origin + pose[:3], t)
            f = f.at[:3].add(0.5 * rho * self.cda * abs_times(u))
        return f

    def energy(self, z) -> Array:
        _, vel, _ = self.split(z)
        return 0.5 * (self.mass + self.added) * vel[:3] @ vel[:3]
