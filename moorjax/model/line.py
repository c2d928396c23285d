"""A mooring line: a line type, an unstretched length, two ends and an element.

The element (the discretisation) is a swappable part: :class:`LinearElement`
(Aamo & Fossen's Galerkin linear element) is the default; a mixed Hermite-cubic
element with a tension field (Wu et al.) can stand beside it, as long as it
implements :class:`moorjax.element.AbstractElement`.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array

from .._checks import check_positive
from .._numerics import as_float
from .ends import AbstractEnd
from .line_type import LineType


class LineState(eqx.Module):
    """Dynamic state of a line's free (interior) nodes.

    Attributes:
        r: (n−1, 3) node positions [m].
        v: (n−1, 3) node velocities [m/s].
    """

    r: Array
    v: Array


class Line(eqx.Module):
    """One line between end A (node 0) and end B (node n).

    Args:
        line_type: section and material.
        length: unstretched length L [m].
        n_segments: number of elements n (structure: changing it recompiles).
        end_a, end_b: end conditions.
        element: discretisation (default: linear element with nodal mass).
        label: an identifier (e.g. the deck's line id), not traced.
    """

    line_type: LineType
    length: Array
    end_a: AbstractEnd
    end_b: AbstractEnd
    element: "AbstractElement"  # noqa: F821
    n_segments: int = eqx.field(static=True)
    label: str = eqx.field(static=True, default="1")

    def __init__(self, line_type, length, n_segments, end_a, end_b, element=None, label="1"):
        from ..element import LinearElement

        check_positive(length, "line length", "m")
        if int(n_segments) != n_segments or n_segments < 1:
            raise ValueError(f"number of segments = {n_segments} must be an integer >= 1")
        self.line_type = line_type
        self.length = as_float(length)
        self.n_segments = int(n_segments)
        self.end_a = end_a
        self.end_b = end_b
        self.element = LinearElement() if element is None else element
        self.label = str(label)

    @property
    def banded_jacobian(self) -> bool:
        """Whether a free node's force depends only on itself and its two neighbours
        (block-tridiagonal Jacobian): the element's answer for this line."""
        return self.element.line_banded(self)

    @property
    def segment_length(self) -> Array:
        """Unstretched element length l = L/n [m]."""
        return self.length / self.n_segments

    def nodes(self, t, state: LineState):
        """All node positions (n+1, 3) [m] and velocities (n+1, 3) [m/s] at time t."""
        ra, rb = self.end_a.position(t), self.end_b.position(t)
        va, vb = self.end_a.velocity(t), self.end_b.velocity(t)
        r = jnp.concatenate([ra[None], state.r, rb[None]], axis=0)
        v = jnp.concatenate([va[None], state.v, vb[None]], axis=0)
        return r, v

    def straight_state(self, t=0.0) -> LineState:
        """Nodes evenly spaced on the chord between the ends, at rest."""
        ra, rb = self.end_a.position(t), self.end_b.position(t)
        s = jnp.linspace(0.0, 1.0, self.n_segments + 1)[1:-1, None]
        r = ra + s * (rb - ra)
        return LineState(r=r, v=jnp.zeros_like(r))
