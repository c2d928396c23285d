"""The time integration: the one call of ``diffrax.diffeqsolve``.

:func:`integrate` is a pure function of the scene's arrays, the initial state
and the :class:`~moorjax.dynamics.settings.Settings` (jit-, vmap- and
grad-able); ``simulate``, ensembles (a ``vmap`` of it) and identification (its
gradient) all run it. It never raises: the diffrax result code and the outputs
say what happened; :func:`failure_cause` words a failure, :func:`result_names`
names the codes.
"""

from __future__ import annotations

import contextlib
from typing import Any

import diffrax
import equinox as eqx
import jax
import jax.experimental
import numpy as np
from jaxtyping import Array

from .._cache import host_checked_inputs
from .adjoint import diffrax_adjoint
from .vector_field import end_outputs, traced_vector_field, unpack, vector_field


class SimulationResult(eqx.Module):
    """Outputs of :func:`~moorjax.dynamics.simulate` (leading axis: output times).

    Attributes:
        ts: (k,) output times [s] (by default t0, t0 + dt_out, …, t0 + duration).
        tension_a, tension_b: (k, n_lines) end tensions [N] (magnitude of the force
            the line exerts on its end A / B point).
        force_a, force_b: (k, n_lines, 3) those forces [N].
        positions, segment_tensions: per-line tuples of (k, n+1, 3) [m] and (k, n)
            [N] when requested, else ``None``.
        final_state: tuple of :class:`LineState` at the last time reached, then
            each body's 1-D state (``None`` when not kept, see :func:`integrate`).
        num_steps, num_accepted_steps, num_rejected_steps: solver statistics.
        result: diffrax result code (0 = success); see :meth:`succeeded`.
        num_newton_iterations: Newton iterations of all implicit stages (only
            with ``simulate(..., count_newton=True)``, else ``None``).
        num_evaluations: vector-field evaluations (with ``count_newton``).
        body_pose, body_velocity: (k, n_bodies, 6) displacements η [m, rad] and
            velocities η̇ of the scene's floating bodies (``None`` without bodies).
        velocities: per-line tuple of (k, n+1, 3) node velocities [m/s] with
            ``positions``, else ``None``.
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
    velocities: Any = None

    def succeeded(self):
        return self.result == diffrax.RESULTS.successful


#: host-side count of vector-field evaluations (diagnostic runs only)
EVALUATIONS = [0]


def _bump():
    EVALUATIONS[0] += 1


def _counted_vector_field(t, y, scene):
    """The vector field, counting its evaluations on the host (slow: a callback each)."""
    jax.experimental.io_callback(_bump, None, ordered=False)
    return vector_field(t, y, scene)


def integrate(scene, y0, settings, *, count: bool = False, keep_final: bool = True
              ) -> SimulationResult:
    """Integrate ``scene`` from the solver state ``y0`` (see
    :func:`~moorjax.dynamics.vector_field.pack`) with ``settings``.

    Args:
        count: count vector-field evaluations on the host (:data:`EVALUATIONS`).
        keep_final: also return the state at the last time reached
            (``final_state``); without it only what the end outputs need is
            saved (the states at the output times, or the outputs themselves,
            see :func:`outputs_after_loop`), which is all a gradient needs.

    Returns a :class:`SimulationResult`; never raises on a failed solve (the
    outputs after the failure are not finite: diffrax fills them with inf).
    """
    s = settings
    with_nodes = s.save_nodes
    term = diffrax.ODETerm(_counted_vector_field if count else traced_vector_field)
    dt0 = None if isinstance(s.controller, diffrax.StepTo) else s.dt0
    after = outputs_after_loop(y0, s.ts)
    if after:  # the states at ts, their outputs after the loop (see outputs_after_loop)
        subs = [diffrax.SubSaveAt(ts=s.ts)] + ([diffrax.SubSaveAt(t1=True)] if keep_final else [])
        saveat = diffrax.SaveAt(subs=subs)
    elif keep_final:
        saveat = diffrax.SaveAt(
            ts=s.ts, t1=True, fn=lambda t, y, args: (end_outputs(t, y, args, with_nodes), y)
        )
    else:
        saveat = diffrax.SaveAt(ts=s.ts, fn=lambda t, y, args: end_outputs(t, y, args, with_nodes))
    # plan() checked ts, t0 and dt0 on the host: diffrax's runtime checks of
    # them then compile without host callbacks (see moorjax._cache)
    checks = host_checked_inputs() if s.host_checked else contextlib.nullcontext()
    with checks:
        sol = _solve(term, s, dt0, y0, scene, saveat)
    if after:
        outs = jax.vmap(lambda t, y: end_outputs(t, y, scene, with_nodes))(s.ts, sol.ys[0])
        final_y = sol.ys[1] if keep_final else None
        cut = lambda a: a  # noqa: E731
    elif keep_final:
        outs, final_y = sol.ys  # ts outputs, then the t1 (last reached) entry
        cut = lambda a: a[:-1]  # noqa: E731
    else:
        outs, final_y = sol.ys, None
        cut = lambda a: a  # noqa: E731
    final = None if final_y is None else unpack(jax.tree_util.tree_map(lambda a: a[-1], final_y),
                                                scene.lines)
    return SimulationResult(
        ts=s.ts,
        tension_a=cut(outs["tension_a"]),
        tension_b=cut(outs["tension_b"]),
        force_a=cut(outs["force_a"]),
        force_b=cut(outs["force_b"]),
        positions=(tuple(cut(p) for p in outs["positions"]) if with_nodes else None),
        segment_tensions=(tuple(cut(p) for p in outs["segment_tensions"]) if with_nodes else None),
        final_state=final,
        num_steps=sol.stats["num_steps"],
        num_accepted_steps=sol.stats["num_accepted_steps"],
        num_rejected_steps=sol.stats["num_rejected_steps"],
        result=sol.result,
        body_pose=cut(outs["body_pose"]) if "body_pose" in outs else None,
        body_velocity=cut(outs["body_velocity"]) if "body_velocity" in outs else None,
        velocities=(tuple(cut(p) for p in outs["velocities"]) if with_nodes else None),
    )


#: the most numbers of saved states (output times × state size) for which an
#: integration saves its states and computes its outputs after the loop
#: (:func:`outputs_after_loop`): 2²² float64, 32 MB
STATES_AFTER_LOOP = 2 ** 22


def outputs_after_loop(y0, ts) -> bool:
    """Whether :func:`integrate` saves the states at its output times and computes
    the outputs (:func:`~moorjax.dynamics.vector_field.end_outputs`) from them after
    the time loop, in one call vectorised over the output times, instead of inside
    the loop at every output time (structure only: shapes, decided at trace time).

    Inside the loop diffrax compiles the outputs three times (at each output time
    within a step, at the last time reached, and for a run with t0 = t1), and
    evaluates them one output time at a time. After the loop they are compiled
    once and vectorised; the price is memory for the states at every output time,
    so runs whose saved states would exceed :data:`STATES_AFTER_LOOP` numbers keep
    the outputs in the loop (``benchmarks/README.md``, session 35)."""
    size = sum(int(np.prod(np.shape(x))) for x in jax.tree_util.tree_leaves(y0))
    return int(np.shape(ts)[0]) * size <= STATES_AFTER_LOOP


def storable_run(scene, y0, settings, *, count: bool = False, keep_final: bool = True) -> bool:
    """Whether :func:`integrate` with these arguments compiles to a program that
    can be stored (``moorjax._cache.StoredProgram``): no host callbacks (no
    evaluation count, no progress meter) and host-checked settings."""
    del scene, y0, keep_final
    return (not count and settings.host_checked
            and isinstance(settings.meter, diffrax.NoProgressMeter))


def _solve(term, s, dt0, y0, scene, saveat):
    return diffrax.diffeqsolve(
        term,
        s.solver,
        s.t0,
        s.ts[-1],
        dt0,
        y0,
        args=scene,
        saveat=saveat,
        stepsize_controller=s.controller,
        max_steps=s.max_steps,
        throw=False,
        progress_meter=s.meter,
        adjoint=diffrax_adjoint(s, y0),
    )


def is_implicit_solver(solver) -> bool:
    return isinstance(solver, diffrax.AbstractImplicitSolver)


# -- result codes and failures ----------------------------------------------

#: diffrax's result codes by name (those of diffrax 0.7; absent ones are skipped)
_NAMES = ("successful", "max_steps_reached", "singular", "breakdown", "stagnation", "conlim",
          "nonfinite_input", "nonlinear_max_steps_reached", "nonlinear_divergence",
          "nonfinite", "dt_min_reached", "event_occurred", "max_steps_rejected",
          "internal_error")


def result_codes(result) -> np.ndarray:
    """The integer code(s) of a diffrax result (one per ensemble member)."""
    return np.atleast_1d(np.asarray(result._value))


def result_names() -> dict:
    """diffrax result codes by value → short name (e.g. ``"dt_min_reached"``)."""
    return {int(getattr(diffrax.RESULTS, n)._value): n for n in _NAMES
            if hasattr(diffrax.RESULTS, n)}


SUCCESS_CODE = int(diffrax.RESULTS.successful._value)


def first_bad_time(ts, values):
    """The first output time [s] at which some of ``values`` (k, …) is not finite
    (``None`` if all are)."""
    values = np.asarray(values)
    bad = ~np.all(np.isfinite(values.reshape(values.shape[0], -1)), axis=-1)
    return float(np.asarray(ts)[np.argmax(bad)]) if bad.any() else None


def failure_cause(res: SimulationResult, max_steps: int, fixed: bool = False):
    """``None`` if the run succeeded with finite outputs, else (time text, cause, code)."""
    # the code read on the host: ``bool(res.succeeded())`` is an XLA operation of
    # its own (about 60 µs, against 1.5 µs for the copy)
    ok = int(np.asarray(res.result._value)) == SUCCESS_CODE
    t_bad = first_bad_time(res.ts, res.tension_b)
    if ok and t_bad is None:
        return None
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
            "Newton did not converge at the fixed step dt (a snap load, slack line or "
            "seabed landing within one step?): use adaptive steps (no dt), a smaller dt, "
            "or retry_failed_steps=True"
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
    return where, cause, code
