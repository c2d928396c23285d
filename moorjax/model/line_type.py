"""Line type: the cross-section properties shared by lines of one material.

Hydrodynamic groups are optional *structure*: a line type without ``drag`` or
without ``added_mass`` never traces those terms.

Conventions (the same as MoorDyn's, so that its decks mean the same here):

- ``diameter`` is the volume-equivalent diameter d: buoyancy, normal drag and added
  mass use it, with area A = πd²/4.
- Normal drag per unit (stretched) length: ½·ρ·Cd_n·d·|u_n|·u_n.
- Axial drag per unit length acts on the *surface* π·d: ½·ρ·Cd_ax·π·d·|u_t|·u_t
  (Aamo & Fossen write C_DT·d; their C_DT equals π·Cd_ax).
- Added mass per unit length: ρ·A·(Ca_n·(I − ttᵀ) + Ca_ax·ttᵀ).
- ``damping`` is MoorDyn's BA as a coefficient in N·s: the damping tension is
  BA·dε/dt. (A negative BA in a deck means −ζ and is converted by the deck builder.)
- ``ei`` is the bending stiffness EI [N·m²] (MoorDyn's EI column). It is structure
  too: ``None`` (the default, EI = 0) traces no bending term; a number, even 0,
  gives the term with a differentiable coefficient. Bending couples a node to its
  second neighbours, so a line with EI has no block-tridiagonal Jacobian.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array

from .._checks import check_nonnegative, check_positive
from .._numerics import as_float
from .axial import AbstractAxialLaw, LinearEA


class MorisonDrag(eqx.Module):
    """Drag coefficients: normal (on d) and axial (on π·d) [-]."""

    cd_normal: Array
    cd_axial: Array

    def __init__(self, cd_normal, cd_axial=0.0):
        check_nonnegative(cd_normal, "Cd normal", "-")
        check_nonnegative(cd_axial, "Cd axial", "-")
        self.cd_normal = as_float(cd_normal)
        self.cd_axial = as_float(cd_axial)


class AddedMass(eqx.Module):
    """Added-mass coefficients, normal and axial [-], on the displaced mass ρA."""

    ca_normal: Array
    ca_axial: Array

    def __init__(self, ca_normal, ca_axial=0.0):
        check_nonnegative(ca_normal, "Ca normal", "-")
        check_nonnegative(ca_axial, "Ca axial", "-")
        self.ca_normal = as_float(ca_normal)
        self.ca_axial = as_float(ca_axial)


class LineType(eqx.Module):
    """Material and section of a line.

    Args:
        diameter: volume-equivalent diameter d [m].
        mass_per_length: dry mass per unit unstretched length [kg/m].
        axial: axial law (a number is taken as a linear EA [N]).
        damping: internal axial damping BA [N·s] (tension BA·dε/dt).
        drag: Morison drag coefficients, or ``None`` for no drag.
        added_mass: added-mass coefficients, or ``None`` for none.
        mbl: minimum breaking load [N], informative (``None`` if unknown).
        ei: bending stiffness EI [N·m²], or ``None`` for none (EI = 0, untraced).
    """

    diameter: Array
    mass_per_length: Array
    axial: AbstractAxialLaw
    damping: Array
    drag: MorisonDrag | None
    added_mass: AddedMass | None
    mbl: Array | None
    ei: Array | None

    def __init__(
        self,
        diameter,
        mass_per_length,
        axial,
        damping=0.0,
        drag: MorisonDrag | None = None,
        added_mass: AddedMass | None = None,
        mbl=None,
        ei=None,
    ):
        check_positive(diameter, "diameter", "m")
        check_positive(mass_per_length, "mass per length", "kg/m")
        check_nonnegative(damping, "internal damping BA", "N·s")
        if not isinstance(axial, AbstractAxialLaw):
            axial = LinearEA(axial)
        if mbl is not None:
            check_positive(mbl, "MBL", "N")
            mbl = as_float(mbl)
        if ei is not None:
            check_nonnegative(ei, "bending stiffness EI", "N·m²")
            ei = as_float(ei)
        self.diameter = as_float(diameter)
        self.mass_per_length = as_float(mass_per_length)
        self.axial = axial
        self.damping = as_float(damping)
        self.drag = drag
        self.added_mass = added_mass
        self.mbl = mbl
        self.ei = ei

    @property
    def area(self) -> Array:
        """Volume-equivalent cross-section area πd²/4 [m²]."""
        return jnp.pi * self.diameter**2 / 4.0

    def wet_weight(self, rho, g) -> Array:
        """Submerged weight per unit unstretched length (m − ρA)·g [N/m] (< 0: buoyant)."""
        return (self.mass_per_length - rho * self.area) * g
