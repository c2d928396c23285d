"""A rigid floating body with six degrees of freedom (Wu et al. Eq. 1, Cummins form).

    (M + A∞) η̈ + ∫₀ᵗ K(t−τ) η̇(τ) dτ + C η = F_wave + F_moor + F_wind + F_current

η = (surge, sway, heave [m], roll, pitch, yaw [rad]) is the displacement of the
body's reference point (its centre of gravity, ``origin`` in the global frame at
η = 0) and of its orientation. The hydrodynamic model is linear, as in the
paper: rotations are small, and the radiation, hydrostatic and wave terms act on
η and η̇ directly, the angles being the rotational coordinates. The *mooring*
geometry is not linearised: fairleads move with the full rotation
R = Rz(ψ)·Ry(θ)·Rx(φ), their velocities are the exact time derivatives, and the
lines' moments enter as the angles' generalised forces Jᵀf (J = ∂(R·p)/∂angles),
so the coupling exchanges energy exactly.

The memory integral is replaced by a fitted state-space model
(:class:`moorjax.body.hydro.RadiationStateSpace`): ξ̇ = A ξ + B η̇,
F_rad = −C ξ. At η = 0 weight and buoyancy are assumed to balance (give
``static_force`` otherwise).

Solver state of a body: one 1-D array ``[η (6), η̇ (6), ξ (m)]`` (see
:class:`~moorjax.body.base.AbstractBody`, the interface this class implements).

Optional structure (``radiation``, ``damping``, ``loads``) is never traced when
absent.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._checks import check_finite, check_positive
from .base import AbstractBody
from .waves import WaveLoads

DOF_NAMES = ("surge", "sway", "heave", "roll", "pitch", "yaw")


def rotation(angles) -> Array:
    """R = Rz(ψ)·Ry(θ)·Rx(φ) (3, 3) from (roll φ, pitch θ, yaw ψ) [rad]."""
    phi, theta, psi = angles[0], angles[1], angles[2]
    c, s = jnp.cos, jnp.sin
    rx = jnp.array([[1.0, 0.0, 0.0], [0.0, c(phi), -s(phi)], [0.0, s(phi), c(phi)]])
    ry = jnp.array([[c(theta), 0.0, s(theta)], [0.0, 1.0, 0.0], [-s(theta), 0.0, c(theta)]])
    rz = jnp.array([[c(psi), -s(psi), 0.0], [s(psi), c(psi), 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx


def _arm_jacobian(angles, local):
    """∂(R(angles)·p)/∂angles (…, 3, 3) for body-fixed points p (…, 3)."""
    d_rot = jax.jacfwd(rotation)(angles)  # (3, 3, 3): ∂R_ij/∂angle_k
    return jnp.einsum("ijk,...j->...ik", d_rot, local)


def _matrix(value, name, unit, symmetric=False):
    m = jnp.asarray(value, dtype=float)
    if m.shape != (6, 6):
        raise ValueError(f"{name} must be a 6×6 matrix [{unit}], got shape {m.shape}")
    check_finite(m, name, unit)
    if symmetric:
        mn = np.asarray(m)
        if not np.allclose(mn, mn.T, rtol=1e-6, atol=1e-9 * np.abs(mn).max()):
            raise ValueError(f"{name} [{unit}] must be symmetric")
    return m


class RigidBody(AbstractBody):
    """A floating body (all matrices about its centre of gravity, global axes).

    Args:
        mass: body mass [kg] (scalar) — or give ``mass_matrix``.
        inertia: (3,) principal moments Ixx, Iyy, Izz [kg·m²] with ``mass``.
        mass_matrix: full (6, 6) rigid-body mass matrix instead of mass/inertia.
        added_mass: (6, 6) infinite-frequency added mass A∞ [kg, kg·m, kg·m²].
        hydrostatic: (6, 6) hydrostatic restoring matrix C [N/m, N, N·m/rad];
            C[2, 2] (heave) must be positive.
        origin: (3,) position of the centre of gravity at η = 0 [m].
        radiation: optional :class:`RadiationStateSpace` (memory of the waves
            the body radiates); ``None``: no radiation damping.
        damping: optional (6, 6) linear damping [N·s/m, ...] (e.g. viscous).
        loads: tuple of external loads, each with ``force(t) -> (6,)`` [N, N·m]
            (waves, wind, current): see :mod:`moorjax.body.waves`,
            :mod:`moorjax.body.loads`.
        static_force: (6,) constant force/moment at η = 0 (e.g. a weight–
            buoyancy imbalance) [N, N·m]; default none.
        half_size: optional (3,) half extents of the hull's bounding box about the
            centre of gravity [m]; used to reject fairleads outside the body.
        label: a name (not traced).
    """

    mass_matrix: Array
    added_mass: Array
    hydrostatic: Array
    origin: Array
    radiation: eqx.Module | None
    damping: Array | None
    loads: tuple
    static_force: Array | None
    half_size: Array | None
    label: str = eqx.field(static=True, default="body")

    def __init__(self, mass=None, inertia=None, *, mass_matrix=None, added_mass=None,
                 hydrostatic, origin=(0.0, 0.0, 0.0), radiation=None, damping=None, loads=(),
                 static_force=None, half_size=None, label="body"):
        if mass_matrix is None:
            if mass is None or inertia is None:
                raise ValueError("give the body's mass [kg] and inertia (3,) [kg·m²], or mass_matrix")
            check_positive(mass, "body mass", "kg")
            check_positive(inertia, "body moments of inertia", "kg·m²")
            inertia = jnp.asarray(inertia, dtype=float).reshape(3)
            mass_matrix = jnp.diag(jnp.concatenate([jnp.full(3, float(mass)), inertia]))
        self.mass_matrix = _matrix(mass_matrix, "body mass matrix", "kg, kg·m²", symmetric=True)
        self.added_mass = (jnp.zeros((6, 6)) if added_mass is None
                           else _matrix(added_mass, "infinite-frequency added mass", "kg, kg·m²"))
        self.hydrostatic = _matrix(hydrostatic, "hydrostatic restoring matrix", "N/m, N·m/rad")
        c33 = np.asarray(self.hydrostatic)[2, 2]
        if not c33 > 0:
            raise ValueError(
                f"body {label!r}: hydrostatic stiffness in heave C[2,2] = {c33:g} N/m must be "
                "positive (a floating body needs a waterplane)")
        total = np.asarray(self.mass_matrix + self.added_mass)
        if not np.all(np.linalg.eigvalsh(0.5 * (total + total.T)) > 0):
            raise ValueError(f"body {label!r}: mass + added mass must be positive definite")
        check_finite(origin, "body origin", "m")
        self.origin = jnp.asarray(origin, dtype=float).reshape(3)
        self.radiation = radiation
        self.damping = None if damping is None else _matrix(damping, "body damping", "N·s/m")
        self.loads = tuple(loads)
        for ld in self.loads:
            if not callable(getattr(ld, "force", None)):
                raise TypeError(f"body load {ld!r} has no force(t) method")
        self.static_force = None if static_force is None else jnp.asarray(static_force, float).reshape(6)
        if half_size is not None:
            check_positive(half_size, "body half size", "m")
            half_size = jnp.asarray(half_size, dtype=float).reshape(3)
        self.half_size = half_size
        self.label = str(label)

    # -- state layout -------------------------------------------------------
    @property
    def n_radiation(self) -> int:
        return 0 if self.radiation is None else int(self.radiation.A.shape[0])

    @property
    def n_internal(self) -> int:
        """The radiation states ξ."""
        return self.n_radiation

    # -- kinematics ---------------------------------------------------------
    def point_position(self, pose, local) -> Array:
        """Global position (…, 3) [m] of body-fixed points ``local`` (…, 3) (about the CoG)."""
        rot = rotation(pose[3:])
        return self.origin + pose[:3] + jnp.einsum("ij,...j->...i", rot, local)

    def point_velocity(self, pose, velocity, local) -> Array:
        """Global velocity (…, 3) [m/s] of body-fixed points: d/dt of
        :meth:`point_position` (exact for the angles as coordinates)."""
        return velocity[:3] + jnp.einsum("...ik,k->...i", _arm_jacobian(pose[3:], local), velocity[3:])

    def wrench(self, pose, local, force) -> Array:
        """Generalised (6,) force [N, N·m] of point forces (k, 3) applied at ``local`` (k, 3).

        The rotational part is Jᵀf with J = ∂(R·p)/∂(φ, θ, ψ), the work-conjugate
        of the angles (so the coupling exchanges energy exactly); for small
        angles it is the moment (R·p) × f about the centre of gravity.
        """
        jac = _arm_jacobian(pose[3:], local)  # (k, 3, 3)
        return jnp.concatenate([jnp.sum(force, axis=0), jnp.einsum("kij,ki->j", jac, force)])

    # -- dynamics -----------------------------------------------------------
    def external_force(self, t, pose, velocity, rad_state) -> Array:
        """All forces but the mooring's (6,) [N, N·m] at time t."""
        f = -self.hydrostatic @ pose
        if self.static_force is not None:
            f = f + self.static_force
        if self.damping is not None:
            f = f - self.damping @ velocity
        if self.radiation is not None:
            f = f + self.radiation.force(rad_state)
        for ld in self.loads:
            f = f + ld.force(t)
        return f

    def rate(self, t, z, mooring, env=None) -> Array:
        """dz/dt of the solver state given the mooring wrench (6,) on the body
        (``env`` is not needed: the body's matrices hold the water's properties)."""
        pose, vel, xi = self.split(z)
        total = self.mass_matrix + self.added_mass
        acc = jnp.linalg.solve(total, self.external_force(t, pose, vel, xi) + mooring)
        parts = [vel, acc]
        if self.radiation is not None:
            parts.append(self.radiation.rate(xi, vel))
        return jnp.concatenate(parts)

    def mean_load(self, pose, t=0.0, env=None, *, loads: bool = True) -> Array:
        """Static load at ``pose``: −Cη, ``static_force`` and (with ``loads``) each
        external load's mean: a wave load's mean slow drift (its first-order
        force averages to zero), any other load's force at time ``t``."""
        f = -self.hydrostatic @ pose
        if self.static_force is not None:
            f = f + self.static_force
        if loads:
            for ld in self.loads:
                f = f + mean_load_of(ld, t)
        return f

    def energy(self, z) -> Array:
        """Kinetic (with A∞) plus hydrostatic energy ½η̇ᵀ(M+A∞)η̇ + ½ηᵀCη [J]."""
        pose, vel, _ = self.split(z)
        return 0.5 * vel @ (self.mass_matrix + self.added_mass) @ vel + 0.5 * pose @ self.hydrostatic @ pose


def mean_load_of(load, t) -> Array:
    """The mean (6,) [N, N·m] of one external load: a :class:`WaveLoads`' mean
    drift, else the load's force at time ``t`` (steady loads)."""
    if isinstance(load, WaveLoads):
        return load.mean_drift()
    return load.force(t)
