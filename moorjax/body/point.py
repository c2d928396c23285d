"""A free connection point: a point mass where lines meet (MoorDyn's free point).

It moves with three translational degrees of freedom under the forces of the
lines ending on it, its weight and buoyancy, and optional drag. It shares the
body interface (lines end on it with ``BodyEnd(k, (0, 0, 0))`` and it sits in
``Scene.bodies``), with the same 1-D solver-state layout as a rigid body
[η (6), η̇ (6)] whose rotational entries stay zero, so statics, the Newton solve
and the error norm treat it like any body.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array

from .._checks import check_finite, check_nonnegative
from .._numerics import abs_times


class ConnectionPoint(eqx.Module):
    """A free point mass at ``origin`` (3,) [m].

    Args:
        mass: [kg] (mass + added_mass > 0). The lines' end forces already include
            the wet weight of their end half-elements but not their inertia: to
            match a line node, give the point their mass and a volume that makes
            that mass neutral (see ``tests/test_connection_point.py``).
        volume: displaced volume [m³] (buoyancy ρVg).
        added_mass: translational added mass [kg] (e.g. Ca·ρV).
        cda: drag area Cd·A [m²]: drag ½ρ·CdA·|v|v.
        rho, g: water density [kg/m³] and gravity [m/s²].
        current: optional :class:`~moorjax.model.environment.AbstractCurrent`:
            the drag then acts on the velocity relative to the water at the
            point's height (MoorDyn's points do the same).
    """

    mass: Array
    added: Array
    origin: Array
    static_force: Array
    cda: Array
    rho: Array
    current: object = None
    label: str = eqx.field(static=True, default="point")

    radiation = None
    damping = None
    loads = ()
    half_size = None

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
        net = (float(rho) * float(volume) - float(mass)) * float(g)
        self.static_force = jnp.array([0.0, 0.0, net, 0.0, 0.0, 0.0])
        self.cda = jnp.asarray(cda, dtype=float)
        self.rho = jnp.asarray(rho, dtype=float)
        self.current = current
        self.label = str(label)

    @property
    def hydrostatic(self):
        """No restoring in translation; the (frozen) rotations get a unit stiffness so
        that the system statics stay well posed."""
        return jnp.diag(jnp.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0]))

    @property
    def n_radiation(self) -> int:
        return 0

    def rest_state(self, pose=None) -> Array:
        pose = jnp.zeros(6) if pose is None else jnp.asarray(pose, dtype=float).reshape(6)
        return jnp.concatenate([pose.at[3:].set(0.0), jnp.zeros(6)])

    @staticmethod
    def split(z):
        return z[:6], z[6:12], z[12:]

    def point_position(self, pose, local) -> Array:
        return self.origin + pose[:3] + local

    def point_velocity(self, pose, velocity, local) -> Array:
        return jnp.broadcast_to(velocity[:3], jnp.shape(local))

    def wrench(self, pose, local, force) -> Array:
        return jnp.concatenate([jnp.sum(force, axis=0), jnp.zeros(3)])

    def rate(self, t, z, mooring) -> Array:
        pose, vel, _ = self.split(z)
        f = self.static_force[:3] + mooring[:3]
        if self.cda is not None:
            u = vel[:3]
            if self.current is not None:
                u = u - self.current.velocity(self.origin[2] + pose[2], t)
            f = f - 0.5 * self.rho * self.cda * abs_times(u)
        acc = f / (self.mass + self.added)
        zero = jnp.zeros(3)
        return jnp.concatenate([vel[:3], zero, acc, zero])

    def energy(self, z) -> Array:
        _, vel, _ = self.split(z)
        return 0.5 * (self.mass + self.added) * vel[:3] @ vel[:3]
