"""Time-domain simulation of a scene: settings → initial state → integrate → check.

``simulate`` validates its settings (:func:`~moorjax.dynamics.settings.plan`),
starts by default from the static equilibrium at t0
(:func:`~moorjax.dynamics.initial.equilibrium_state`), integrates the lines'
Galerkin equations (:func:`~moorjax.dynamics.integrate.integrate`, the one call
of diffrax) and raises with the cause when the run fails. It returns end forces
at requested times (by default every ``dt_out`` from t0, the initial state, to
the end of the run). A run must stay within the time span of every tabulated
motion it is given. The integration is one ``eqx.filter_jit``-compiled function:
calling it again with other parameter *values* (EA, Cd, lengths, motions of the
same shape) does not recompile; changing structure (segment counts, force
terms, solver) does.
"""

from __future__ import annotations

import time as _time
import warnings
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp

from .initial import initial_state as initial_state
from .initial import (catenary_state, check_geometry, equilibrium_state, failed_lines,
                      not_converged_message, start_layout)
from .integrate import SimulationResult as SimulationResult
from .._cache import StoredProgram
from .integrate import EVALUATIONS, failure_cause, integrate, is_implicit_solver, storable_run
from .newton import linearisation_evaluations
from .settings import Plan as Plan
from .settings import Settings as Settings
from .settings import check_time_span as check_time_span
from .settings import default_output_times as default_output_times
from .settings import plan as plan
from .vector_field import pack

_integrate = StoredProgram(integrate, storable=storable_run, compile_for="runs")


def simulate(
    scene,
    duration=None,
    *,
    ts=None,
    dt_out: float = 0.05,
    t0: float = 0.0,
    init=None,
    solver: str | Any = "auto",
    rtol: float = 1e-5,
    atol: float = 1e-4,
    atol_velocity: float | None = None,
    dt: float | None = None,
    dt0: float | None = None,
    max_steps: int = 1_000_000,
    save_nodes: bool = False,
    dense_newton: bool = False,
    linear_solver: str = "reduced",
    progress: bool = False,
    throw: bool = True,
    count_newton: bool = False,
    retry_failed_steps: bool = False,
    stretch_share: float | None = None,
) -> SimulationResult:
    """Integrate a scene in time.

    Args:
        scene: a :class:`moorjax.Scene`.
        duration: simulated time after ``t0`` [s] (or give ``ts``).
        ts: output times [s] (increasing, >= t0; the run ends at the last);
            default every ``dt_out`` s from t0 (the initial state) to
            ``t0 + duration`` (exactly, also when ``dt_out`` does not divide it).
        t0: start time [s]. Every tabulated motion of the scene must cover
            ``[t0, end of the run]``: a run that leaves it raises ``ValueError``
            (a point is never held still past the end of its motion).
        init: tuple of :class:`LineState` (default: static equilibrium at t0,
            :func:`~moorjax.dynamics.initial.equilibrium_state`; ``RuntimeError``
            if it does not converge), followed by each body's 1-D state
            (default: at rest at η = 0 when only line states are given); or a
            name: ``"statics"`` (the default) or ``"catenary"``, MoorDyn's start
            with ``TmaxIC = 0`` (:func:`~moorjax.dynamics.initial.catenary_state`:
            each line's own static shape, points and bodies where the scene puts
            them, not balanced; lines whose solve fails start straight, with a
            warning).
        solver: ``"auto"`` (default): ROS34PW2, the Rosenbrock-W method, for
            scenes of lines with the linear element (no bodies, no bending),
            else Kvaerno5 (see :func:`~moorjax.dynamics.settings.resolve_solver`);
            or a name from
            :data:`moorjax.dynamics.SOLVERS`, or a diffrax solver.
        rtol: relative error-control tolerance (of node positions and velocities).
        atol: absolute tolerance of node positions [m] (default 0.1 mm).
            Adaptive steps also hold each segment chord of a linear-element line
            to ``stretch_share·(atol + rtol·|r|)/n_segments`` (the line's position
            tolerance shared out over its segments), so that its tension error
            does not grow with the number of segments
            (:class:`~moorjax.dynamics.error_control.StretchControl`).
        atol_velocity: absolute tolerance of node velocities [m/s] (default
            100·atol per second). The same tolerances and norm stop the
            implicit methods' Newton iterations.
        dt: fixed step [s] (no error control) — otherwise adaptive, with a PI
            controller (coefficients 0.3/0.4, suited to stiff problems).
        retry_failed_steps: with ``dt``, retry a step whose Newton solve fails
            with a quarter of it (steps grow back to ``dt``; no error control).
            Lets fixed steps pass seabed landings and snap loads: case A at
            N = 40 completes at dt = 10, 20 and 50 ms (0.79–0.81 % error).
        stretch_share: multiplier of the segment-chord tolerance (default 1;
            ``float("inf")``: positions and velocities alone, as before session 24:
            at loose tolerances on fine meshes of stiff lines that let tension
            errors of 20× the tension's std through).
        dt0: first step of the adaptive controller [s] (default: dt_out/10).
        max_steps: step limit.
        save_nodes: also return node positions and segment tensions.
        linear_solver: Newton's linear solve: ``"reduced"`` (default; positions
            eliminated, 3×3 block-tridiagonal), ``"block"`` (6×6 blocks),
            ``"element"`` (each line's element factors its own stage matrix) or
            ``"dense"`` (dense LU, O(n³); for comparison). Scenes of Hermite
            lines (consistent mass: a dense Jacobian M⁻¹K) take ``"element"``
            (the block-tridiagonal mass form M − c·C − c²·K,
            :mod:`~moorjax.element.hermite_stage`; a clamped slope's held
            components projected out; with bodies each body's exact block
            beside its lines', their coupling left to the Newton iteration)
            where every line has the strain closure; other lines with the
            consistent mass (Eq. 2) and Wu's mixed field use ``"dense"``.
        dense_newton: same as ``linear_solver="dense"``.
        progress: print a text progress meter.
        throw: raise ``RuntimeError`` (with the simulated time and likely cause) if
            the solve fails; with ``False`` inspect ``result`` instead (for
            ensembles). Under ``jit``/``vmap`` use ``throw=False``.
        count_newton: count vector-field evaluations and Newton iterations
            (a diagnostic: a host callback per evaluation slows the run). For
            the implicit methods each step costs one evaluation at the
            Jacobian's linearisation point (none where the lines' elements
            factor their own stage matrix, two with diffrax's own chord,
            :func:`~moorjax.dynamics.newton.linearisation_evaluations`); every
            other evaluation is a Newton iteration.
    """
    p = plan(
        duration, ts=ts, dt_out=dt_out, t0=t0, solver=solver, rtol=rtol, atol=atol,
        atol_velocity=atol_velocity, dt=dt, dt0=dt0, max_steps=max_steps,
        save_nodes=save_nodes, dense_newton=dense_newton, linear_solver=linear_solver,
        progress=progress, scene=scene, retry_failed_steps=retry_failed_steps,
        stretch_share=stretch_share,
    )
    if init is None or isinstance(init, str):
        # the start is a static solve: compile the integration meanwhile (after
        # the geometry checks, so that an impossible line stops before any compile)
        check_geometry(scene, t0)
        _integrate.compile_ahead(scene, start_layout(scene), p, count=bool(count_newton))
    if isinstance(init, str):
        init = _named_start(scene, init, t0)
    if init is None:
        eq = equilibrium_state(scene, t0)
        if not isinstance(eq.converged, jax.core.Tracer) and not bool(eq.converged):
            raise RuntimeError(f"static equilibrium at t0 = {float(t0):g} s: "
                               + not_converged_message(scene, eq))
        init = eq.state
    elif scene.bodies and len(init) == len(scene.lines):
        init = tuple(init) + tuple(b.rest_state() for b in scene.bodies)
    EVALUATIONS[0] = 0
    res = _integrate(scene, pack(init, host=True), p, count=bool(count_newton))
    if count_newton:
        jax.block_until_ready(res.tension_b)
        evals = EVALUATIONS[0]
        steps = int(res.num_steps)
        implicit = is_implicit_solver(p.solver)
        newton = evals - linearisation_evaluations(p.solver) * steps if implicit else 0
        res = eqx.tree_at(
            lambda r: (r.num_newton_iterations, r.num_evaluations), res,
            (jnp.asarray(newton), jnp.asarray(evals)), is_leaf=lambda x: x is None,
        )
    if throw and not isinstance(res.num_steps, jax.core.Tracer):
        failure = failure_cause(res, max_steps,
                                fixed=dt is not None and is_implicit_solver(p.solver))
        if failure is not None:
            where, cause, code = failure
            raise RuntimeError(
                f"simulation with {p.name} failed {where}: {cause} [diffrax: {code}]")
    return res


def timed_simulate(scene, duration, **kwargs):
    """Run :func:`simulate` twice: returns (result, compile+first-run s, run s)."""
    t_a = _time.perf_counter()
    res = simulate(scene, duration, **kwargs)
    jax.block_until_ready(res.tension_b)
    t_b = _time.perf_counter()
    res = simulate(scene, duration, **kwargs)
    jax.block_until_ready(res.tension_b)
    t_c = _time.perf_counter()
    return res, t_b - t_a, t_c - t_b


INITIAL = ("statics", "catenary")


def _named_start(scene, name, t0):
    """``simulate``'s ``init`` given by name (:data:`INITIAL`)."""
    if name == "statics":
        return None
    if name != "catenary":
        raise ValueError(f"init = {name!r}: expected a tuple of states or one of {INITIAL}")
    eq = catenary_state(scene, t0)
    if not isinstance(eq.converged, jax.core.Tracer) and not bool(eq.converged):
        warnings.warn(f"init='catenary': the static solve of line(s) {', '.join(failed_lines(scene, eq))} "
                      "with the points "
                      "and bodies where the scene puts them did not converge; they start straight "
                      "between their ends, as MoorDyn's lines do when its catenary fails",
                      RuntimeWarning, stacklevel=3)
    return eq.state

