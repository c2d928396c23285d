"""Axial (tension–strain) laws of a line.

Every law maps the engineering strain ``ε = ℓ/l − 1`` of a segment (stretched length
ℓ, unstretched length l) to the axial tension ``T`` [N]. Laws are tension-only: a
slack segment (ε < 0) carries no compression. Wrap a law in :class:`Bilateral` for
the ``EA·ε`` form of Aamo & Fossen, whose existence result assumes strictly positive
strain (compression then follows the law's initial slope).

All parameters are array fields, so they are differentiable and changing a value
never recompiles.
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike

from .._checks import check_nonnegative, check_positive
from .._numerics import as_float


class AbstractAxialLaw(eqx.Module):
    """Interface: ``tension(strain)`` [N] for any strain, tension-only by default."""

    @abc.abstractmethod
    def tension_positive(self, strain: Array) -> Array:
        """Tension [N] for strain ε ≥ 0 (with T(0) = 0)."""

    @abc.abstractmethod
    def nominal_ea(self) -> Array:
        """Small-strain axial stiffness dT/dε at ε = 0 [N] (used for damping ratios)."""

    def tension(self, strain: Array) -> Array:
        """Tension [N]; zero for a slack segment (ε ≤ 0)."""
        return self.tension_positive(jnp.maximum(strain, 0.0))


class LinearEA(AbstractAxialLaw):
    """Hooke's law ``T = EA·ε``.

    Args:
        ea: axial stiffness EA [N].
    """

    ea: Array

    def __init__(self, ea: ArrayLike):
        check_positive(ea, "EA", "N")
        self.ea = as_float(ea)

    def tension_positive(self, strain):
        return self.ea * strain

    def nominal_ea(self):
        return self.ea


def _load_dependent_tension(strain, scale, alpha, beta, bs, cap):
    """Solve ``T = ε·scale·(α + β·T/Bs)`` exactly for T.

    ``T = ε·scale·α / (1 − ε·scale·β/Bs)``. The denominator vanishes at
    ε* = Bs/(scale·β); beyond ``cap·ε*`` the law continues linearly with the slope
    it has there, so tensions stay finite (and C¹) for any strain.
    """
    k = scale * beta / bs
    has_cap = k > 0  # β = 0: constant stiffness, no singular strain
    e_cap = jnp.where(has_cap, cap / jnp.where(has_cap, k, 1.0), 1e300)
    e = jnp.minimum(strain, e_cap)
    denom = 1.0 - e * k
    t = e * scale * alpha / denom
    slope = scale * alpha / (denom * denom)
    return jnp.where(strain > e_cap, t + slope * (strain - e_cap), t)


class PolyesterWu(AbstractAxialLaw):
    """Load-dependent polyester stiffness of Wu et al. (2018) Eq. 15 (Tahar & Kim).

    ``AE(T) = RHOL·(α + β·T/Bs)·10⁶`` with ``ε = T/AE(T)``, solved exactly for T.

    Args:
        rhol: dry mass per unit length RHOL [kg/m] (the paper's "dry weight").
        alpha, beta: material constants [-] (Wu et al.: α = 2.5, β = 2.0).
        breaking_strength: minimum breaking strength Bs [N].
        cap: fraction of the singular strain Bs/(RHOL·β·10⁶) after which the law
            is continued linearly (default 0.9) [-].
    """

    rhol: Array
    alpha: Array
    beta: Array
    breaking_strength: Array
    cap: float = eqx.field(static=True, default=0.9)

    def __init__(self, rhol, alpha, beta, breaking_strength, cap: float = 0.9):
        check_positive(rhol, "RHOL", "kg/m")
        check_positive(alpha, "alpha", "-")
        check_nonnegative(beta, "beta", "-")
        check_positive(breaking_strength, "breaking strength Bs", "N")
        self.rhol = as_float(rhol)
        self.alpha = as_float(alpha)
        self.beta = as_float(beta)
        self.breaking_strength = as_float(breaking_strength)
        self.cap = cap

    def tension_positive(self, strain):
        return _load_dependent_tension(
            strain, self.rhol * 1e6, self.alpha, self.beta, self.breaking_strength, self.cap
        )

    def nominal_ea(self):
        return self.rhol * 1e6 * self.alpha


class PolyesterMBL(AbstractAxialLaw):
    """MBL-normalised load-dependent stiffness used in industry.

    ``EA(T) = MBL·(α + β·T/MBL)`` with ``ε = T/EA(T)``, solved exactly for T.

    Args:
        mbl: minimum breaking load [N].
        alpha, beta: dimensionless stiffness constants [-] (e.g. α ≈ 10–30).
        cap: as in :class:`PolyesterWu`.
    """

    mbl: Array
    alpha: Array
    beta: Array
    cap: float = eqx.field(static=True, default=0.9)

    def __init__(self, mbl, alpha, beta, cap: float = 0.9):
        check_positive(mbl, "MBL", "N")
        check_positive(alpha, "alpha", "-")
        check_nonnegative(beta, "beta", "-")
        self.mbl = as_float(mbl)
        self.alpha = as_float(alpha)
        self.beta = as_float(beta)
        self.cap = cap

    def tension_positive(self, strain):
        return _load_dependent_tension(strain, self.mbl, self.alpha, self.beta, self.mbl, self.cap)

    def nominal_ea(self):
        return self.mbl * self.alpha


class TabulatedEA(AbstractAxialLaw):
    """Piecewise-linear strain–tension curve (as MoorDyn's nonlinear EA table).

    The table is prefixed with (0, 0) if it does not start there and is continued
    beyond its last point with its last slope.

    Args:
        strain: increasing strains [-].
        tension: tensions [N] at those strains, non-negative.
    """

    strain: Array
    tension_values: Array

    def __init__(self, strain, tension):
        s = jnp.asarray(strain, dtype=float)
        t = jnp.asarray(tension, dtype=float)
        if s.ndim != 1 or s.shape != t.shape or s.shape[0] < 1:
            raise ValueError(
                f"tabulated EA needs matching 1-D strain and tension arrays, got shapes {s.shape} and {t.shape}"
            )
        check_nonnegative(t, "tabulated tension", "N")
        check_nonnegative(s, "tabulated strain", "-")
        if not bool(jnp.all(jnp.diff(s) > 0)):
            raise ValueError(f"tabulated EA: strains {list(map(float, s))} must be strictly increasing")
        if float(s[0]) == 0.0 and float(t[0]) != 0.0:
            raise ValueError(
                f"tabulated EA: tension at strain 0 is {float(t[0])} N; expected 0 N "
                "(a slack line carries no tension)"
            )
        if float(s[0]) > 0.0:
            s = jnp.concatenate([jnp.zeros(1), s])
            t = jnp.concatenate([jnp.zeros(1), t])
        if s.shape[0] < 2:
            raise ValueError("tabulated EA needs at least one point with strain > 0")
        self.strain = s
        self.tension_values = t

    def tension_positive(self, strain):
        s, t = self.strain, self.tension_values
        last_slope = (t[-1] - t[-2]) / (s[-1] - s[-2])
        inside = jnp.interp(strain, s, t)
        return jnp.where(strain > s[-1], t[-1] + last_slope * (strain - s[-1]), inside)

    def nominal_ea(self):
        return (self.tension_values[1] - self.tension_values[0]) / (self.strain[1] - self.strain[0])


class Bilateral(AbstractAxialLaw):
    """Allow compression: ``T = law(ε)`` for ε ≥ 0 and ``nominal_EA·ε`` for ε < 0.

    This is Aamo & Fossen's ``EA·e`` form (their existence result assumes e > 0).
    """

    law: AbstractAxialLaw

    def tension_positive(self, strain):
        return self.law.tension_positive(strain)

    def nominal_ea(self):
        return self.law.nominal_ea()

    def tension(self, strain):
        return jnp.where(
            strain >= 0.0,
            self.law.tension_positive(jnp.maximum(strain, 0.0)),
            self.law.nominal_ea() * strain,
        )
