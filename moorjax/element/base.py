"""Interface of a line discretisation (an element type).

An element turns a line, its environment and its state into time derivatives,
end forces and segment tensions. The dynamics driver and the statics solver use
only this interface, so a new discretisation (a Hermite-cubic element with a
tension field, bending stiffness) plugs in beside the linear element.
"""

from __future__ import annotations

import abc

import equinox as eqx


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
