"""What the adaptive step-size controller measures: positions, velocities and
the stretch of each segment.

diffrax's PID controller accepts a step when ``norm(error / (atol + rtol·|y|))``
is below one. For a line's node positions ``|y|`` is a coordinate (tens to
hundreds of metres), so a position tolerance is ``atol + rtol·|r|`` and the
controller lets neighbouring nodes err independently by that much. A segment's
tension moves by EA/l per metre of relative displacement, so on a fine mesh of a
stiff line a loose tolerance admitted tension errors of meganewtons that the
controller never saw: reference case B (polyester, EA = 150 MN) at 80 segments
and ``rtol``/``atol`` = 4e-4/4e-3 ran "successfully" with 45 MN peaks against
2 MN and a fairlead error of 1,950 % of the tension's standard deviation.

:class:`StretchControl` adds what was missing: the error of each segment's
chord ``r_{i+1} − r_i`` of a linear-element line, against the line's position
tolerance shared out over its segments,

    tol_i = stretch_share · (atol + rtol · max|r|) / n_segments,

so that the allowed strain error, tol_i / l, is the position tolerance over the
line's length and does not grow as the mesh is refined. The end nodes of the
state are neighbours of the line's ends, whose error is zero (a prescribed path)
or the body's own (measured with the body's state). The step's error is the
larger of the state's RMS norm (:class:`StateNorm`) and the chords' RMS norm.

Measured and not kept: the chords of the velocities ``v_{i+1} − v_i`` (the
strain rate, which a segment's internal damping turns into tension) against
``(atol_velocity + rtol·|v|) / n_segments``: 1.4–1.6× the steps of reference
case B at the default tolerances (N = 10, 20) for the same error.

What the controller cannot see is the dense output between steps. With the
cubic Hermite interpolation through h·f(t₁, y₁) (diffrax's, which the Kvaerno
solvers use), where a line goes slack or snaps within a step the interpolated
chords, and so the output tensions, can be off by more than the steps' own
error. ROS34PW2 interpolates with its stages instead
(:class:`~moorjax.dynamics.rosenbrock.StagePolynomialInterpolation`), which cut
the drawn lines' worst output error about tenfold (``benchmarks/README.md``,
"Session 25").

Newton's convergence tests (:mod:`moorjax.dynamics.newton`) keep measuring the
plain state: the chord measure is an accuracy requirement on the accepted step,
not on the stage equations' solution.
"""

from __future__ import annotations

from typing import Any

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array

__all__ = ["Measured", "StateNorm", "StretchControl", "STRETCH_SHARE", "stretch_segments"]

#: default multiplier of the chord tolerance (see the module docstring): 1 shares the
#: position tolerance out over the segments
STRETCH_SHARE = 1.0


class Measured(eqx.Module):
    """The state (or its error) with the segment chords of its lines beside it."""

    state: Any
    chords: tuple


def _rms(leaves):
    sq = sum(jnp.sum(jnp.abs(x) ** 2) for x in leaves)
    return jnp.sqrt(sq / sum(x.size for x in leaves))


class StateNorm(eqx.Module):
    """RMS norm of a solver-state pytree with velocities weighted against positions.

    Leaves are (n, 6) [r, v] arrays (or anything whose last axis is 6), or 1-D
    body states (see :meth:`_body_weights`). The
    velocity columns are multiplied by ``velocity_weight`` = atol / atol_velocity,
    so that with the controller's ``atol`` in metres, a velocity error of
    ``atol_velocity`` [m/s] counts as much as a position error of ``atol`` [m].
    A :class:`Measured` tree (the step-size controller's, see
    :class:`StretchControl`) has the larger of its state's norm and its chords'
    RMS norm. A NaN anywhere makes the norm +inf, so the step-size controller
    rejects the step and shrinks it (diffrax would otherwise propagate a NaN step
    size and spin until ``max_steps``). An array field: changing it does not
    recompile.
    """

    velocity_weight: Array

    def _body_weights(self, n):
        """A body's 1-D state [η (6) m/rad, η̇ (6), radiation states]: η̇ weighted
        like node velocities, the rest like positions."""
        return jnp.concatenate([jnp.ones(6), jnp.full(6, 1.0) * self.velocity_weight,
                                jnp.ones(n - 12)])

    def _state(self, tree):
        w = jnp.concatenate([jnp.ones(3), jnp.full(3, 1.0) * self.velocity_weight])
        leaves = jax.tree_util.tree_leaves(tree)
        if not leaves:
            return jnp.asarray(0.0)
        return _rms([x * (w if x.ndim != 1 else self._body_weights(x.shape[0])) for x in leaves])

    def __call__(self, tree):
        if isinstance(tree, Measured):
            value = jnp.maximum(self._state(tree.state), _rms(tree.chords))
        else:
            value = self._state(tree)
        return jnp.where(jnp.isnan(value), jnp.inf, value)


def stretch_segments(scene) -> tuple:
    """Per entry of the solver state: the segment count of a linear-element line
    (its state holds the free nodes, whose chords :class:`StretchControl`
    measures), else 0 (other elements, bodies). ``()`` without a scene."""
    if scene is None:
        return ()
    from ..element.linear import LinearElement

    lines = tuple(line.n_segments if isinstance(line.element, LinearElement) else 0
                  for line in scene.lines)
    return lines + (0,) * len(scene.bodies)


def _chords(r):
    """The n chords of a line whose n − 1 free nodes are the rows of r, its
    ends taken as exact: (n, 3)."""
    zero = jnp.zeros_like(r[:1])
    return jnp.diff(jnp.concatenate([zero, r, zero]), axis=0)


def _node_pairs_max(a):
    """max over the two nodes of each chord of (n − 1, k) values, ends repeating
    their neighbour: (n, k)."""
    padded = jnp.concatenate([a[:1], a, a[-1:]])
    return jnp.maximum(padded[:-1], padded[1:])


class StretchControl(diffrax.PIDController):
    """diffrax's PID controller that also measures each segment chord's error
    against its share of the position tolerance (module docstring).

    ``segments`` (static): per entry of the solver state, the segment count of a
    linear-element line, 0 for entries it does not measure (see
    :func:`stretch_segments`). ``stretch_share`` (an array: changing it does not
    recompile) multiplies the chord tolerance; ``inf`` turns the chord measure off.
    """

    segments: tuple = eqx.field(static=True, default=())
    stretch_share: Array = eqx.field(default_factory=lambda: jnp.asarray(STRETCH_SHARE))

    def _measure(self, y0, y1, y_error):
        leaves0, leaves1, errors = tuple(y0), tuple(y1), tuple(y_error)
        zeros, scaled = [], []
        for n, a, b, e in zip(self.segments, leaves0, leaves1, errors):
            if not n:
                continue
            size = _node_pairs_max(jnp.maximum(jnp.abs(a[:, :3]), jnp.abs(b[:, :3])))
            tol = self.stretch_share * (self.atol + self.rtol * size) / n
            zeros.append(jnp.zeros_like(tol))
            # the controller divides by atol + rtol·0: hand it chord error · atol / tol
            scaled.append(_chords(e[:, :3]) * (self.atol / tol))
        return (Measured(y0, tuple(zeros)), Measured(y1, tuple(zeros)),
                Measured(y_error, tuple(scaled)))

    def adapt_step_size(self, t0, t1, y0, y1_candidate, args, y_error, error_order,
                        controller_state):
        if y_error is not None and any(self.segments):
            y0, y1_candidate, y_error = self._measure(y0, y1_candidate, y_error)
        return super().adapt_step_size(t0, t1, y0, y1_candidate, args, y_error, error_order,
                                       controller_state)
