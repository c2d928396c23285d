"""The validated settings of a time integration (:class:`Settings`, built by :func:`plan`).

One object carries everything the integrator needs besides the scene and the
initial state: output times, start time, solver (with its Newton root finder),
step-size controller, first step, step limit, whether node data are saved, the
progress meter, and the adjoint (how derivatives pass through the solve, see
:mod:`moorjax.dynamics.adjoint`) with its checkpoint count. ``simulate``,
ensembles and identification all build theirs here, so every setting is checked
in one place.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._numerics import as_float
from .adjoint import ADJOINTS, banded_jacobian, check_adjoint
from .meter import StepMeter
from .error_control import STRETCH_SHARE, StateNorm, StretchControl, stretch_segments
from .solvers import LINEARLY_IMPLICIT, is_implicit, make_solver
from .vector_field import has_stage_factors


class Settings(eqx.Module):
    """Validated, scene-independent settings of an integration (see :func:`plan`).

    Array fields (output times, t0, first step, tolerances inside the solver and
    controller) may change without recompiling; the static ones may not.
    """

    ts: Array
    t0: Array  # arrays, so other start times and first steps do not recompile
    solver: Any
    controller: Any
    dt0: Array
    max_steps: int = eqx.field(static=True)
    save_nodes: bool = eqx.field(static=True)
    meter: Any
    name: str = eqx.field(static=True)
    adjoint: str = eqx.field(static=True, default="checkpointed")
    checkpoints: int = eqx.field(static=True, default=0)  # reverse mode (0: diffrax's schedule)
    #: output times, t0 and the first step were checked on the host (not traced):
    #: diffrax's own runtime checks of them can then compile without host
    #: callbacks, so the run is kept in the persistent compilation cache
    host_checked: bool = eqx.field(static=True, default=False)

    @property
    def n_steps(self) -> int:
        """The step limit."""
        return self.max_steps

    def with_adjoint(self, adjoint: str) -> "Settings":
        """The same settings with another adjoint (``"checkpointed"`` or ``"forward"``)."""
        check_adjoint(adjoint)
        return dataclasses.replace(self, adjoint=adjoint)

    def run(self, scene, y0):
        """The pure integration: a :class:`~moorjax.dynamics.integrate.SimulationResult`
        (no checks, no throw)."""
        from .integrate import integrate

        return integrate(scene, y0, self)


#: the former name of :class:`Settings`
Plan = Settings

#: the method ``solver="auto"`` picks for scenes without a structured W
#: (bodies, Hermite or bending lines)
AUTO_FALLBACK = "kvaerno5"

def resolve_tolerances(solver, rtol, atol, atol_velocity=None, scene=None):
    """``(solver, rtol, atol, atol_velocity)`` with ``"auto"`` resolved
    (:func:`resolve_solver`) and ``atol_velocity`` defaulting to 100·atol: the
    settings a run uses, which passed again reproduce it.

    Until the step-size controller measured segment chords
    (:class:`~moorjax.dynamics.error_control.StretchControl`), ``auto`` ran
    ROS34PW2 at a tenth of the given tolerances, because at equal nominal
    tolerances it was less accurate than Kvaerno5. With the chords measured it is
    as accurate at the tolerances as given: on the reference cases (20 s, error
    against the N = 160 references) A, N = 40: 0.792 % at 4.8 ms per simulated
    s, against 0.792 % at 5.9 at the former tenth (Kvaerno5: 0.795 % at 10.9);
    B, N = 10: 0.664 % at 1.4 against 0.663 % at 2.2; a stiff chain swinging
    into a current (tests/data/current_steady) within 1.2e-3 of a converged run's
    fairlead tension (the former tenth: 1.9e-3); MoorDyn's wavekin_3.txt, 45 s:
    0.015 of the tension's std (0.022). See benchmarks/README.md, "Session 24".
    """
    name = resolve_solver(solver, scene)
    if atol_velocity is None:
        atol_velocity = 100.0 * float(atol)
    return name, rtol, atol, atol_velocity


def factorises_nothing_dense(solver) -> bool:
    """Whether ``solver`` (a diffrax solver object) steps without dense
    factorisations of its own: the Rosenbrock-W stepper (on a band, for scenes
    that give one) or an explicit Runge–Kutta method. The Kvaerno methods'
    Newton iterations may factorise dense matrices (batched LAPACK kernels;
    see :func:`moorjax._xla_flags.pool_for_devices`)."""
    from .rosenbrock import RosenbrockW

    return isinstance(solver, RosenbrockW | diffrax.AbstractERK)


def resolve_solver(solver, scene=None):
    """The method name ``"auto"`` stands for: ``"ros34pw2"`` (the Rosenbrock-W
    method; as accurate as Kvaerno5 at equal tolerances and 1.5–2.5× cheaper on
    the reference cases)
    when every line provides a structured Jacobian approximation (linear element,
    nodal mass, no bending) and there are no bodies, else ``"kvaerno5"``; other
    names and solver objects are returned as they are."""
    if not (isinstance(solver, str) and solver.lower() == "auto"):
        return solver
    from .vector_field import has_stiff_band

    return "ros34pw2" if scene is not None and has_stiff_band(scene) else AUTO_FALLBACK


#: smallest adaptive step [s], relative to max(1 s, end time)
_DT_MIN = 1e-9

#: a retried step is this fraction of the failed one; steps grow back by at most
#: ``1/RETRY`` per accepted step, up to ``dt`` (see ``retry_failed_steps``)
RETRY = 0.25


def plan(
    duration=None,
    *,
    ts=None,
    dt_out: float = 0.05,
    t0: float = 0.0,
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
    scene=None,
    adjoint: str = "checkpointed",
    checkpoints: int = 0,
    retry_failed_steps: bool = False,
    stretch_share: float | None = None,
) -> Settings:
    """Check the settings of :func:`~moorjax.dynamics.simulate` (same arguments)
    and build the solver.

    ``solver="auto"`` (the default) resolves with :func:`resolve_tolerances`
    (without ``scene``: Kvaerno5). Raises ``ValueError`` naming the offending
    setting. With ``scene``, a
    structured linear solver is replaced by the dense one when some line's
    element does not have a block-tridiagonal Jacobian (consistent mass), and
    the run is checked against the time spans of the scene's motions.

    Further (for differentiable runs, see :mod:`moorjax.identify`):
        adjoint: ``"checkpointed"`` (reverse mode) or ``"forward"``.
        checkpoints: reverse-mode checkpoints (0: diffrax's O(√steps) schedule);
            used only when they fit in :data:`~moorjax.dynamics.adjoint.CHECKPOINT_BYTES`.
        retry_failed_steps: with ``dt``, retry a step whose implicit (Newton)
            solve fails with a quarter of it (steps grow back to ``dt``): a PID
            controller whose error control is off. Where no step fails the
            steps are exactly ``dt``.
        stretch_share: adaptive steps: the multiplier of the segment-chord
            tolerance (:class:`~moorjax.dynamics.error_control.StretchControl`;
            default :data:`~moorjax.dynamics.error_control.STRETCH_SHARE`,
            ``inf`` measures the state alone).
    """
    check_adjoint(adjoint)
    if stretch_share is None:
        stretch_share = STRETCH_SHARE
    if not (float(stretch_share) > 0):
        raise ValueError(f"stretch_share = {stretch_share} must be > 0 (inf: chords not measured)")
    if atol_velocity is None:
        atol_velocity = 100.0 * float(atol)
    for name, tol, unit, hi in (
        ("rtol", rtol, "", 0.1),
        ("atol", atol, " m", 0.1),
        ("atol_velocity", atol_velocity, " m/s", 10.0),
    ):
        if not (1e-14 <= float(tol) <= hi):
            raise ValueError(f"{name} = {tol}{unit} is out of range; expected 1e-14 <= {name} <= {hi}")
    solver, rtol, atol, atol_velocity = resolve_tolerances(solver, rtol, atol, atol_velocity, scene)
    if scene is not None and linear_solver in ("reduced", "block") and not banded_jacobian(scene):
        # Hermite lines factor their stage matrix in mass form (block-tridiagonal)
        linear_solver = "element" if has_stage_factors(scene) else "dense"
    if linear_solver == "element" and (scene is None or not has_stage_factors(scene)):
        raise ValueError("linear_solver='element' needs a scene whose lines all factor their "
                         "stage matrix (Hermite lines with the strain closure)")
    if (scene is not None and scene.bodies and isinstance(solver, str)
            and solver.lower() in LINEARLY_IMPLICIT):
        linear_solver = "dense"  # ROS2's band needs line states only
    if ts is None:
        if duration is None:
            raise ValueError("give the simulated duration [s] or the output times ts")
        duration = float(duration)
        if not np.isfinite(duration) or duration <= 0:
            raise ValueError(f"duration = {duration} s must be a positive finite number")
        if not (np.isfinite(dt_out) and dt_out > 0):
            raise ValueError(f"dt_out = {dt_out} s must be > 0")
        ts = t0 + default_output_times(duration, dt_out)
    # concrete times stay NumPy arrays: the compiled run takes them as arguments
    # (a device_put of its own costs tens of µs per array, see _host_float)
    ts = jnp.asarray(ts, dtype=float) if isinstance(ts, jax.core.Tracer) else _host_float(ts)
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
    ratio = float(atol) / float(atol_velocity)

    if isinstance(solver, str):
        name = solver
        fixed_implicit = dt is not None and is_implicit(solver)
        solver = _solver(solver, float(rtol) if fixed_implicit else None,
                         float(atol) if fixed_implicit else None, ratio, linear_solver,
                         bool(dense_newton))
    else:
        name = type(solver).__name__
    if dt is not None:
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt = {dt} s must be > 0")
        step0 = dt
        if retry_failed_steps:
            controller = diffrax.PIDController(
                # error control off (velocities on plan's default 100x looser
                # scale): only steps whose Newton solve fails are retried
                rtol=1.0, atol=1e9, norm=StateNorm(jnp.asarray(0.01)),
                dtmax=float(dt), dtmin=float(dt) * RETRY**6, force_dtmin=False,
                factormin=RETRY, factormax=1.0 / RETRY,
            )
        else:
            controller = diffrax.ConstantStepSize()
    else:
        # dtmin: a member whose state turns non-finite stops at once (with
        # RESULTS.dt_min_reached) instead of shrinking its step until max_steps.
        t_end = float(np.max(np.abs(np.asarray(ts)))) if not isinstance(ts, jax.core.Tracer) else 1.0
        controller = _adaptive(float(rtol), float(atol), ratio, _DT_MIN * max(1.0, t_end),
                               stretch_segments(scene), float(stretch_share))
        if dt0 is not None and not (np.isfinite(dt0) and dt0 > 0):
            raise ValueError(f"dt0 = {dt0} s (the first adaptive step) must be > 0")
        step0 = dt0 if dt0 is not None else float(dt_out) / 10.0

    meter = StepMeter() if progress else _NO_METER
    return Settings(
        ts, _host_float(t0), solver, controller, _host_float(step0),
        int(max_steps), bool(save_nodes), meter, name, adjoint, int(checkpoints),
        host_checked=not isinstance(ts, jax.core.Tracer),
    )


def _host_float(x):
    """A float64 NumPy array of concrete ``x`` (a traced one as ``jnp``). A plan's
    times are arguments of the compiled run, which places NumPy arrays on the
    device in its own call; ``jax.device_put`` per array cost about 50 µs of a
    plan's 0.45 ms (case B integrates 20 s in about 8 ms)."""
    if isinstance(x, jax.core.Tracer):
        return jnp.asarray(x, dtype=float)
    return np.asarray(x, dtype=np.float64)


#: the progress meter of a run without one (built once: a module costs µs to make)
_NO_METER = diffrax.NoProgressMeter()


# -- the solver and controller of a plan, built once per setting --------------
#
# Building them (equinox modules, each tolerance an array on the device) took
# about 0.5 ms, a twentieth of integrating 20 s of reference case B; they hold
# no state, so a plan with the same settings shares them. They are built with
# ``jax.ensure_compile_time_eval``: a plan made while tracing (``simulate``
# under the caller's ``jit``) would otherwise keep that trace's tracers.

@functools.lru_cache(maxsize=64)
def _norm(ratio: float) -> StateNorm:
    with jax.ensure_compile_time_eval():
        return StateNorm(as_float(ratio))


@functools.lru_cache(maxsize=64)
def _solver(name, newton_rtol, newton_atol, ratio, linear_solver, dense_newton):
    """:func:`make_solver` (the Newton tolerances given with fixed steps only)."""
    with jax.ensure_compile_time_eval():
        return make_solver(
            name,
            newton_rtol=None if newton_rtol is None else as_float(newton_rtol),
            newton_atol=None if newton_atol is None else as_float(newton_atol),
            norm=_norm(ratio),
            linear_solver=linear_solver,
            dense_newton=dense_newton,
        )


@functools.lru_cache(maxsize=64)
def _adaptive(rtol, atol, ratio, dtmin, segments=(), share=STRETCH_SHARE):
    """The adaptive step-size controller (coefficients 0.3/0.4, suited to stiff
    problems); dtmin [s]: a member whose state turns non-finite stops at once;
    segments, share: the segment chords it measures
    (:class:`~moorjax.dynamics.error_control.StretchControl`)."""
    with jax.ensure_compile_time_eval():
        return StretchControl(
            rtol=as_float(rtol), atol=as_float(atol), norm=_norm(ratio), pcoeff=0.3,
            icoeff=0.4, dtmin=jnp.asarray(dtmin), force_dtmin=False,
            segments=segments, stretch_share=as_float(share),
        )


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


__all__ = ["ADJOINTS", "Plan", "Settings", "banded_jacobian", "check_time_span",
           "default_output_times", "plan", "resolve_solver"]
