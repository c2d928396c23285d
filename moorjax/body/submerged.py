"""A free submerged rigid body with six degrees of freedom (MoorDyn's free body).

MoorDyn v2's ``BODIES`` row with attachment ``free``: a rigid body that moves
under the lines fixed in it, its weight and buoyancy, its own drag and added
mass, with no waterplane (no hydrostatic stiffness, unlike the floating
:class:`~moorjax.body.RigidBody`). Its loads, all computed from the body's
parameters whenever it is evaluated (so ``jax.grad`` reaches them):

- weight −m·g·ẑ at the centre of gravity ``cg`` and buoyancy ρ·V·g·ẑ at the
  centre of buoyancy ``cb`` (MoorDyn puts both at the CG: the deck builder
  gives ``cb = cg``);
- drag ½ρ·R·diag(CdA)·Rᵀ·u·|u| on the velocity ``u`` of the water relative to
  the reference point (the current at its depth and the environment's waves
  there, if any; statics: the current only, the mean state) and ½ρ·R·diag(CdA_rot)·Rᵀ·(−ω)·|ω|
  on the rotation (MoorDyn's form: |u| is the norm of the vector);
- added mass ρ·V·Ca (translation, body axes) at the reference point;
- fixtures: points fixed in the body with their own mass [kg] (weighed and
  inertial), volume [m³] (buoyant) and an inertia-only 3×3 mass [kg] (the
  points' Ca·ρ·V and the lines' end nodes, whose weight the lines' end forces
  already carry).

Pose η = (x, y, z [m] of the reference point relative to ``origin``, then the
angles roll, pitch, yaw [rad] added to ``orientation``), with MoorDyn's
rotation R = Rx(roll)·Ry(pitch)·Rz(yaw) (:mod:`moorjax.io.frames`); a point p
fixed in the body is at origin + η[:3] + R·p.

Solver state ``[η (6), v (3), ω (3)]``: the velocity slots hold the reference
point's velocity v [m/s] and the angular velocity ω [rad/s] in global axes
(MoorDyn's body state), not the angles' rates: the angles move with
d(angles)/dt = E(angles)⁻¹·ω (singular at pitch ±90°, where the yaw and roll
axes align). Rigid-body dynamics about the reference point O, in global axes:

    M(η)·[a_O; ω̇] = [F; τ_O] − [ω×(ω×S); ω×(I_O·ω)]

with S = Σm·r the first moment and I_O the inertia of the rigid masses about O
(body and fixture masses), M the rigid plus added mass. (MoorDyn omits the
gyroscopic term ω×(I_O·ω) and takes the centripetal term with all of M's
translational mass at the CG; both are second order in ω.)
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._checks import check_finite, check_nonnegative
from .._numerics import abs_times, as_float
from .base import AbstractBody


def moordyn_rotation(angles) -> Array:
    """R = Rx(roll)·Ry(pitch)·Rz(yaw) (3, 3) from angles (3,) [rad] (MoorDyn's order)."""
    phi, theta, psi = angles[0], angles[1], angles[2]
    c, s = jnp.cos, jnp.sin
    rx = jnp.array([[1.0, 0.0, 0.0], [0.0, c(phi), -s(phi)], [0.0, s(phi), c(phi)]])
    ry = jnp.array([[c(theta), 0.0, s(theta)], [0.0, 1.0, 0.0], [-s(theta), 0.0, c(theta)]])
    rz = jnp.array([[c(psi), -s(psi), 0.0], [s(psi), c(psi), 0.0], [0.0, 0.0, 1.0]])
    return rx @ ry @ rz


def angular_velocity_map(angles) -> Array:
    """E (3, 3) with ω = E·d(angles)/dt for :func:`moordyn_rotation`."""
    phi, theta = angles[0], angles[1]
    c, s = jnp.cos, jnp.sin
    # columns: x, Rx·y, Rx·Ry·z
    return jnp.array([[1.0, 0.0, s(theta)],
                      [0.0, c(phi), -s(phi) * c(theta)],
                      [0.0, s(phi), c(phi) * c(theta)]])


def _skew(r) -> Array:
    """[r]× (…, 3, 3): [r]×·x = r × x."""
    x, y, z = r[..., 0], r[..., 1], r[..., 2]
    o = jnp.zeros_like(x)
    return jnp.stack([jnp.stack([o, -z, y], -1), jnp.stack([z, o, -x], -1),
                      jnp.stack([-y, x, o], -1)], -2)


def _translate(mass3, r) -> Array:
    """6×6 mass matrix about O of a 3×3 mass ``mass3`` (…, 3, 3) at arm r (…, 3), summed."""
    sk = _skew(r)
    top = jnp.concatenate([mass3, -mass3 @ sk], axis=-1)
    bottom = jnp.concatenate([sk @ mass3, -sk @ mass3 @ sk], axis=-1)
    return jnp.sum(jnp.concatenate([top, bottom], axis=-2).reshape(-1, 6, 6), axis=0)


def _vec(value, n, name, unit):
    v = as_float(value)
    if v.ndim == 0:
        v = (jnp.broadcast_to(v, (n,)) if isinstance(v, jax.core.Tracer)
             else as_float(np.broadcast_to(np.asarray(v), (n,))))
    if v.shape != (n,):
        raise ValueError(f"{name} must be a scalar or have {n} values [{unit}], got shape {v.shape}")
    check_finite(v, name, unit)
    return v


@eqx.filter_jit
def _rest_mass_matrix(body):
    """The mass matrix at η = 0 (one small program for the constructor's check,
    not one eager XLA operation per array operation)."""
    return body.mass_matrix(jnp.zeros(6))


@eqx.filter_jit
def _hydrostatic(body):
    """−∂(weight and buoyancy)/∂η at η = 0 (equinox evaluates the property when
    a body is built: one small program)."""
    return -jax.jacfwd(body.gravity_wrench)(jnp.zeros(6))


class SubmergedBody(AbstractBody):
    """A free 6-DOF body (see the module notes).

    Args:
        mass: body mass [kg] (≥ 0).
        origin: (3,) reference point at η = 0 [m].
        orientation: (3,) roll, pitch, yaw at η = 0 [rad].
        cg: (3,) centre of gravity in body axes relative to the reference point [m].
        inertia: (3,) moments of inertia about the CG in body axes [kg·m²].
        volume: displaced volume [m³] (buoyancy ρ·V·g at ``cb``).
        cb: (3,) centre of buoyancy in body axes [m]; default ``cg`` (MoorDyn).
        cda: (6,) drag areas Cd·A in body axes: x, y, z [m²], then about x, y, z [m²·m³]
            (a scalar: all six).
        ca: (3,) added-mass coefficients in body axes [-] (of ρ·V).
        fixtures: optional ``(points (k, 3) [m] in body axes, mass (k,) [kg],
            volume (k,) [m³], inertia-only mass (k, 3, 3) [kg] in global axes)``.
        rho, g: water density [kg/m³] and gravity [m/s²].
        current: optional :class:`~moorjax.model.environment.AbstractCurrent`
            (drag on the velocity relative to the water at the reference point).
        label: a name (not traced).
    """

    mass: Array
    origin: Array
    orientation: Array
    cg: Array
    inertia: Array
    volume: Array
    cb: Array
    cda: Array
    ca: Array
    fixture_points: Array
    fixture_mass: Array
    fixture_volume: Array
    fixture_inertia: Array
    rho: Array
    g: Array
    current: object = None
    label: str = eqx.field(static=True, default="body")

    def __init__(self, mass, origin, *, orientation=(0.0, 0.0, 0.0), cg=(0.0, 0.0, 0.0),
                 inertia=(0.0, 0.0, 0.0), volume=0.0, cb=None, cda=0.0, ca=0.0, fixtures=None,
                 rho=1025.0, g=9.80665, current=None, label="body"):
        check_nonnegative(mass, f"body {label!r} mass", "kg")
        check_nonnegative(volume, f"body {label!r} volume", "m³")
        self.mass = as_float(mass)
        self.origin = _vec(origin, 3, f"body {label!r} reference point", "m")
        self.orientation = _vec(orientation, 3, f"body {label!r} orientation", "rad")
        self.cg = _vec(cg, 3, f"body {label!r} centre of gravity", "m")
        self.inertia = _vec(inertia, 3, f"body {label!r} moments of inertia", "kg·m²")
        check_nonnegative(self.inertia, f"body {label!r} moments of inertia", "kg·m²")
        self.volume = as_float(volume)
        self.cb = self.cg if cb is None else _vec(cb, 3, f"body {label!r} centre of buoyancy", "m")
        self.cda = _vec(cda, 6, f"body {label!r} CdA", "m²")
        check_nonnegative(self.cda, f"body {label!r} CdA", "m²")
        self.ca = _vec(ca, 3, f"body {label!r} Ca", "-")
        check_nonnegative(self.ca, f"body {label!r} Ca", "-")
        if fixtures is None:
            fixtures = (np.zeros((0, 3)), np.zeros(0), np.zeros(0), np.zeros((0, 3, 3)))
        pts, fm, fv, fi = fixtures
        k = int(np.size(pts)) // 3
        self.fixture_points = as_float(pts, (k, 3))
        self.fixture_mass = as_float(fm, (k,))
        self.fixture_volume = as_float(fv, (k,))
        self.fixture_inertia = as_float(fi, (k, 3, 3))
        check_nonnegative(self.fixture_mass, f"body {label!r} fixture masses", "kg")
        self.rho = as_float(rho)
        self.g = as_float(g)
        self.current = current
        self.label = str(label)
        try:
            m6 = np.asarray(_rest_mass_matrix(self))
        except (jax.errors.ConcretizationTypeError, jax.errors.TracerArrayConversionError):
            return  # traced parameters (jax.grad, vmap): no check
        eig = np.linalg.eigvalsh(0.5 * (m6 + m6.T))
        if not np.all(eig > 0):
            raise ValueError(
                f"body {label!r}: the 6×6 mass matrix (body Mass [kg], I [kg·m²], added mass ρ·V·Ca "
                f"and the masses fixed in it) is singular (eigenvalues {np.array2string(eig, precision=3)}); "
                "give the body a positive Mass and moments of inertia I")

    @property
    def half_size(self):
        return None

    @property
    def n_internal(self) -> int:
        return 0

    # -- geometry ------------------------------------------------------------
    def rotation(self, pose) -> Array:
        """R (3, 3) at pose η."""
        return moordyn_rotation(self.orientation + pose[3:])

    def point_position(self, pose, local) -> Array:
        return self.origin + pose[:3] + jnp.einsum("ij,...j->...i", self.rotation(pose), local)

    def point_velocity(self, pose, velocity, local) -> Array:
        """v + ω × (R·p) (``velocity`` = (v, ω) in global axes)."""
        arm = jnp.einsum("ij,...j->...i", self.rotation(pose), local)
        return velocity[:3] + jnp.cross(jnp.broadcast_to(velocity[3:], arm.shape), arm)

    def wrench(self, pose, local, force) -> Array:
        """Force and moment about the reference point (global axes) [N, N·m]."""
        arm = jnp.einsum("ij,kj->ki", self.rotation(pose), local)
        return jnp.concatenate([jnp.sum(force, axis=0), jnp.sum(jnp.cross(arm, force), axis=0)])

    # -- inertia -------------------------------------------------------------
    def _rigid(self, rot):
        """(6, 6) rigid mass about O, first moment S (3,) [kg·m], inertia I_O (3, 3)."""
        eye = jnp.eye(3)
        rc = rot @ self.cg
        i_g = rot @ jnp.diag(self.inertia) @ rot.T
        arms = self.fixture_points @ rot.T
        m6 = _translate(self.mass * eye, rc) + _translate(
            self.fixture_mass[:, None, None] * eye, arms)
        m6 = m6.at[3:, 3:].add(i_g)
        first = self.mass * rc + jnp.sum(self.fixture_mass[:, None] * arms, axis=0)
        return m6, first, m6[3:, 3:]

    def mass_matrix(self, pose) -> Array:
        """(6, 6) rigid plus added mass about the reference point, global axes."""
        rot = self.rotation(pose)
        m6, _, _ = self._rigid(rot)
        added = rot @ jnp.diag(self.rho * self.volume * self.ca) @ rot.T
        m6 = m6.at[:3, :3].add(added)
        return m6 + _translate(self.fixture_inertia, self.fixture_points @ rot.T)

    # -- loads ---------------------------------------------------------------
    def gravity_wrench(self, pose) -> Array:
        """(6,) weight and buoyancy of the body and its fixtures about O [N, N·m]."""
        rot = self.rotation(pose)
        up = jnp.array([0.0, 0.0, 1.0])
        arms = jnp.concatenate([jnp.stack([rot @ self.cg, rot @ self.cb]),
                                self.fixture_points @ rot.T])
        lift = jnp.concatenate([jnp.stack([-self.mass, self.rho * self.volume]),
                                self.rho * self.fixture_volume - self.fixture_mass]) * self.g
        forces = lift[:, None] * up
        return jnp.concatenate([jnp.sum(forces, 0), jnp.sum(jnp.cross(arms, forces), 0)])

    def drag_wrench(self, t, pose, velocity, env=None) -> Array:
        """(6,) drag on the water's velocity relative to the body [N, N·m]: the current
        and (with ``env.waves``) the wave particle velocity at the reference point."""
        rot = self.rotation(pose)
        u = -velocity[:3]
        pos = self.origin + pose[:3]
        pos_current = pos
        if env is not None and env.waves is not None:  # MoorDyn's body kinematics at its reference point
            eta, u_wave, _ = env.waves.kinematics(pos, t)
            u = u + u_wave
            pos_current = pos.at[2].set(env.waves.current_height(pos, eta))
        if self.current is not None:
            u = u + self.current.velocity_at(pos_current, t)
        f = 0.5 * self.rho * rot @ (self.cda[:3] * (rot.T @ abs_times(u)))
        m = 0.5 * self.rho * rot @ (self.cda[3:] * (rot.T @ abs_times(-velocity[3:])))
        return jnp.concatenate([f, m])

    # -- interface -----------------------------------------------------------
    def rate(self, t, z, mooring, env=None) -> Array:
        pose, vel, _ = self.split(z)
        rot = self.rotation(pose)
        omega = vel[3:]
        _, first, i_o = self._rigid(rot)
        bias = jnp.concatenate([jnp.cross(omega, jnp.cross(omega, first)),
                                jnp.cross(omega, i_o @ omega)])
        load = self.gravity_wrench(pose) + self.drag_wrench(t, pose, vel, env) + mooring - bias
        acc = jnp.linalg.solve(self.mass_matrix(pose), load)
        angle_rates = jnp.linalg.solve(angular_velocity_map(self.orientation + pose[3:]), omega)
        return jnp.concatenate([vel[:3], angle_rates, acc])

    def mean_load(self, pose, t=0.0, env=None, *, loads: bool = True) -> Array:
        """Weight and buoyancy at ``pose``; with ``loads``, the current's drag on the body at rest."""
        f = self.gravity_wrench(pose)
        if loads and self.current is not None:
            f = f + self.drag_wrench(t, pose, jnp.zeros(6))
        return f

    @property
    def hydrostatic(self) -> Array:
        """(6, 6) restoring stiffness −∂(weight and buoyancy)/∂η at η = 0 (no waterplane:
        only the moments of weight and buoyancy about the reference point)."""
        return _hydrostatic(self)

    def energy(self, z) -> Array:
        """Kinetic energy ½[v, ω]ᵀ·M·[v, ω] plus the potential of weight and buoyancy [J]."""
        pose, vel, _ = self.split(z)
        rot = self.rotation(pose)
        zs = (self.origin[2] + pose[2]
              + jnp.concatenate([jnp.stack([(rot @ self.cg)[2], (rot @ self.cb)[2]]),
                                 (self.fixture_points @ rot.T)[:, 2]]))
        lift = jnp.concatenate([jnp.stack([-self.mass, self.rho * self.volume]),
                                self.rho * self.fixture_volume - self.fixture_mass]) * self.g
        return 0.5 * vel @ self.mass_matrix(pose) @ vel - jnp.sum(lift * zs)
