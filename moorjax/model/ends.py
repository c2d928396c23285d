"""End conditions of a line: a fixed point, a prescribed motion or a body's fairlead.

An end gives its position [m], velocity [m/s] and acceleration [m/s²] at time t
[s]. Paths are pure functions of t and differentiable in their parameters.
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array

from .._checks import check_finite, check_positive
from .._numerics import as_float


class AbstractEnd(eqx.Module):
    """Where a line end is at time t."""

    @abc.abstractmethod
    def position(self, t) -> Array:
        """(3,) [m]."""

    @abc.abstractmethod
    def velocity(self, t) -> Array:
        """(3,) [m/s]."""

    @abc.abstractmethod
    def acceleration(self, t) -> Array:
        """(3,) [m/s²]."""

    def time_span(self) -> tuple:
        """The times [s] (first, last) within which the end is defined.

        A simulation must stay inside it (:func:`moorjax.dynamics.simulate`
        refuses a run that leaves it); paths given by a formula are defined at
        all times.
        """
        return -float("inf"), float("inf")


class FixedEnd(AbstractEnd):
    """An anchor or a held fairlead at ``point`` (3,) [m]."""

    point: Array

    def __init__(self, point):
        check_finite(point, "end position", "m")
        self.point = as_float(point, 3)

    def position(self, t):
        return self.point

    def velocity(self, t):
        return jnp.zeros(3)

    def acceleration(self, t):
        return jnp.zeros(3)


class KinematicEnd(AbstractEnd):
    """An end at ``point`` moving with ``velocity`` at this instant (no acceleration).

    What a :class:`BodyEnd` becomes once its body's state is known (inside the
    vector field); rarely built by hand.
    """

    point: Array
    speed: Array

    def __init__(self, point, velocity):
        self.point = as_float(point, 3)
        self.speed = as_float(velocity, 3)

    def position(self, t):
        return self.point

    def velocity(self, t):
        return self.speed

    def acceleration(self, t):
        return jnp.zeros(3)


class BodyEnd(AbstractEnd):
    """A fairlead fixed to body number ``body`` of the scene.

    Args:
        body: index of the body in ``Scene.bodies`` (structure).
        point: (3,) fairlead position in body axes, relative to the body's centre
            of gravity [m].
        origin: (3,) the body's centre of gravity at rest [m] (set by the scene
            from the body; needed only to place the end when the body's state is
            not at hand, e.g. a line's statics at rest).

    Inside a simulation the end follows the body: the scene replaces it by a
    :class:`KinematicEnd` at the body's current pose.
    """

    point: Array
    origin: Array
    body: int = eqx.field(static=True, default=0)

    def __init__(self, body, point, origin=(0.0, 0.0, 0.0)):
        if int(body) != body or body < 0:
            raise ValueError(f"body index = {body} must be an integer >= 0")
        check_finite(point, "fairlead position in body axes", "m")
        check_finite(origin, "body origin", "m")
        self.body = int(body)
        self.point = as_float(point, 3)
        self.origin = as_float(origin, 3)

    def position(self, t):
        return self.origin + self.point

    def velocity(self, t):
        return jnp.zeros(3)

    def acceleration(self, t):
        return jnp.zeros(3)


class SinePath(AbstractEnd):
    """``r(t) = center + amplitude·sin(2πt/period + phase)`` (amplitude (3,) [m])."""

    center: Array
    amplitude: Array
    period: Array
    phase: Array

    def __init__(self, center, amplitude, period, phase=0.0):
        check_finite(center, "path center", "m")
        check_finite(amplitude, "path amplitude", "m")
        check_positive(period, "path period", "s")
        self.center = as_float(center, 3)
        self.amplitude = as_float(amplitude, 3)
        self.period = as_float(period)
        self.phase = as_float(phase)

    def _w(self):
        return 2 * jnp.pi / self.period

    def position(self, t):
        return self.center + self.amplitude * jnp.sin(self._w() * t + self.phase)

    def velocity(self, t):
        return self.amplitude * self._w() * jnp.cos(self._w() * t + self.phase)

    def acceleration(self, t):
        return -self.amplitude * self._w() ** 2 * jnp.sin(self._w() * t + self.phase)


class TabulatedPath(AbstractEnd):
    """A sampled path, interpolated by cubic Hermite splines (C¹ in position).

    Without sampled velocities the spline slopes come from central differences of
    the positions (one-sided at the ends), so velocity is the exact derivative of
    the interpolated position.

    The path is defined on ``[t[0], t[-1]]`` (:meth:`time_span`); a simulation
    must stay within it. Just outside, the first and last cubics continue
    (position, velocity and acceleration of the same polynomial), because an
    implicit Runge–Kutta step may evaluate its stages past the step's end
    (Kvaerno5 at 1.23 steps, Kvaerno4 at 1.15): a run that ends on the last
    sample then sees the path's own smooth continuation there, not a point that
    stops dead. Far outside, that cubic is no sensible motion: extend the table.

    A table sampled at a constant interval (to 1e-6 of it: times written as
    decimals) is looked up by arithmetic, O(1), with one neighbour check; any
    other by binary search (``uniform``, decided from the times given, never
    from traced ones). The interval found is the same either way; the
    arithmetic lookup is a far smaller program to compile (about a third of the
    vector field of a line driven at one end).

    Args:
        t: (k,) strictly increasing sample times [s], k ≥ 2.
        position: (k, 3) [m].
        velocity: optional (k, 3) [m/s].
    """

    t: Array
    r: Array
    v: Array
    uniform: bool = eqx.field(static=True)

    def __init__(self, t, position, velocity=None):
        t = as_float(t)
        r = as_float(position)
        if t.ndim != 1 or t.shape[0] < 2 or r.shape != (t.shape[0], 3):
            raise ValueError(f"tabulated path needs t (k>=2,) and position (k, 3); got {t.shape}, {r.shape}")
        check_finite(t, "path time", "s")
        check_finite(r, "path position", "m")
        if not isinstance(t, jax.core.Tracer) and not np.all(np.diff(np.asarray(t)) > 0):
            raise ValueError("tabulated path: times [s] must be strictly increasing")
        if velocity is None:
            v = jnp.gradient(r, t, axis=0)
        else:
            v = as_float(velocity)
            if v.shape != r.shape:
                raise ValueError(f"tabulated path velocity shape {v.shape} != position shape {r.shape}")
            check_finite(v, "path velocity", "m/s")
        self.t, self.r, self.v = t, r, v
        self.uniform = _uniform_grid(t)

    def time_span(self):
        if isinstance(self.t, jax.core.Tracer):
            return self.t[0], self.t[-1]
        t = np.asarray(self.t)  # concrete: read on the host, no XLA op
        return float(t[0]), float(t[-1])

    def _interval(self, t):
        """The index i of the interval [t_i, t_i+1) holding t (clipped to the table)."""
        last = self.t.shape[0] - 2
        if not self.uniform:
            return jnp.clip(jnp.searchsorted(self.t, t, side="right") - 1, 0, last)
        step = (self.t[-1] - self.t[0]) / (last + 1)
        i = jnp.clip(jnp.floor((t - self.t[0]) / step).astype(jnp.int32), 0, last)
        # rounding of the times may put t just across a sample: one neighbour check
        t_i = lax.dynamic_slice_in_dim(self.t, i, 2)
        i = i - (t < t_i[0]).astype(i.dtype) + (t >= t_i[1]).astype(i.dtype)
        return jnp.clip(i, 0, last)

    def _locate(self, t):
        """The interval holding t: its length h [s], the local coordinate s (in [0, 1]
        inside it; < 0 before the table, > 1 after it: the end cubics continue) and
        the positions and velocities at its two samples, each (2, 3)."""
        i = self._interval(t)
        t_i = lax.dynamic_slice_in_dim(self.t, i, 2)
        h = t_i[1] - t_i[0]
        return (h, (t - t_i[0]) / h, lax.dynamic_slice_in_dim(self.r, i, 2),
                lax.dynamic_slice_in_dim(self.v, i, 2))

    def position(self, t):
        h, s, r, v = self._locate(t)
        h00 = 2 * s**3 - 3 * s**2 + 1
        h10 = s**3 - 2 * s**2 + s
        h01 = -2 * s**3 + 3 * s**2
        h11 = s**3 - s**2
        return h00 * r[0] + h10 * h * v[0] + h01 * r[1] + h11 * h * v[1]

    def velocity(self, t):
        h, s, r, v = self._locate(t)
        d00 = 6 * s**2 - 6 * s
        d10 = 3 * s**2 - 4 * s + 1
        d11 = 3 * s**2 - 2 * s
        return d00 * (r[0] - r[1]) / h + d10 * v[0] + d11 * v[1]

    def acceleration(self, t):
        h, s, r, v = self._locate(t)
        return ((12 * s - 6) * (r[0] - r[1]) / h + (6 * s - 4) * v[0] + (6 * s - 2) * v[1]) / h


def _uniform_grid(t) -> bool:
    """Whether the sample times ``t`` are (concretely) equally spaced, to 1e-6 of the interval."""
    try:
        times = np.asarray(t, dtype=float)
    except (jax.errors.ConcretizationTypeError, jax.errors.TracerArrayConversionError, TypeError):
        return False
    steps = np.diff(times)
    return bool(steps.size and np.all(np.abs(steps - steps.mean()) <= 1e-6 * steps.mean()))


class AbstractClampedEnd(AbstractEnd):
    """An end that holds the line's direction as well as its position.

    A line with bending stiffness EI carries an end moment there; without EI a
    clamp is a pin (a cable has no moment to hold). ``direction(t)`` is the
    unit vector in which the line leaves the end — from end A that is the
    tangent dr/ds, from end B it is −dr/ds — so the same end object clamps
    either end of a line.
    """

    @abc.abstractmethod
    def direction(self, t) -> Array:
        """(3,) unit vector [-] along which the line leaves the end."""


def _clamp_unit(direction, who):
    """The clamp's direction (3,) normalised; a zero vector is refused."""
    check_finite(direction, "clamp direction", "-")
    d = as_float(direction, 3)
    norm = jnp.linalg.norm(d)
    if not isinstance(norm, jax.core.Tracer) and float(norm) == 0.0:
        raise ValueError(f"{who}: direction = (0, 0, 0) has no direction; give the unit "
                         "vector along which the line leaves the clamp, e.g. (1, 0, 0)")
    return d / norm


class ClampedEnd(AbstractClampedEnd):
    """A fixed clamp at ``point`` (3,) [m] holding the line along ``direction`` (3,).

    ``direction`` is normalised here; it points from the clamp into the line
    (for a horizontal cantilever from end A along +x: ``(1, 0, 0)``).
    """

    point: Array
    unit: Array

    def __init__(self, point, direction):
        check_finite(point, "end position", "m")
        self.unit = _clamp_unit(direction, "ClampedEnd")
        self.point = as_float(point, 3)

    def position(self, t):
        return self.point

    def velocity(self, t):
        return jnp.zeros(3)

    def acceleration(self, t):
        return jnp.zeros(3)

    def direction(self, t):
        return self.unit


class MovingClampedEnd(AbstractClampedEnd):
    """A clamp carried along a prescribed ``path`` that keeps its ``direction``.

    ``path`` is an end with a prescribed motion (:class:`SinePath`,
    :class:`TabulatedPath`, :class:`FixedEnd`): the clamp is where it is and
    moves as it moves (its time span is the path's); the line leaves the clamp
    along ``direction`` (3,) at all times (normalised here), so the clamp
    translates without turning — a hang-off on a vessel whose rotations are
    left out. A clamp fixed to a body would turn with it: not supported
    (refused here for a :class:`BodyEnd` path).
    """

    path: AbstractEnd
    unit: Array

    def __init__(self, path, direction):
        if not isinstance(path, AbstractEnd):
            raise TypeError(f"MovingClampedEnd: path must be an end with a motion (SinePath, "
                            f"TabulatedPath, FixedEnd), got {type(path).__name__}")
        if isinstance(path, (BodyEnd, KinematicEnd)):
            raise ValueError("MovingClampedEnd: a clamp on a body would turn with the body, "
                             "which moorjax does not model yet; pin the line to the body "
                             "(BodyEnd) or prescribe the clamp's path")
        if isinstance(path, AbstractClampedEnd):
            raise ValueError("MovingClampedEnd: path is already a clamp; give its path")
        self.unit = _clamp_unit(direction, "MovingClampedEnd")
        self.path = path

    def position(self, t):
        return self.path.position(t)

    def velocity(self, t):
        return self.path.velocity(t)

    def acceleration(self, t):
        return self.path.acceleration(t)

    def time_span(self):
        return self.path.time_span()

    def direction(self, t):
        return self.unit


def clamp_directions(end_a, end_b, t=0.0):
    """The clamps' unit directions along the line (A to B) at its two ends:
    ``(d_a, d_b)``, from end A the clamp's direction, from end B its reverse;
    ``None`` for an end that is not clamped (structure, decided at trace time)."""
    d_a = end_a.direction(t) if isinstance(end_a, AbstractClampedEnd) else None
    d_b = -end_b.direction(t) if isinstance(end_b, AbstractClampedEnd) else None
    return d_a, d_b
