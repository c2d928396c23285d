"""The scene's equations of motion as a first-order ODE on a pytree.

Solver state: a tuple with one (n_i − 1, 6) array per line, the free nodes'
[position, velocity] side by side, followed by one 1-D array per body of
``scene.bodies`` (its pose, velocity and internal states; see
:class:`moorjax.body.base.AbstractBody`): the first ``len(scene.lines)`` entries
are the lines'. This node-major layout keeps each line's
Jacobian block-tridiagonal (6×6 blocks), which the block-tridiagonal Newton solve
exploits; a system of several lines stacks into one larger band.

Lines of one structure (same segment count, end types, force terms and element)
are evaluated together: they are grouped at trace time, stacked, and their
accelerations computed by one ``vmap`` — a four-line spread with equal
discretisation costs about one line's worth of XLA operations, not four. Lines of
different structure fall into separate groups automatically.

A line whose end forces carry its ends' inertia (the Hermite element's
consistent mass) and that ends on a body is solved together with the bodies
(:func:`moorjax.body.end_inertia.couple`): the bodies' accelerations and those
lines' end accelerations are one linear solve, decided by the scene's structure
(:func:`inertial_ends`); scenes without such lines take the plain path.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._numerics import safe_norm
from ..linalg.banded_solver import dense_lu
from ..linalg.ordering import after
from ..model.grouping import map_lines
from ..model.line import LineState


def _pack_one(s, host=False):
    from ..element.hermite_motion import HermiteState

    if isinstance(s, LineState):
        if host and not any(isinstance(x, jax.core.Tracer) for x in (s.r, s.v)):
            return np.concatenate([np.asarray(s.r), np.asarray(s.v)], axis=-1)
        return jnp.concatenate([s.r, s.v], axis=-1)
    if isinstance(s, HermiteState):
        return s.packed()
    return s


def pack(states, host: bool = False) -> tuple:
    """States → solver state: each :class:`LineState` to an (n−1, 6) array, each
    :class:`~moorjax.element.hermite_motion.HermiteState` to its (2n, 6) array; body
    states (1-D arrays) pass through. ``host``: a concrete line state is packed
    by NumPy (for a compiled call's argument, which places it on the device
    itself: an eager ``jnp.concatenate`` is an XLA program call of about 50 µs)."""
    return tuple(_pack_one(s, host) for s in states)


def unpack(y, lines) -> tuple:
    """Solver state → each line's state (its element's, see
    :meth:`~moorjax.element.base.AbstractElement.unpack_state`), then the body
    states (1-D arrays) as they are. ``lines``: the scene's lines (or their
    number, for lines of node elements only)."""
    y = tuple(y)
    if isinstance(lines, int):
        return tuple(LineState(r=q[..., :3], v=q[..., 3:]) for q in y[:lines]) + y[lines:]
    n = len(lines)
    return tuple(ln.element.unpack_state(ln, q) for ln, q in zip(lines, y[:n])) + y[n:]


def _body_kinematics(y, scene):
    """Line arrays, the lines with fairleads placed, and body (η, η̇) lists."""
    n = len(scene.lines)
    if not scene.bodies:
        return y[:n], scene.lines, (), ()
    from ..body.coupling import attach

    zs = y[n:]
    poses = [z[:6] for z in zs]
    vels = [z[6:12] for z in zs]
    return y[:n], attach(scene.lines, scene.bodies, poses, vels), poses, vels


def _line_rate(line, q, env, t):
    return line.element.state_rate(line, env, t, q)


def vector_field(t, y, scene):
    """dy/dt: (velocity, acceleration) of every line's free nodes, then each body's rate."""
    if inertial_ends(scene):
        line_rates, _, body_rates = _coupled(t, y, scene)
        return line_rates + body_rates
    y_lines, lines, poses, vels = _body_kinematics(y, scene)
    out = _line_rates(t, y_lines, lines, scene.env)
    if not scene.bodies:
        return out
    from ..body.coupling import mooring_wrenches

    ends = _grouped(_end_forces, t, y_lines, lines, scene.env)
    wrenches = mooring_wrenches(scene.lines, scene.bodies, poses, ends)
    rates = tuple(body.rate(t, z, w, scene.env) for body, z, w in
                  zip(scene.bodies, y[len(scene.lines):], wrenches))
    return out + rates


#: :func:`vector_field` traced once per structure of its arguments. A solver
#: evaluates the vector field several times per step (ROS34PW2: four stages, the
#: time column, the end-of-step check, its ``init``; 14 traces of a case-A
#: integration), and each plain call is traced anew; through ``filter_jit`` the
#: later calls reuse the first trace. XLA inlines the calls, so the compiled
#: program computes the same numbers (bit-identical on ``oc3_catenary``); a run's
#: tracing took 2.3-2.7 -> 1.2-1.3 s (``benchmarks/README.md``, session 34).
traced_vector_field = eqx.filter_jit(vector_field)


def inertial_ends(scene) -> bool:
    """Whether some line on a body carries its end inertia (a consistent-mass
    element, see :mod:`moorjax.body.end_inertia`): then the bodies' and those
    lines' accelerations are solved together (structure, decided at trace time)."""
    from ..body.coupling import body_ends

    return any(line.element.carries_end_inertia and body_ends(line) for line in scene.lines)


def _coupled(t, y, scene):
    """(line rates, end forces per line (2, 3) [N], body rates) with the lines' end inertia."""
    from ..body.end_inertia import couple

    y_lines, lines, _, _ = _body_kinematics(y, scene)
    responses = _grouped(_line_response, t, y_lines, lines, scene.env)
    return couple(t, scene.lines, scene.bodies, y[len(scene.lines):], responses, scene.env)


def _line_response(line, q, env, t):
    return line.element.state_end_response(line, env, t, q)


def _end_forces(line, q, env, t):
    return line.element.state_end_forces(line, env, t, q)


def _line_rates(t, y, lines, env):
    return _grouped(_line_rate, t, y, lines, env)


def _grouped(fn, t, y, lines, env):
    """``fn(line, q, env, t)`` for every line, one ``vmap`` per group of equal structure."""
    return map_lines(lambda line, q: fn(line, q, env, t), lines, y)


def end_outputs(t, y, scene, with_nodes: bool = False):
    """Forces on each line's end points at time t (and optionally node data).

    Returns a dict with ``force_a``, ``force_b`` (n_lines, 3) [N], ``tension_a``,
    ``tension_b`` (n_lines,) [N]; with ``with_nodes``, also ``positions`` and
    ``segment_tensions`` (and ``velocities``): tuples with one (n+1, 3) [m] / (n,) [N]
    (/ (n+1, 3) [m/s]) array per line;
    with bodies, ``body_pose`` and ``body_velocity`` (n_bodies, 6).
    """
    fa, fb, pos, ten, vel = [], [], [], [], []
    y_lines, lines, poses, vels = _body_kinematics(y, scene)
    # lines with end inertia: their end forces with the bodies' accelerations
    coupled = _coupled(t, y, scene)[1] if inertial_ends(scene) else None
    for i, (line, q) in enumerate(zip(lines, y_lines)):
        if coupled is None:
            a, b = line.element.state_end_forces(line, scene.env, t, q)
        else:
            a, b = coupled[i][0], coupled[i][1]
        fa.append(a)
        fb.append(b)
        if with_nodes:
            r, v, tension = line.element.state_outputs(line, scene.env, t, q)
            pos.append(r)
            vel.append(v)
            ten.append(tension)
    fa, fb = jnp.stack(fa), jnp.stack(fb)
    out = dict(
        force_a=fa,
        force_b=fb,
        tension_a=safe_norm(fa, axis=-1),
        tension_b=safe_norm(fb, axis=-1),
    )
    if scene.bodies:
        out["body_pose"] = jnp.stack(poses)
        out["body_velocity"] = jnp.stack(vels)
    if with_nodes:
        out["positions"] = tuple(pos)
        out["velocities"] = tuple(vel)
        out["segment_tensions"] = tuple(ten)
    return out


def has_stiff_band(scene) -> bool:
    """Whether :func:`stiff_band` gives a band for ``scene`` (structure only)."""
    return not scene.bodies and all(line.element.provides_stiff_band(line) for line in scene.lines)


def stiff_band(t, y, scene):
    """W ≈ ∂(vector field)/∂y for a Rosenbrock-W stepper: each line's
    :meth:`~moorjax.element.base.AbstractElement.stiff_band` stacked along the
    node axis (a :class:`~moorjax.linalg.mass_form.MassFormW`), or ``None``
    (decided at trace time) when the scene has bodies or some line's element
    has no such band.
    Builds no time column (see :func:`stiff_linearisation`)."""
    if scene.bodies:
        return None
    parts = [line.element.stiff_band(line, scene.env, t, q) for line, q in zip(scene.lines, y)]
    if any(band is None for band in parts):
        return None
    return _stacked(parts)


def _stacked(parts):
    """Lines' W stacked along the node axis (lines do not couple)."""
    return jax.tree_util.tree_map(lambda *x: jnp.concatenate(x, axis=0), *parts)


def stiff_linearisation(t, y, scene):
    """(:func:`stiff_band`, W_t): W_t ≈ ∂(vector field)/∂t, one (rows, 6) array
    per line as the state (each line's
    :meth:`~moorjax.element.base.AbstractElement.stiff_linearisation`), or
    ``None`` when some line has none (then the stepper differences the vector
    field in t). Structure decides both at trace time."""
    if scene.bodies:
        return None, None
    parts, times = [], []
    for line, q in zip(scene.lines, y):
        band, time = line.element.stiff_linearisation(line, scene.env, t, q)
        if band is None:
            return None, None
        parts.append(band)
        times.append(time)
    return _stacked(parts), (None if any(x is None for x in times) else tuple(times))


def has_stage_factors(scene) -> bool:
    """Whether :func:`stage_factors` factors ``scene``'s stage matrix (structure
    only): every line's element factors its own."""
    return all(line.element.provides_stage_factor(line) for line in scene.lines)


class DenseStageFactor(eqx.Module):
    """A body's block of the stage matrix, I − c·∂(its rate)/∂(its state), by LU."""

    lu: jax.Array
    pivots: jax.Array

    def solve(self, r):
        return jax.scipy.linalg.lu_solve((self.lu, self.pivots), r)


def stage_factors(t, y, scene, c) -> tuple:
    """The factored blocks of the stage matrix I − c·∂(dy/dt)/∂y at time t [s]
    and solver state y, c = γ·h [s]: each line's own
    (:meth:`~moorjax.element.base.AbstractElement.stage_factor`, lines of one
    structure in one vmapped call), then each body's (exact, one derivative of
    the vector field per body state, LU).

    Without bodies the lines do not couple and the blocks are the matrix. With
    bodies the lines are factored with their fairleads where the bodies are
    (moving with them) and the couplings between a body and its lines are left
    out: a block-Jacobi matrix, as the linear element's structured solve with
    bodies (:mod:`~moorjax.linalg.banded_solver`); Newton's iteration then
    contracts at about (c·dt)²·k/M (fairlead stiffness against body mass) and
    its convergence test still decides."""
    n = len(scene.lines)
    y_lines, lines, _, _ = _body_kinematics(y, scene)
    env = scene.env
    factors = map_lines(lambda line, q: line.element.stage_factor(line, env, t, q, c),
                        lines, y_lines)
    if not scene.bodies:
        return factors
    blocks = []
    y_after = after(y, factors)  # one batched LAPACK call at a time (linalg.ordering)
    for i, z in enumerate(y_after[n:]):
        def column(e, i=i):  # (I − c·J)·e for e on body i's state only
            dy = tuple(jnp.zeros_like(x) for x in y)
            dy = dy[:n + i] + (e,) + dy[n + i + 1:]
            return e - c * jax.jvp(lambda w: vector_field(t, w, scene), (y_after,), (dy,))[1][n + i]

        blocks.append(DenseStageFactor(*dense_lu(column, z.shape[0], z.dtype)))
    return factors + tuple(blocks)
