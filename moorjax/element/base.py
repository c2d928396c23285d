"""Interface of a line discretisation (an element type).

An element turns a line, its environment and its state into time derivatives,
end forces and segment tensions. The dynamics driver and the statics solver use
only this interface, so a new discretisation (a Hermite-cubic element with a
tension field, bending stiffness) plugs in beside the linear element.
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax.numpy as jnp


class AbstractElement(eqx.Module):
    """A finite-element discretisation of the cable equation."""

    @property
    def banded_jacobian(self) -> bool:
        """Whether a free node's acceleration depends only on itself and its two
        neighbours (a block-tridiagonal Jacobian, which the structured Newton
        solves exploit). Elements coupling further must return ``False``."""
        return True

    def line_banded(self, line) -> bool:
        """``banded_jacobian`` for this element on ``line`` (a line's section can
        couple nodes further, as bending stiffness does). Default: the element's."""
        return self.banded_jacobian

    @abc.abstractmethod
    def nodal_forces(self, line, env, r, v, t=0.0):
        """All non-inertial forces on every node (n+1, 3) [N], ends included, at
        time t [s] (which matters only to time-varying water kinematics)."""

    @abc.abstractmethod
    def accelerations(self, line, env, t, r, v):
        """Accelerations of the free nodes (n−1, 3) [m/s²] (inertia solved)."""

    @abc.abstractmethod
    def segment_tensions(self, line, r, v):
        """Axial tension of each segment (n,) [N], damping included."""

    @abc.abstractmethod
    def end_forces(self, line, env, r, v, t=0.0):
        """Forces (3,), (3,) [N] that the line exerts on its end A and end B points."""

    # -- the dynamics driver's view: a line's packed solver state q (rows, 6) ----
    # Node elements pack their free nodes' [position, velocity] (n−1, 6) (a
    # :class:`~moorjax.model.line.LineState`); an element with more unknowns per
    # node (slopes) overrides these four and packs them in more rows.

    def provides_stiff_band(self, line) -> bool:
        """Whether :meth:`stiff_band` returns a band for ``line``."""
        del line
        return False

    def stiff_band(self, line, env, t, q):
        """An approximation W of the Jacobian of :meth:`state_rate` for a
        Rosenbrock-W stepper in the packed [r, v] rows, a
        :class:`~moorjax.linalg.mass_form.MassFormW` (nodal masses and 3×3
        block-tridiagonal force derivatives), or ``None`` when the element has
        none (the stepper then differentiates the whole vector field).
        Default: ``None``."""
        del line, env, t, q
        return None

    def stiff_linearisation(self, line, env, t, q):
        """(:meth:`stiff_band`, W_t): W_t ≈ ∂(state rate)/∂t (rows, 6) where the
        element gives it cheaply (the Rosenbrock-W stepper's time column), else
        ``None`` (the stepper then differences the vector field in t).
        Default: ``(stiff_band(...), None)``."""
        return self.stiff_band(line, env, t, q), None

    def provides_stage_factor(self, line) -> bool:
        """Whether :meth:`stage_factor` returns a factor for ``line``."""
        del line
        return False

    def stage_factor(self, line, env, t, q, c):
        """The implicit stages' Newton matrix I − c·∂(state_rate)/∂q at the packed
        state q, factored: an object whose ``solve(r)`` returns δ (rows, 6) with
        (I − c·J)·δ = r, or ``None`` (node elements: the driver's band solvers
        take the coloured Jacobian of the whole vector field). c = γ·h [s]."""
        del line, env, t, q, c
        return None

    def state_rate(self, line, env, t, q):
        """dq/dt (rows, 6) of the packed state q at time t [s]."""
        from ..model.line import LineState

        r, v = line.nodes(t, LineState(r=q[:, :3], v=q[:, 3:]))
        acc = self.accelerations(line, env, t, r, v)
        return jnp.concatenate([q[:, 3:], acc], axis=-1)

    def state_end_forces(self, line, env, t, q):
        """Forces (3,), (3,) [N] the line exerts on its end points, from the packed state."""
        from ..model.line import LineState

        r, v = line.nodes(t, LineState(r=q[:, :3], v=q[:, 3:]))
        return self.end_forces(line, env, r, v, t)

    @property
    def wets_partially(self) -> bool:
        """Whether the element is buoyant only where it is under the free surface
        (MoorDyn's submerged fraction; see :mod:`moorjax.element.linear`). ``False``:
        buoyancy, drag and added mass act above the surface as if submerged, and
        the command line warns of such nodes."""
        return False

    @property
    def carries_end_inertia(self) -> bool:
        """Whether the end forces hold the end nodes' inertia (a consistent mass
        couples the ends' accelerations to the line's): then a body or point the
        line ends on must not add that inertia to its own (see
        :meth:`state_end_response`). Node elements: ``False`` (their end nodes'
        mass is the body's to carry)."""
        return False

    def state_end_response(self, line, env, t, q):
        """The packed rate and end forces, and their derivatives with respect to
        the ends' accelerations beyond their paths' (what a body the line ends on
        adds).

        Returns ``(rate (rows, 6), forces (2, 3) [N], rate_gain (rows, 6, 6),
        force_gain (2, 3, 6) [kg])`` with the gains per (a_A, a_B) (6,) [m/s²];
        the gains are ``None`` (absent structure) where neither depends on the
        ends' accelerations, as for node elements.
        """
        fa, fb = self.state_end_forces(line, env, t, q)
        return self.state_rate(line, env, t, q), jnp.stack([fa, fb]), None, None

    def state_outputs(self, line, env, t, q):
        """Node positions (n+1, 3) [m], velocities (n+1, 3) [m/s] and segment
        tensions (n,) [N] from the packed state."""
        from ..model.line import LineState

        r, v = line.nodes(t, LineState(r=q[:, :3], v=q[:, 3:]))
        return r, v, self.segment_tensions(line, r, v)

    def state_rows(self, line) -> int:
        """Rows of the line's packed (rows, 6) solver state: its free nodes."""
        return line.n_segments - 1

    def unpack_state(self, line, q):
        """The packed state q as the element's state pytree (a ``LineState`` here)."""
        from ..model.line import LineState

        return LineState(r=q[:, :3], v=q[:, 3:])
