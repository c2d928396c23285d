"""Time-stepping methods by name, and the error norm they share.

Implicit (ESDIRK, L-stable) Kvaerno methods get a Newton (very-chord) root
finder whose linear solves exploit the structure of the stage matrix: the
Jacobian is rebuilt once per step from 18 coloured JVPs of the vector field, the
positions are eliminated (``ṙ = v`` makes their rows trivial) and the remaining
3×3 block-tridiagonal velocity system is factored in O(n)
(:class:`~moorjax.linalg.banded_solver.SecondOrderBandSolver`). The chord
iteration (:class:`~moorjax.dynamics.newton.StageChord`, :data:`NEWTON`) tests
convergence on the stage state. The linearly implicit ROS34PW2
(:mod:`~moorjax.dynamics.rosenbrock`, ``"ros34pw2"``) solves each of its four
stages with one band solve and no Newton iteration, with a Jacobian
approximation W that the linear element assembles from its stiff terms
(:func:`~moorjax.dynamics.vector_field.stiff_band`); it is what
``solver="auto"`` picks for scenes of such lines. Explicit methods are there
for comparison.

Error control measures positions [m] and velocities [m/s] on separate absolute
scales (:class:`StateNorm`): tensions depend on positions to ~EA/l per metre,
while velocity errors of a few mm/s are harmless; one common ``atol`` would make
the controller chase tiny high-frequency axial velocity oscillations. Adaptive
steps also measure each segment chord of a linear-element line
(:mod:`~moorjax.dynamics.error_control`).
"""

from __future__ import annotations

import diffrax
import equinox as eqx

from ..linalg.banded_solver import BlockTridiagonalSolver, SecondOrderBandSolver
from .error_control import StateNorm
from .newton import StageChord, StageFactorSolver, VeryChord
from .rosenbrock import RosenbrockW

__all__ = ["IMPLICIT", "EXPLICIT", "LINEARLY_IMPLICIT", "SOLVERS", "LINEAR_SOLVERS", "StateNorm", "make_solver",
           "is_implicit", "StageChord", "VeryChord"]

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
#: Rosenbrock-W methods: one matrix per step, no Newton iteration (see
#: :mod:`moorjax.dynamics.rosenbrock`)
LINEARLY_IMPLICIT = {
    "ros34pw2": RosenbrockW,
}
SOLVERS = tuple(sorted(IMPLICIT) + sorted(LINEARLY_IMPLICIT) + sorted(EXPLICIT))


LINEAR_SOLVERS = ("reduced", "block", "element", "dense")

#: the implicit methods' default chord root finder
NEWTON = StageChord


def make_solver(
    name: str,
    *,
    newton_rtol=None,
    newton_atol=None,
    norm=None,
    linear_solver: str = "reduced",
    dense_newton: bool = False,
    newton=None,
):
    """A diffrax solver from its name (case-insensitive).

    Args:
        name: one of :data:`SOLVERS`.
        newton_rtol, newton_atol, norm: Newton tolerances and norm of implicit
            methods; by default those of the step-size controller (with fixed
            steps there is none, so give them).
        linear_solver: Newton's linear solve: ``"reduced"`` (positions
            eliminated, 3×3 block-tridiagonal, default), ``"block"`` (6×6
            block-tridiagonal), ``"element"`` (each line's element factors its
            own stage matrix: the Hermite element's block-tridiagonal mass form,
            :mod:`~moorjax.element.hermite_stage`; implicit Runge–Kutta methods
            with :class:`~moorjax.dynamics.newton.StageChord` only) or
            ``"dense"`` (dense LU, O(n³), for comparison and for Jacobians that
            are not banded).
        dense_newton: same as ``linear_solver="dense"`` (kept for compatibility).
        newton: the chord root finder's class (default :data:`NEWTON`):
            :class:`~moorjax.dynamics.newton.StageChord` (tolerances on the
            stage state) or :class:`~moorjax.dynamics.newton.VeryChord`
            (diffrax's, tolerances on the iterated stage derivatives).
    """
    key = name.lower().replace("-", "_")
    if key in EXPLICIT:
        return EXPLICIT[key]()
    if key in LINEARLY_IMPLICIT:
        if linear_solver not in LINEAR_SOLVERS:
            raise ValueError(f"unknown linear solver {linear_solver!r}; choose one of "
                             f"{', '.join(LINEAR_SOLVERS)}")
        from .vector_field import stage_factors, stiff_linearisation

        if linear_solver == "element" and not dense_newton:
            return LINEARLY_IMPLICIT[key](structured=False, factors=_ByName(stage_factors))
        structured = not dense_newton and linear_solver != "dense"
        band = _ByName(stiff_linearisation) if structured else None
        return LINEARLY_IMPLICIT[key](structured=structured, band=band)
    if key not in IMPLICIT:
        raise ValueError(f"unknown solver {name!r}; choose one of {', '.join(SOLVERS)}")
    if dense_newton:
        linear_solver = "dense"
    if linear_solver not in LINEAR_SOLVERS:
        raise ValueError(
            f"unknown linear solver {linear_solver!r}; choose one of {', '.join(LINEAR_SOLVERS)}"
        )
    kwargs = {
        "reduced": {"linear_solver": SecondOrderBandSolver()},
        "block": {"linear_solver": BlockTridiagonalSolver()},
        "element": {"linear_solver": StageFactorSolver()},
        "dense": {},
    }[linear_solver]
    newton = NEWTON if newton is None else newton
    if newton_rtol is None:
        root_finder = diffrax.with_stepsize_controller_tols(newton)(**kwargs)
    else:
        if norm is not None:
            kwargs["norm"] = norm
        root_finder = newton(rtol=newton_rtol, atol=newton_atol, **kwargs)
    return IMPLICIT[key](root_finder=root_finder)


def is_implicit(name: str) -> bool:
    return name.lower().replace("-", "_") in IMPLICIT


class _ByName:
    """A module-level function as a solver's static field, named by its import
    path: equal and hashed as the function, and printed without an object
    address, so that a stored program's key (``moorjax._cache``) is the same in
    every process. Called through ``eqx.filter_jit``: traced once per structure
    of its arguments however often a step calls it (see
    :data:`~moorjax.dynamics.vector_field.traced_vector_field`)."""

    def __init__(self, fn):
        self.fn = fn
        self._traced = eqx.filter_jit(fn)

    def __call__(self, *args, **kwargs):
        return self._traced(*args, **kwargs)

    def __eq__(self, other):
        return isinstance(other, _ByName) and other.fn is self.fn

    def __hash__(self):
        return hash(self.fn)

    def __repr__(self):
        return f"{self.fn.__module__}.{self.fn.__qualname__}"

