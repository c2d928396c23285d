"""The water the lines live in: depth, density, gravity, seabed, current and waves.

Axes: z up, z = 0 at the free surface, the seabed at z = −depth.
``seabed``, ``current`` and ``waves`` are optional structure: a scene without
them never traces contact, current or wave terms.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array

from .._checks import check_finite, check_nonnegative, check_positive
from .._numerics import as_float
from .waves import AbstractWaveKinematics


class SeabedFriction(eqx.Module):
    """Smoothed Coulomb friction on the seabed.

    Friction force −μ·N·u/√(|u|² + v_slip²) on the horizontal node velocity u:
    Coulomb above the slip velocity, viscous below it (so it is differentiable).

    Args:
        mu: friction coefficient [-].
        v_slip: regularisation velocity [m/s].
    """

    mu: Array
    v_slip: Array

    def __init__(self, mu, v_slip=1e-2):
        check_nonnegative(mu, "seabed friction coefficient", "-")
        check_positive(v_slip, "friction slip velocity", "m/s")
        self.mu = as_float(mu)
        self.v_slip = as_float(v_slip)


class Bathymetry(eqx.Module):
    """A seabed height grid z_b(x, y) [m] (MoorDyn's ``SeafloorFile``), bilinear
    inside the grid and held at the nearest edge outside it (as MoorDyn).

    Args:
        x: (nx,) increasing grid x [m]; y: (ny,) increasing grid y [m].
        z: (nx, ny) seabed heights [m] (negative below the surface).
    """

    x: Array
    y: Array
    z: Array

    def __init__(self, x, y, z):
        x, y, z = (jnp.asarray(a, dtype=float) for a in (x, y, z))
        if x.ndim != 1 or y.ndim != 1 or z.shape != (x.shape[0], y.shape[0]):
            raise ValueError(f"bathymetry needs x (nx,), y (ny,), z (nx, ny); got {x.shape}, {y.shape}, "
                             f"{z.shape}")
        for arr, name in ((x, "x"), (y, "y")):
            check_finite(arr, f"bathymetry {name}", "m")
            if arr.shape[0] > 1 and not bool(jnp.all(jnp.diff(arr) > 0)):
                raise ValueError(f"bathymetry grid {name} [m] must be strictly increasing")
        check_finite(z, "bathymetry heights", "m")
        self.x, self.y, self.z = x, y, z

    def height(self, x, y):
        """Seabed height z_b [m] at (x, y) (any equal shapes), bilinear, clamped."""
        i, fx = _bracket(self.x, x)
        j, fy = _bracket(self.y, y)
        i1 = jnp.minimum(i + 1, self.x.shape[0] - 1)
        j1 = jnp.minimum(j + 1, self.y.shape[0] - 1)
        z = self.z
        return ((1 - fx) * (1 - fy) * z[i, j] + fx * (1 - fy) * z[i1, j]
                + (1 - fx) * fy * z[i, j1] + fx * fy * z[i1, j1])

    def lowest(self) -> float:
        """The deepest seabed height [m] (concrete grids only)."""
        return float(jnp.min(self.z))


class Seabed(eqx.Module):
    """Vertical spring–damper contact (MoorDyn's kBot/cBot), optional friction.

    Contact pressure per unit line length and diameter: kBot·δ − cBot·ż for a
    penetration δ > 0, so the force on a node is (kBot·δ − cBot·ż)·d·l_node.

    With a :class:`Bathymetry` the seabed is z_b(x, y) instead of the flat
    z = −depth, and the contact acts along the local normal n of the seabed
    surface: penetration δ = (z_b − z)·n_z (the distance below its tangent
    plane), force (kBot·δ − cBot·v·n)·d·l_node·n, friction on the velocity
    along the surface. (MoorDyn v2 takes the local depth but keeps the contact
    vertical; the two agree to O(slope²).)

    **Damping ramp (differs from MoorDyn).** MoorDyn applies the full cBot the
    moment a node penetrates, so the contact force jumps by cBot·|ż|·d·l when a
    node lands (≈ 4e5 N for a 22 m chain segment landing at 0.7 m/s): the
    implicit stage equations are then discontinuous in position and Newton
    stalls, at fixed steps it fails. Here the damping is ramped in with a
    smoothstep s(δ/δ_r) = 3x² − 2x³ (x = δ/δ_r clipped to [0, 1]) over a depth
    δ_r: by default the line's *rest penetration* w/(kBot·d) (wet weight w
    [N/m], diameter d [m]; 2.6 mm for the chain of reference case A), so nodes
    resting on the bed (δ ≈ δ_r) are damped fully as in MoorDyn and only the
    first millimetres of a landing are softened. The contact force is then
    continuous (C¹ in the damping) in position. Measured on reference case A
    (N = 40): the converged fairlead tension moves by 0.03 % of its standard
    deviation; see ``benchmarks/README.md``. ``damping_depth=0`` restores
    MoorDyn's step.

    Args:
        stiffness: kBot [Pa/m].
        damping: cBot [Pa·s/m].
        friction: optional :class:`SeabedFriction`.
        bathymetry: optional :class:`Bathymetry` (default: flat at −depth).
        damping_depth: δ_r [m], the penetration over which cBot is ramped in;
            default (None): each line's rest penetration w/(kBot·d); 0: no ramp
            (MoorDyn's law).
    """

    stiffness: Array
    damping: Array
    friction: SeabedFriction | None
    bathymetry: Bathymetry | None = None
    damping_depth: Array | None = None

    def __init__(self, stiffness=3e6, damping=3e5, friction: SeabedFriction | None = None,
                 bathymetry: Bathymetry | None = None, damping_depth=None):
        check_positive(stiffness, "seabed stiffness kBot", "Pa/m")
        check_nonnegative(damping, "seabed damping cBot", "Pa·s/m")
        self.stiffness = as_float(stiffness)
        self.damping = as_float(damping)
        self.friction = friction
        self.bathymetry = bathymetry
        if damping_depth is not None:
            check_nonnegative(damping_depth, "seabed damping ramp depth", "m")
            damping_depth = as_float(damping_depth)
        self.damping_depth = damping_depth

    def rest_penetration(self, wet_weight, diameter):
        """Penetration δ [m] at which the spring carries a line of wet weight
        ``wet_weight`` [N/m] and diameter ``diameter`` [m] lying on the bed:
        max(w, 0)/(kBot·d)."""
        return jnp.maximum(wet_weight, 0.0) / (self.stiffness * diameter)

    def damping_fraction(self, pen, wet_weight, diameter):
        """Fraction (0 … 1) of cBot acting at penetrations ``pen`` [m]: 0 above
        the bed, a smoothstep over the ramp depth δ_r (see the class), 1 below."""
        ramp = (self.rest_penetration(wet_weight, diameter) if self.damping_depth is None
                else self.damping_depth)
        positive = ramp > 0
        x = jnp.clip(pen / jnp.where(positive, ramp, 1.0), 0.0, 1.0)
        return jnp.where(positive, x * x * (3.0 - 2.0 * x), jnp.where(pen > 0, 1.0, 0.0))

    def contact(self, r, v, diameter, wet_weight, depth):
        """The bed's load per unit line length on points r (…, 3) [m] moving at v
        (…, 3) [m/s] (``None``: at rest): (load (…, 3) [N/m], height above the
        bed z − z_b (…) [m] (< 0: below), the bed's unit normal n (…, 3)).

        The load is (kBot·δ − cBot·s(δ)·v·n)·d·n for a penetration δ > 0 along the
        normal (the damping ramp s: :meth:`damping_fraction`), and with friction
        −μ·kBot·δ·d·v_t/√(|v_t|² + v_slip²) on the velocity v_t along the bed.
        Flat bed (no bathymetry): z_b = −depth, n = e_z."""
        z = r[..., 2]
        if self.bathymetry is None:
            zb = -depth * jnp.ones_like(z)
            n = jnp.zeros_like(r).at[..., 2].set(1.0)
            pen = zb - z
        else:
            import jax

            def height(xy):
                return self.bathymetry.height(xy[0], xy[1])

            flat = r.reshape(-1, 3)[:, :2]
            zb, grad = jax.vmap(jax.value_and_grad(height))(flat)
            zb, grad = zb.reshape(z.shape), grad.reshape(z.shape + (2,))
            up = jnp.concatenate([-grad, jnp.ones_like(zb)[..., None]], axis=-1)
            n = up / jnp.sqrt(jnp.sum(up * up, axis=-1, keepdims=True))  # never zero: n_z > 0
            pen = (zb - z) * n[..., 2]  # the distance below the bed's tangent plane
        spring = jnp.where(pen > 0, self.stiffness * pen * diameter, 0.0)
        if v is None:
            return spring[..., None] * n, z - zb, n
        vn = jnp.sum(v * n, axis=-1)
        ramp = self.damping_fraction(pen, wet_weight, diameter)
        load = (spring - self.damping * ramp * vn * diameter)[..., None] * n
        if self.friction is not None:
            fr = self.friction
            vt = v - vn[..., None] * n
            speed = jnp.sqrt(jnp.sum(vt * vt, axis=-1) + fr.v_slip**2)
            load = load - (fr.mu * spring / speed)[..., None] * vt
        return load, z - zb, n


class AbstractCurrent(eqx.Module):
    """A current field U(x, y, z, t) [m/s] (steady fields ignore t).

    The physics samples every current through :meth:`velocity_at`, so a field
    that varies in x and y (:class:`GridCurrent`) acts on lines, points and
    bodies as a depth profile does.
    """

    #: the field does not change in time (structure: a class's answer, not a
    #: value's); unknown fields are taken to change
    time_invariant: ClassVar[bool] = False

    @abc.abstractmethod
    def velocity_at(self, position: Array, t=0.0) -> Array:
        """Current velocity (..., 3) [m/s] at positions (..., 3) [m] and time t [s]."""


class AbstractDepthCurrent(AbstractCurrent):
    """A current that depends on the height z (and time) only: U(z, t) [m/s]."""

    @abc.abstractmethod
    def velocity(self, z: Array, t=0.0) -> Array:
        """Current velocity (..., 3) [m/s] at heights z (...) [m] and time t [s]."""

    def velocity_at(self, position, t=0.0):
        return self.velocity(jnp.asarray(position)[..., 2], t)


class UniformCurrent(AbstractDepthCurrent):
    """The same current at every depth. ``velocity``: (3,) [m/s]."""

    time_invariant: ClassVar[bool] = True
    u: Array

    def __init__(self, velocity):
        check_finite(velocity, "current velocity", "m/s")
        self.u = as_float(velocity, 3)

    def velocity(self, z, t=0.0):
        return jnp.broadcast_to(self.u, jnp.shape(z) + (3,))


class ProfileCurrent(AbstractDepthCurrent):
    """A depth profile, linearly interpolated (held constant beyond its ends).

    Args:
        z: increasing heights [m] (negative below the surface).
        velocity: (len(z), 3) current velocities [m/s].
    """

    time_invariant: ClassVar[bool] = True
    z: Array
    u: Array

    def __init__(self, z, velocity):
        z = jnp.asarray(z, dtype=float)
        u = jnp.asarray(velocity, dtype=float)
        if z.ndim != 1 or u.shape != (z.shape[0], 3):
            raise ValueError(f"current profile needs z (k,) and velocity (k, 3); got {z.shape}, {u.shape}")
        check_finite(z, "current profile z", "m")
        check_finite(u, "current profile velocity", "m/s")
        if z.shape[0] > 1 and not bool(jnp.all(jnp.diff(z) > 0)):
            raise ValueError("current profile heights z [m] must be strictly increasing")
        self.z, self.u = z, u

    def velocity(self, z, t=0.0):
        zf = jnp.ravel(z)
        out = jnp.stack([jnp.interp(zf, self.z, self.u[:, i]) for i in range(3)], axis=-1)
        return out.reshape(jnp.shape(z) + (3,))


def _bracket(grid, x):
    """Index i and weight f with x ≈ (1 − f)·grid[i] + f·grid[i+1], clamped to the ends."""
    if grid.shape[0] == 1:
        return jnp.zeros(jnp.shape(x), int), jnp.zeros(jnp.shape(x))
    i = jnp.clip(jnp.searchsorted(grid, x, side="right") - 1, 0, grid.shape[0] - 2)
    f = jnp.clip((x - grid[i]) / (grid[i + 1] - grid[i]), 0.0, 1.0)
    return i, f


class TimeProfileCurrent(AbstractDepthCurrent):
    """A depth profile that changes in time (MoorDyn's ``Currents = 2``).

    Bilinear in z and t, held at the values of the nearest end beyond the
    tabulated heights and times (MoorDyn v2 docs, "Currents = 2 (Dynamic
    Currents Grid)": "a point outside of the defined grid (either in z value or
    in time) will use the nearest value").

    Args:
        t: (n_t,) increasing times [s].
        z: (k,) increasing heights [m] (negative below the surface).
        velocity: (n_t, k, 3) current velocities [m/s].
    """

    t: Array
    z: Array
    u: Array

    def __init__(self, t, z, velocity):
        t = jnp.asarray(t, dtype=float)
        z = jnp.asarray(z, dtype=float)
        u = jnp.asarray(velocity, dtype=float)
        if t.ndim != 1 or z.ndim != 1 or u.shape != (t.shape[0], z.shape[0], 3):
            raise ValueError(f"a time-varying current profile needs t (n,), z (k,) and velocity "
                             f"(n, k, 3); got {t.shape}, {z.shape}, {u.shape}")
        for arr, name, unit in ((t, "t", "s"), (z, "z", "m"), (u, "velocity", "m/s")):
            check_finite(arr, f"current profile {name}", unit)
        for arr, name, unit in ((t, "times t", "s"), (z, "heights z", "m")):
            if arr.shape[0] > 1 and not bool(jnp.all(jnp.diff(arr) > 0)):
                raise ValueError(f"current profile {name} [{unit}] must be strictly increasing")
        self.t, self.z, self.u = t, z, u

    def velocity(self, z, t=0.0):
        it, ft = _bracket(self.t, jnp.asarray(t, dtype=float))
        j = jnp.minimum(it + 1, self.t.shape[0] - 1)
        profile = (1.0 - ft) * self.u[it] + ft * self.u[j]  # (k, 3) at time t
        zf = jnp.ravel(z)
        out = jnp.stack([jnp.interp(zf, self.z, profile[:, i]) for i in range(3)], axis=-1)
        return out.reshape(jnp.shape(z) + (3,))


class GridCurrent(AbstractCurrent):
    """A current tabulated on a 4-D grid (x, y, z, t) (MoorDyn's ``Currents = 5``,
    ``current_profile_4d.txt``; MoorDyn v2 docs, ``docs/waterkinematics.rst``,
    "Currents = 5 (4D Current Grid)").

    Linear in each of x, y, z and t between the grid values (quadrilinear), and
    held at the nearest grid value outside the grid in any of them, as
    MoorDyn's grids (``interp_factor``/``interp4Vec``). An axis of one value is
    constant along it. (Beyond the last time MoorDyn's code repeats the table
    with period n_t·Δt, Δt its smallest time step; moorjax holds the last
    value, as MoorDyn's docs say for its grids.)

    Args:
        x: (nx,), y: (ny,), z: (nz,) strictly increasing grid coordinates [m];
        t: (nt,) strictly increasing times [s];
        velocity: (nx, ny, nz, nt, 3) current velocities [m/s].
    """

    x: Array
    y: Array
    z: Array
    t: Array
    u: Array

    def __init__(self, x, y, z, t, velocity):
        axes = [jnp.asarray(a, dtype=float) for a in (x, y, z, t)]
        u = jnp.asarray(velocity, dtype=float)
        names = (("x", "m"), ("y", "m"), ("z", "m"), ("t", "s"))
        if any(a.ndim != 1 or a.shape[0] < 1 for a in axes) or u.shape != tuple(
                a.shape[0] for a in axes) + (3,):
            raise ValueError("a 4-D current grid needs x (nx,), y (ny,), z (nz,), t (nt,) and velocity "
                             f"(nx, ny, nz, nt, 3); got {[a.shape for a in axes]}, {u.shape}")
        for a, (name, unit) in zip(axes, names):
            check_finite(a, f"current grid {name}", unit)
            if a.shape[0] > 1 and not bool(jnp.all(jnp.diff(a) > 0)):
                raise ValueError(f"current grid {name} [{unit}] must be strictly increasing")
        check_finite(u, "current grid velocity", "m/s")
        self.x, self.y, self.z, self.t = axes
        self.u = u

    def velocity_at(self, position, t=0.0):
        position = jnp.asarray(position, dtype=float)
        shape = position.shape[:-1]
        p = position.reshape(-1, 3)
        it, ft = _bracket(self.t, jnp.asarray(t, dtype=float))
        jt = jnp.minimum(it + 1, self.t.shape[0] - 1)
        u = (1.0 - ft) * self.u[:, :, :, it] + ft * self.u[:, :, :, jt]  # (nx, ny, nz, 3) at t
        for axis, grid in enumerate((self.x, self.y, self.z)):
            i, f = _bracket(grid, p[:, axis])
            j = jnp.minimum(i + 1, grid.shape[0] - 1)
            if axis == 0:
                u = (1.0 - f)[:, None, None, None] * u[i] + f[:, None, None, None] * u[j]  # (n, ny, nz, 3)
            else:
                n = jnp.arange(p.shape[0])
                lo, hi = u[n, i], u[n, j]  # drop the leading grid axis of this coordinate
                w = f.reshape((-1,) + (1,) * (lo.ndim - 1))
                u = (1.0 - w) * lo + w * hi
        return u.reshape(shape + (3,))


class Environment(eqx.Module):
    """Water depth [m], density ρ [kg/m³] (≥ 0; 0 is air), gravity g [m/s²]
    (≥ 0), optional seabed, current and waves.

    ``waves`` (an :class:`moorjax.model.waves.AbstractWaveKinematics`: wave
    components as :class:`~moorjax.model.waves.AiryWaves`, or a user's function
    as :class:`~moorjax.model.waves.ExternalWaves`) adds the wave particle
    velocity to the current in the line drag and loads the lines with the
    water's acceleration (Froude–Krylov and added-mass parts). Statics solve
    the mean state without them (:meth:`without_waves`), as MoorDyn's initial
    condition does.
    """

    depth: Array
    rho: Array
    g: Array
    seabed: Seabed | None
    current: AbstractCurrent | None
    waves: AbstractWaveKinematics | None = None

    def __init__(self, depth, rho=1025.0, g=9.80665, seabed: Seabed | None = None,
                 current: AbstractCurrent | None = None, waves: AbstractWaveKinematics | None = None):
        check_positive(depth, "water depth", "m")
        # zero is allowed, as in MoorDyn: rho = 0 is a line in air (no buoyancy,
        # drag or added mass), g = 0 a weightless system
        check_nonnegative(rho, "water density", "kg/m³")
        check_nonnegative(g, "gravity", "m/s²")
        if waves is not None and not isinstance(waves, AbstractWaveKinematics):
            raise ValueError("waves must be an AbstractWaveKinematics (moorjax.model.waves: AiryWaves, "
                             f"ExternalWaves), got {type(waves).__name__}")
        self.depth = as_float(depth)
        self.rho = as_float(rho)
        self.g = as_float(g)
        self.seabed = seabed
        self.current = current
        self.waves = waves

    def seabed_height(self, x, y) -> Array:
        """Height of the seabed [m] under (x, y) (arrays of one shape): the
        bathymetry's where the seabed has one, else −depth."""
        bathymetry = None if self.seabed is None else self.seabed.bathymetry
        if bathymetry is None:
            return -self.depth * jnp.ones_like(jnp.asarray(x, dtype=float))
        import jax

        return jax.vmap(bathymetry.height)(jnp.ravel(x), jnp.ravel(y)).reshape(jnp.shape(x))

    @property
    def steady(self) -> bool:
        """Whether the water does not change in time (no waves, no current or a
        time-invariant one): then a line's equations depend on time only through
        its ends' motions (structure, decided at trace time)."""
        return self.waves is None and (self.current is None or self.current.time_invariant)

    def without_waves(self) -> "Environment":
        """The same water without waves: the mean state that statics solve for."""
        if self.waves is None:
            return self
        return eqx.tree_at(lambda e: e.waves, self, None, is_leaf=lambda x: x is None)
