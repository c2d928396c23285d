"""Time-stepping methods by name.

Implicit (ESDIRK, L-stable) Kvaerno methods get a Newton (very-chord) root
finder whose linear solves are block-tridiagonal: the Jacobian is rebuilt once per
step from 18 coloured JVPs of the vector field and factored in O(n). Explicit
methods are there for comparison.
"""

from __future__ import annotations

import diffrax

from ..linalg.banded_solver import BlockTridiagonalSolver

IMPLICIT = {
    "kvaerno3": diffrax.Kvaerno3,
    "kvaerno4": diffrax.Kvaerno4,
    "kvaerno5": diffrax.Kvaerno5,
    "implicit_euler": diffrax.ImplicitEuler,
}
EXPLICIT = {
    "tsit5": diffrax.Tsit5,
    "dopri5": diffrax.Dopri5,
    "dopri8": diffrax.Dopri8,
    "heun": diffrax.Heun,
    "midpoint": diffrax.Midpoint,
    "ralston": diffrax.Ralston,
    "bosh3": diffrax.Bosh3,
    "euler": diffrax.Euler,
}
SOLVERS = tuple(sorted(IMPLICIT) + sorted(EXPLICIT))


def make_solver(name: str, *, newton_rtol=None, newton_atol=None, dense_newton: bool = False):
    """A diffrax solver from its name (case-insensitive).

    Args:
        name: one of :data:`SOLVERS`.
        newton_rtol, newton_atol: Newton tolerances of implicit methods; by
            default those of the step-size controller (needed for fixed steps).
        dense_newton: use a dense LU instead of the block-tridiagonal solve
            (for comparison and for Jacobians that are not banded).
    """
    key = name.lower().replace("-", "_")
    if key in EXPLICIT:
        return EXPLICIT[key]()
    if key not in IMPLICIT:
        raise ValueError(f"unknown solver {name!r}; choose one of {', '.join(SOLVERS)}")
    linear_solver = None if dense_newton else BlockTridiagonalSolver()
    kwargs = {} if linear_solver is None else {"linear_solver": linear_solver}
    if newton_rtol is None:
        root_finder = diffrax.with_stepsize_controller_tols(diffrax.VeryChord)(**kwargs)
    else:
        root_finder = diffrax.VeryChord(rtol=newton_rtol, atol=newton_atol, **kwargs)
    return IMPLICIT[key](root_finder=root_finder)


def is_implicit(name: str) -> bool:
    return name.lower().replace("-", "_") in IMPLICIT
