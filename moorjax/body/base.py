"""What the dynamics and the statics need of a body lines end on.

A body is anything in ``Scene.bodies``: a :class:`~moorjax.body.RigidBody` (six
degrees of freedom, Cummins form) or a :class:`~moorjax.body.ConnectionPoint`
(a free point mass) or a :class:`~moorjax.body.SubmergedBody` (MoorDyn's free
6-DOF body). Lines attach to it through
:class:`~moorjax.model.ends.BodyEnd` s; the coupling
(:mod:`moorjax.body.coupling`) asks it where those points are and how they move,
and turns the lines' end forces into a wrench on it; the vector field asks it
for its rate; the statics for its mean load at a pose.

Solver state of a body: one 1-D array ``[η (6), η̇ (6), internal states]``
(η = surge, sway, heave [m], roll, pitch, yaw [rad] of its reference point).
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array


class AbstractBody(eqx.Module):
    """Interface of a body in a scene (see the module notes).

    Subclasses provide ``origin`` (3,) [m] (the reference point at η = 0),
    ``label``, ``half_size`` ((3,) half extents in body axes [m] that
    fairleads must lie within, or ``None``), ``hydrostatic`` (6, 6) (the
    restoring stiffness, for the linearised system) and the methods below. Every
    parameter-dependent force (weights, buoyancy) is computed from the body's
    parameters when it is evaluated, so ``jax.grad`` reaches it.
    """

    origin: eqx.AbstractVar[Array]
    label: eqx.AbstractVar[str]
    half_size: eqx.AbstractVar[Array | None]
    #: (6, 6) restoring stiffness about η = 0 [N/m, N·m/rad]
    hydrostatic: eqx.AbstractVar[Array]

    # -- state layout -------------------------------------------------------
    @property
    @abc.abstractmethod
    def n_internal(self) -> int:
        """Number of internal states after [η, η̇] (e.g. radiation memory)."""

    def rest_state(self, pose=None) -> Array:
        """Solver state at rest at ``pose`` (6,) (default η = 0)."""
        pose = jnp.zeros(6) if pose is None else jnp.asarray(pose, dtype=float).reshape(6)
        return jnp.concatenate([pose, jnp.zeros(6 + self.n_internal)])

    @staticmethod
    def split(z):
        """Solver state → (η, η̇, internal states)."""
        return z[:6], z[6:12], z[12:]

    # -- kinematics and the lines' wrench ----------------------------------
    @abc.abstractmethod
    def point_position(self, pose, local) -> Array:
        """Global positions (…, 3) [m] of body-fixed points ``local`` (…, 3)."""

    @abc.abstractmethod
    def point_velocity(self, pose, velocity, local) -> Array:
        """Global velocities (…, 3) [m/s] of body-fixed points ``local``."""

    @abc.abstractmethod
    def wrench(self, pose, local, force) -> Array:
        """Generalised (6,) force [N, N·m] of point forces (k, 3) at ``local`` (k, 3)."""

    # -- dynamics and statics ---------------------------------------------
    @abc.abstractmethod
    def rate(self, t, z, mooring, env=None) -> Array:
        """dz/dt of the solver state given the lines' wrench ``mooring`` (6,);
        ``env`` is the scene's :class:`~moorjax.model.environment.Environment`
        (for bodies whose loads depend on the water)."""

    @abc.abstractmethod
    def mean_load(self, pose, t=0.0, env=None, *, loads: bool = True) -> Array:
        """(6,) static non-mooring load at ``pose`` [N, N·m]: restoring, weight
        and buoyancy, and (with ``loads``) the mean of the external loads."""

    @abc.abstractmethod
    def energy(self, z) -> Array:
        """Mechanical energy of the body's state [J] (diagnostics)."""
