"""Time-domain simulation of a scene with diffrax.

``simulate`` integrates the lines' Galerkin equations from an initial state (by
default the static equilibrium at t0) and returns end forces at requested times
(by default every ``dt_out`` from t0, the initial state, to the end of the run).
A run must stay within the time span of every tabulated motion it is given.
The core is one ``eqx.filter_jit``-compiled function: calling it again with other
parameter *values* (EA, Cd, lengths, motions of the same shape) does not
recompile; changing structure (segment counts, force terms, solver) does.
"""

from __future__ import annotations

import time as _time
from typing import Any

import diffrax
import equinox as eqx
import jax
import jax.experimental
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from ..statics.fem import solve_line_statics
from .solvers import StateNorm, is_implicit, make_solver
from .vector_field import end_outputs, pack, unpack, vector_field


class SimulationResult(eqx.Module):
    """Outputs of :func:`simulate` (leading axis: output times).

    Attributes:
        ts: (k,) output times [s] (by default t0, t0 + dt_out, …, t0 + duration).
        tension_a, tension_b: (k, n_lines) end tensions [N] (magnitude of the force
            the line exerts on its end A / B point).
        force_a, force_b: (k, n_lines, 3) those forces [N].
        positions, segment_tensions: per-line tuples of (k, n+1, 3) [m] and (k, n)
            [N] when requested, else ``None``.
        final_state: tuple of :class:`LineState` at the last time reached.
        num_steps, num_accepted_steps, num_rejected_steps: solver statistics.
        result: diffrax result code (0 = success); see :meth:`succeeded`.
        num_newton_iterations: Newton iterations of all implicit stages (only
            with ``simulate(..., count_newton=True)``, else ``None``).
        num_evaluations: vector-field evaluations (with ``count_newton``).
        body_pose, body_velocity: (k, n_bodies, 6) displacements η [m, rad] and
            velocities η̇ of the scene's floating bodies (``None`` without bodies).
    """

    ts: Array
    tension_a: Array
    tension_b: Array
    force_a: Array
    force_b: Array
    positions: Any
    segment_tensions: Any
    final_state: Any
    num_steps: Array
    num_accepted_steps: Array
    num_rejected_steps: Array
    result: Any
    num_newton_iterations: Any = None
    num_evaluations: Any = None
    body_pose: Any = None
    body_velocity: Any = None

    def succeeded(self):
        return self.result == diffrax.RESULTS.successful


#: host-side count of vector-field evaluations (diagnostic runs only)
_EVALUATIONS = [0]


def _bump():
    _EVALUATIONS[0] += 1


def _counted_vector_field(t, y, scene):
    """The vector field, counting its evaluations on the host (slow: a callback each)."""
    jax.experimental.io_callback(_bump, None, ordered=False)
    return vector_field(t, y, scene)


def _solve(scene, y0, ts, t0, solver, controller, dt0, max_steps, with_nodes, progress,
           count=False):
    """One integration as a pure function of arrays (jit-, vmap- and grad-able)."""
    term = diffrax.ODETerm(_counted_vector_field if count else vector_field)
    saveat = diffrax.SaveAt(
        ts=ts, t1=True, fn=lambda t, y, args: (end_outputs(t, y, args, with_nodes), y)
    )
    sol = diffrax.diffeqsolve(
        term,
        solver,
        t0,
        ts[-1],
        dt0,
        y0,
        args=scene,
        saveat=saveat,
        stepsize_controller=controller,
        max_steps=max_steps,
        throw=False,
        progress_meter=progress,
    )
    outs, ys = sol.ys  # ts outputs, then the t1 (last reached) entry
    return SimulationResult(
        ts=ts,
        tension_a=outs["tension_a"][:-1],
        tension_b=outs["tension_b"][:-1],
        force_a=outs["force_a"][:-1],
        force_b=outs["force_b"][:-1],
        positions=(tuple(p[:-1] for p in outs["positions"]) if with_nodes else None),
        segment_tensions=(
            tuple(p[:-1] for p in outs["segment_tensions"]) if with_nodes else None
        ),
        final_state=unpack(jax.tree_util.tree_map(lambda a: a[-1], ys)),
        num_steps=sol.stats["num_steps"],
        num_accepted_steps=sol.stats["num_accepted_steps"],
        num_rejected_steps=sol.stats["num_rejected_steps"],
        result=sol.result,
        body_pose=outs["body_pose"][:-1] if "body_pose" in outs else None,
        body_velocity=outs["body_velocity"][:-1] if "body_velocity" in outs else None,
    )


_integrate = eqx.filter_jit(_solve)


class Plan(eqx.Module):
    """Validated, scene-independent settings of a simulation (see :func:`plan`)."""

    ts: Array
    t0: Array  # arrays, so other start times and first steps do not recompile
    solver: Any
    controller: Any
    dt0: Array
    max_steps: int = eqx.field(static=True)
    save_nodes: bool = eqx.field(static=True)
    meter: Any
    name: str = eqx.field(static=True)

    def run(self, scene, y0):
        """The pure integration: a :class:`SimulationResult` (no checks, no throw)."""
        return _solve(
            scene, y0, self.ts, self.t0, self.solver, self.controller, self.dt0,
            self.max_steps, self.save_nodes, self.meter,
        )


def plan(
    duration=None,
    *,
    ts=None,
    dt_out: float = 0.05,
    t0: float = 0.0,
    solver: str | Any = "kvaerno5",
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
    scene=None,
) -> Plan:
    """Check the settings of :func:`simulate` (same arguments) and build the solver.

    Raises ``ValueError`` naming the offending setting. Used by :func:`simulate`
    and by ensembles, which run one plan on many scenes. With ``scene``, a
    structured linear solver is replaced by the dense one when some line's
    element does not have a block-tridiagonal Jacobian (consistent mass).
    """
    if scene is not None and linear_solver in ("reduced", "block") and not all(
        line.banded_jacobian for line in scene.lines
    ):
        linear_solver = "dense"
    if ts is None:
        if duration is None:
            raise ValueError("give the simulated duration [s] or the output times ts")
        duration = float(duration)
        if not np.isfinite(duration) or duration <= 0:
            raise ValueError(f"duration = {duration} s must be a positive finite number")
        if not (np.isfinite(dt_out) and dt_out > 0):
            raise ValueError(f"dt_out = {dt_out} s must be > 0")
        ts = t0 + default_output_times(duration, dt_out)
    ts = jnp.asarray(ts, dtype=float)
    if ts.ndim != 1 or ts.shape[0] < 1:
        raise ValueError("output times ts must be a non-empty 1-D array [s]")
    if not isinstance(ts, jax.core.Tracer):
        tsn = np.asarray(ts)
        if not np.all(np.isfinite(tsn)) or np.any(np.diff(tsn) <= 0) or tsn[0] < t0:
            raise ValueError(f"output times [s] must be finite, increasing and >= t0 = {t0}")
        if tsn[-1] <= t0:
            raise ValueError(f"the last output time {tsn[-1]} s must be after t0 = {t0} s")
        if scene is not None:
            check_time_span(scene, float(t0), float(tsn[-1]))
    if atol_velocity is None:
        atol_velocity = 100.0 * float(atol)
    for name, tol, unit, hi in (
        ("rtol", rtol, "", 0.1),
        ("atol", atol, " m", 0.1),
        ("atol_velocity", atol_velocity, " m/s", 10.0),
    ):
        if not (1e-14 <= float(tol) <= hi):
            raise ValueError(f"{name} = {tol}{unit} is out of range; expected 1e-14 <= {name} <= {hi}")
    norm = StateNorm(jnp.asarray(float(atol) / float(atol_velocity)))
    rtol_a, atol_a = jnp.asarray(float(rtol)), jnp.asarray(float(atol))

    if isinstance(solver, str):
        name = solver
        fixed_implicit = dt is not None and is_implicit(solver)
        solver = make_solver(
            solver,
            newton_rtol=rtol_a if fixed_implicit else None,
            newton_atol=atol_a if fixed_implicit else None,
            norm=norm,
            linear_solver=linear_solver,
            dense_newton=dense_newton,
        )
    else:
        name = type(solver).__name__
    if dt is not None:
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt = {dt} s must be > 0")
        controller = diffrax.ConstantStepSize()
        step0 = dt
    else:
        # dtmin: a member whose state turns non-finite stops at once (with
        # RESULTS.dt_min_reached) instead of shrinking its step until max_steps.
        t_end = float(np.max(np.abs(np.asarray(ts)))) if not isinstance(ts, jax.core.Tracer) else 1.0
        controller = diffrax.PIDController(
            rtol=rtol_a, atol=atol_a, norm=norm, pcoeff=0.3, icoeff=0.4,
            dtmin=jnp.asarray(_DT_MIN * max(1.0, t_end)), force_dtmin=False,
        )
        step0 = dt0 if dt0 is not None else float(dt_out) / 10.0

    meter = diffrax.TextProgressMeter() if progress else diffrax.NoProgressMeter()
    return Plan(
        ts, jnp.asarray(float(t0)), solver, controller, jnp.asarray(float(step0)),
        int(max_steps), bool(save_nodes), meter, name,
    )


_DT_MIN = 1e-9  # [s] smallest adaptive step, relative to max(1 s, end time)


def default_output_times(duration, dt_out):
    """0, dt_out, 2·dt_out, … [s] after the start, ending with ``duration`` itself
    (exactly: the last sample is where the run ends)."""
    k = int(np.floor(duration / dt_out * (1 + 1e-12)))
    ts = dt_out * np.arange(k + 1)
    if duration - ts[-1] > 1e-9 * duration:
        return np.append(ts, duration)
    ts[-1] = duration
    return ts


def check_time_span(scene, t0, t1):
    """Refuse a run from ``t0`` to ``t1`` [s] that leaves the time span of one of
    the scene's line ends (a tabulated motion): ``ValueError`` naming the line,
    the end, both spans and the fix. Spans that are traced values are skipped."""
    tol = 1e-9 * max(1.0, abs(t0), abs(t1))
    for line in scene.lines:
        for name, end in (("A", line.end_a), ("B", line.end_b)):
            lo, hi = end.time_span()
            if isinstance(lo, jax.core.Tracer) or isinstance(hi, jax.core.Tracer):
                continue
            lo, hi = float(lo), float(hi)
            where = f"line {line.label} end {name}: its prescribed motion"
            need = f"the motion must cover the whole run, t = {t0:.10g} to {t1:.10g} s"
            if lo > t0 + tol:
                raise ValueError(
                    f"{where} starts at t = {lo:.10g} s, after the start of the run t0 = "
                    f"{t0:.10g} s; {need}: give it from t0 on, or start the run at "
                    f"t0 = {lo:.10g} s"
                )
            if hi < t1 - tol:
                raise ValueError(
                    f"{where} ends at t = {hi:.10g} s, before the end of the run at "
                    f"{t1:.10g} s; {need}: extend it to at least {t1:.10g} s (to hold the "
                    "point still, add rows at its last position with zero velocity) or "
                    "shorten the run"
                )


def _first_bad_time(ts, tension):
    bad = ~np.all(np.isfinite(tension), axis=-1)
    return float(ts[np.argmax(bad)]) if bad.any() else None


def simulate(
    scene,
    duration=None,
    *,
    ts=None,
    dt_out: float = 0.05,
    t0: float = 0.0,
    init=None,
    solver: str | Any = "kvaerno5",
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
        init: tuple of :class:`LineState` (default: static equilibrium at t0),
            followed by each body's 1-D state (default: at rest at η = 0 when
            only line states are given).
        solver: a name from :data:`moorjax.dynamics.SOLVERS` or a diffrax solver.
        rtol: relative error-control tolerance (of node positions and velocities).
        atol: absolute tolerance of node positions [m] (default 0.1 mm: a
            tension error of about EA/l·atol).
        atol_velocity: absolute tolerance of node velocities [m/s] (default
            100·atol per second). The same tolerances and norm stop the
            implicit methods' Newton iterations.
        dt: fixed step [s] (no error control) — otherwise adaptive, with a PI
            controller (coefficients 0.3/0.4, suited to stiff problems).
        dt0: first step of the adaptive controller [s] (default: dt_out/10).
        max_steps: step limit.
        save_nodes: also return node positions and segment tensions.
        linear_solver: Newton's linear solve: ``"reduced"`` (default; positions
            eliminated, 3×3 block-tridiagonal), ``"block"`` (6×6 blocks) or
            ``"dense"`` (dense LU, O(n³); for comparison). Lines with the
            consistent mass (Eq. 2) have a dense Jacobian (M⁻¹K), so they always
            use ``"dense"``.
        dense_newton: same as ``linear_solver="dense"``.
        progress: print a text progress meter.
        throw: raise ``RuntimeError`` (with the simulated time and likely cause) if
            the solve fails; with ``False`` inspect ``result`` instead (for
            ensembles). Under ``jit``/``vmap`` use ``throw=False``.
        count_newton: count vector-field evaluations and Newton iterations
            (a diagnostic: a host callback per evaluation slows the run). For
            the implicit methods each step costs one evaluation at its start
            (the explicit first stage; implicit Euler's error estimate) and one
            for the Jacobian's linearisation point; every other evaluation is
            a Newton iteration.
    """
    p = plan(
        duration, ts=ts, dt_out=dt_out, t0=t0, solver=solver, rtol=rtol, atol=atol,
        atol_velocity=atol_velocity, dt=dt, dt0=dt0, max_steps=max_steps,
        save_nodes=save_nodes, dense_newton=dense_newton, linear_solver=linear_solver,
        progress=progress, scene=scene,
    )
    if init is None:
        init = initial_state(scene, t0)
    elif scene.bodies and len(init) == len(scene.lines):
        init = tuple(init) + tuple(b.rest_state() for b in scene.bodies)
    _EVALUATIONS[0] = 0
    res = _integrate(
        scene, pack(init), p.ts, p.t0, p.solver, p.controller, p.dt0, p.max_steps,
        p.save_nodes, p.meter, bool(count_newton),
    )
    if count_newton:
        jax.block_until_ready(res.tension_b)
        evals = _EVALUATIONS[0]
        steps = int(res.num_steps)
        implicit = isinstance(p.solver, diffrax.AbstractImplicitSolver)
        newton = evals - 2 * steps if implicit else 0
        res = eqx.tree_at(
            lambda r: (r.num_newton_iterations, r.num_evaluations), res,
            (jnp.asarray(newton), jnp.asarray(evals)), is_leaf=lambda x: x is None,
        )
    name = p.name
    if throw and not isinstance(res.num_steps, jax.core.Tracer):
        _raise_on_failure(res, name, max_steps, fixed=dt is not None)
    return res


def initial_state(scene, t0=0.0) -> tuple:
    """The static equilibrium at t0 as a solver-ready state: line states, then each
    body at rest at its equilibrium pose (mean loads included)."""
    if not scene.bodies:
        return tuple(solve_line_statics(line, scene.env, t0).state() for line in scene.lines)
    from ..statics.system import solve_system_statics

    st = solve_system_statics(scene, t0)
    return st.state() + st.body_states(scene)


def _raise_on_failure(res, name, max_steps, fixed=False):
    ok = bool(res.succeeded())
    tension = np.asarray(res.tension_b)
    t_bad = _first_bad_time(np.asarray(res.ts), tension)
    if ok and t_bad is None:
        return
    code = res.result
    if code == diffrax.RESULTS.max_steps_reached:
        cause = f"the step limit max_steps={max_steps} was reached (raise it, or loosen tolerances)"
    elif code == diffrax.RESULTS.dt_min_reached:
        cause = (
            "the step size fell below its minimum (the state became non-finite, or a "
            "snap load or slack line the method cannot resolve: check the inputs, try "
            "tighter tolerances or more segments)"
        )
    elif fixed and code != diffrax.RESULTS.successful:
        cause = (
            "Newton did not converge at the fixed step dt (a snap load or slack line "
            "within one step?): use adaptive steps (no dt) or a smaller dt"
        )
    elif code in (
        diffrax.RESULTS.nonlinear_divergence,
        diffrax.RESULTS.singular,
        diffrax.RESULTS.nonlinear_max_steps_reached,
    ):
        cause = "Newton did not converge even at the smallest step (stiff snap or slack line?)"
    else:
        cause = (
            "the state became non-finite or the step size collapsed (a snap load or "
            "slack line the method cannot resolve: try an implicit solver, smaller "
            "tolerances or more segments)"
        )
    where = (
        f"at t ≈ {t_bad:.6g} s" if t_bad is not None else f"before t = {float(res.ts[-1]):.6g} s"
    )
    raise RuntimeError(f"simulation with {name} failed {where}: {cause} [diffrax: {code}]")


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
