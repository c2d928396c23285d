"""The differentiable forward model of an identification: end-tension histories.

``tension_histories(scene, sim)`` is a pure function of the scene's arrays: it
solves each line's statics at t0 (implicit-function gradients), integrates the
dynamics with diffrax and returns the end tensions at the output times. Every
array leaf of the scene (axial law constants, damping, drag and added-mass
coefficients, length, mass, diameter, end positions and motions, current,
seabed) is reachable by ``jax.grad``.

Adjoints (how derivatives pass through ``diffeqsolve``):

- ``"checkpointed"`` (default): diffrax's :class:`~diffrax.RecursiveCheckpointAdjoint`,
  reverse mode *through the solver's own arithmetic* (discretise-then-optimise).
  The gradient is that of the numbers the forward run produced, so it agrees with
  central differences of the same discrete solve (to 1e-5 or better: the Newton
  tolerance), whatever the number of parameters (one backward pass for all of
  them). The implicit stages' Newton solves are differentiated by the implicit
  function theorem (optimistix), not unrolled. Memory is ``checkpoints`` copies of
  the loop state: with (guarded) fixed steps the step count is bounded, so one
  checkpoint per possible step is allotted when that fits in
  :data:`CHECKPOINT_BYTES` (no recomputation: a gradient costs one forward run
  plus one backward sweep), else diffrax's O(√steps) binomial schedule, which
  recomputes steps.
- Inside each implicit step, the derivative of a stage's Newton solution comes
  from the implicit function theorem: one linear solve with the stage matrix
  I − γ·dt·J (transposed, in reverse mode). diffrax calls ``optimistix.root_find``
  without an ``adjoint``, whose default solves that system by a *dense* LU of the
  materialised Jacobian: O(n³) per stage, and 6(n−1) Jacobian-vector products
  to build it — a gradient cost 8× a forward run at N = 20 and 200× at N = 80.
  :func:`structured_implicit_gradients` makes those solves use the root finder's
  own block-tridiagonal solver (exact: the stage matrix is block-tridiagonal);
  every compiled function of :mod:`moorjax.identify` is traced under it.
- ``"forward"``: :class:`~diffrax.ForwardMode`, for ``jax.jvp``/``jax.jacfwd`` —
  the Jacobian of a whole tension history with respect to a few parameters (the
  Gauss–Newton covariance) costs one forward run per parameter instead of one
  backward pass per sample.

Why not diffrax's ``BacksolveAdjoint`` (optimise-then-discretise): it integrates
the adjoint ODE backwards in time with its own errors, so its gradient is not the
derivative of the computed loss (an optimiser's line search then stalls), and the
backward integration of a stiff line (axial waves, snap loads) needs steps as
small as an explicit method's.

Why checkpointed reverse mode with fixed steps is the default:

- *reverse mode*, because a fit needs the derivative of one scalar loss with
  respect to every free parameter: one backward pass gives them all (and the
  derivative with respect to every array of the scene, which is how
  :mod:`~moorjax.identify.objective` serves any choice of free parameters from
  one compilation); forward mode costs one pass per parameter;
- *checkpointed* (``RecursiveCheckpointAdjoint``, discretise-then-optimise),
  because its gradient is exactly that of the computed loss, so the loss values
  and the gradients an optimiser sees are consistent (see ``BacksolveAdjoint``
  above). The number of checkpoints is ``max_steps`` (2·⌈T/dt⌉ + 100: 12 100
  for 60 s at dt = 0.01 s) when ``8·|y|·max_steps`` bytes fit in
  :data:`CHECKPOINT_BYTES` (one line of up to ≈ 115 segments for 60 s at
  dt = 0.01 s), so no step is recomputed; otherwise diffrax's default,
  O(√max_steps) checkpoints with an online binomial (treeverse) schedule that
  recomputes steps;
- *fixed steps*, because with an adaptive controller the loss is not a smooth
  function of the parameters. diffrax stops gradients through the step-size
  choice (``lax.stop_gradient`` in ``PIDController``), so the adaptive-step
  gradient is the exact gradient of the solve *with its step sequence frozen* —
  but a finite difference, and a line search, also see the controller choose
  other steps. Measured on the taut polyester line of ``tests/test_gradients.py``
  (N = 8, 3 s, current, misfit to a history with other α, β, Cd), d(loss)/dCd_normal:

  ============================================  ==================  ==================
  relative difference to the AD gradient         rtol = atol = 1e-6  rtol = atol = 1e-8
  ============================================  ==================  ==================
  accepted (rejected) steps                      90 (2)              518 (27)
  AD with that step sequence frozen (StepTo)     0 (identical)       0 (identical)
  central FD, steps frozen, h/Cd = 1e-4 … 1e-6   1e-7 … 2e-6         2e-8 … 7e-7
  central FD of the adaptive loss, h/Cd = 1e-3   7e-6                1.5e-3
  … h/Cd = 1e-4, 1e-5, 1e-6                      8e-6, 1e-6, 7e-5    1.5e-3, 1.5e-2, 4e-2
  AD, fixed steps dt = 0.01 s (Newton 1e-10)     6e-5                4e-6
  ============================================  ==================  ==================

  So the adaptive-step gradient is right (it is the frozen-step gradient and
  agrees with the fixed-step one); what disagrees is the finite
  difference of the adaptive loss, by an amount that depends on h, the
  tolerance and where the controller's decisions flip (a first probe saw 15 %;
  tighter tolerances do not help: more steps, more flips). An optimiser's line
  search compares loss values and would see the same jumps. With fixed steps the
  loss is a smooth function of the parameters and its gradient matches central
  differences to < 1e-4 for every parameter (``tests/test_gradients.py``).
  ``simulation(ts, dt=None)`` still gives adaptive steps for a single gradient.

The fixed steps are *guarded*: a step whose implicit (very-chord Newton) solve
fails is retried with a quarter of the size, and the steps grow back to ``dt``
(a PID controller whose error control is switched off). Where no step fails —
the usual case — the step sequence is exactly fixed; near such an event the
loss is piecewise smooth. (Before the very-chord fix of commit 7b4edd9, which
lets Newton iterate past two iterations, plain fixed steps failed e.g. on
case A at t ≈ 4 s for dt = 0.02, 0.01 and 0.005 s; the guard got them through.)
"""

from __future__ import annotations

import contextlib
import dataclasses

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from diffrax._solver import implicit_euler as _dfx_implicit_euler
from diffrax._solver import runge_kutta as _dfx_runge_kutta

from ..dynamics.simulate import Plan, plan
from ..dynamics.solvers import StateNorm
from ..linalg.banded_solver import BlockTridiagonalSolver
from ..dynamics.vector_field import end_outputs, pack, vector_field
from ..statics.fem import solve_line_statics

#: memory allowed for storing every step's solver state in reverse mode [bytes]
CHECKPOINT_BYTES = 512 * 2**20

ADJOINTS = ("checkpointed", "forward")


class Simulation(eqx.Module):
    """Settings of the simulations of an identification (built by :func:`simulation`)."""

    plan: Plan
    checkpoints: int = eqx.field(static=True)  # reverse-mode checkpoints (0: diffrax's default)
    adjoint: str = eqx.field(static=True)

    @property
    def n_steps(self) -> int:
        """The step limit (nominal fixed-step count plus room for retried steps)."""
        return self.plan.max_steps

    def with_adjoint(self, adjoint: str) -> "Simulation":
        _check_adjoint(adjoint)
        return Simulation(self.plan, self.checkpoints, adjoint)


def _check_adjoint(adjoint):
    if adjoint not in ADJOINTS:
        raise ValueError(f"unknown adjoint {adjoint!r}; choose one of {', '.join(ADJOINTS)}")


#: a retried step is this fraction of the failed one; steps grow back by at most
#: ``1/_RETRY`` per accepted step, up to ``dt``
_RETRY = 0.25


def simulation(ts, *, dt=0.01, solver="kvaerno3", rtol=1e-6, atol=1e-6, t0=0.0,
               adjoint="checkpointed", max_steps=None) -> Simulation:
    """Settings of the simulations of an identification (scene-independent).

    Args:
        ts: output times [s] (> t0, increasing): the times of the measurements.
        dt: step [s] (default 0.01 s), or ``None`` for error-controlled adaptive
            steps (whose gradients hold the step sequence frozen, see the module
            notes). With ``dt`` the integration takes fixed steps of ``dt``; only a
            step whose implicit (Newton) solve fails — a node touching the seabed,
            a snap load, which the very-chord Newton with the Jacobian frozen at the
            step start cannot follow at that step — is retried with a quarter of
            it, and the steps then grow back to ``dt``. Where no step fails (the
            usual case) the steps are exactly fixed.
        solver: a solver name (default ``"kvaerno3"``: L-stable, cheap stages).
        rtol, atol: Newton tolerances of the implicit stages (relative, and
            absolute [m]); with ``dt=None`` also the error control. Keep ≈ 1e-6.
        t0: start time [s] (the static equilibrium is taken there).
        adjoint: ``"checkpointed"`` (reverse mode, default) or ``"forward"``.
        max_steps: step limit (default: twice the fixed-step count + 100, or 100 000).
    """
    _check_adjoint(adjoint)
    ts = np.asarray(ts, dtype=float)
    if ts.ndim != 1 or ts.size < 1:
        raise ValueError("output times ts must be a non-empty 1-D array [s]")
    span = float(ts[-1] - t0)
    if dt is None:
        max_steps = 100_000 if max_steps is None else int(max_steps)
        p = plan(ts=ts, t0=t0, solver=solver, rtol=rtol, atol=atol, max_steps=max_steps)
        return Simulation(p, 0, adjoint)
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt = {dt} s must be > 0")
    n_fixed = int(np.ceil(span / float(dt) - 1e-9))
    max_steps = 2 * n_fixed + 100 if max_steps is None else int(max_steps)
    # the fixed-step plan: validated settings, Newton with explicit tolerances
    p = plan(ts=ts, t0=t0, solver=solver, rtol=rtol, atol=atol, dt=dt, max_steps=max_steps)
    norm = StateNorm(jnp.asarray(0.01))  # as plan's: velocities on a 100x looser scale
    guard = diffrax.PIDController(
        rtol=1.0, atol=1e9, norm=norm,  # error control off: only failed steps are retried
        dtmax=float(dt), dtmin=float(dt) * _RETRY**6, force_dtmin=False,
        factormin=_RETRY, factormax=1.0 / _RETRY,
    )
    p = dataclasses.replace(p, controller=guard)
    return Simulation(p, max_steps, adjoint)


class _StructuredOptimistix:
    """``optimistix`` as diffrax's implicit solvers see it, except that ``root_find``
    differentiates with the root finder's own block-tridiagonal linear solver."""

    def __getattr__(self, name):
        return getattr(optx, name)

    @staticmethod
    def root_find(fn, solver, y0, args=None, options=None, *, adjoint=None, **kwargs):
        if adjoint is None:
            ls = getattr(solver, "linear_solver", None)
            adjoint = (optx.ImplicitAdjoint(linear_solver=ls)
                       if isinstance(ls, BlockTridiagonalSolver) else optx.ImplicitAdjoint())
        return optx.root_find(fn, solver, y0, args, options, adjoint=adjoint, **kwargs)


def banded(scene) -> bool:
    """Whether every line's dynamics Jacobian is block-tridiagonal (nodal mass)."""
    return all(line.banded_jacobian for line in scene.lines)


@contextlib.contextmanager
def structured_implicit_gradients(enabled: bool = True):
    """Trace diffrax's implicit solvers with structured implicit-function derivatives.

    diffrax 0.7 calls ``optimistix.root_find`` for every implicit stage without an
    ``adjoint``, so its derivative is solved by a dense LU (see the module notes).
    Within this context (which only matters while JAX *traces*), those calls get
    ``ImplicitAdjoint(linear_solver=<the Newton's block-tridiagonal solver>)``.
    Only for scenes whose Jacobian is block-tridiagonal (``enabled``): with a
    consistent mass the band solver would be inexact. Not thread-safe.
    """
    if not enabled:
        yield
        return
    modules = (_dfx_runge_kutta, _dfx_implicit_euler)
    saved = [m.optx for m in modules]
    for m in modules:
        m.optx = _STRUCTURED
    try:
        yield
    finally:
        for m, old in zip(modules, saved):
            m.optx = old


_STRUCTURED = _StructuredOptimistix()


def _diffrax_adjoint(sim: Simulation, y0):
    if sim.adjoint == "forward":
        return diffrax.ForwardMode()
    if sim.checkpoints > 0:
        # every step's loop state (y, solver and controller state) ~ a few copies of y
        state_bytes = 8 * sum(int(np.prod(x.shape)) for x in jax.tree_util.tree_leaves(y0))
        if sim.checkpoints * 8 * state_bytes <= CHECKPOINT_BYTES:
            return diffrax.RecursiveCheckpointAdjoint(checkpoints=sim.checkpoints)
    return diffrax.RecursiveCheckpointAdjoint()


def initial_states(scene, t0=0.0):
    """Static equilibrium of every line at t0 (differentiable), and whether all converged."""
    sts = [solve_line_statics(line, scene.env, t0, throw=False) for line in scene.lines]
    ok = jnp.all(jnp.stack([st.converged for st in sts]))
    return tuple(st.state() for st in sts), ok


class Histories(eqx.Module):
    """End tensions (k, n_lines) [N] at the output times and a success flag."""

    tension_a: jax.Array
    tension_b: jax.Array
    ok: jax.Array


def tension_histories(scene, sim: Simulation) -> Histories:
    """Simulate ``scene`` from its static equilibrium at ``sim``'s t0; pure and differentiable.

    Never raises on a failed solve: ``ok`` is False and the tensions after the
    failure are not finite (diffrax fills them with inf).
    """
    p = sim.plan
    init, statics_ok = initial_states(scene, p.t0)
    y0 = pack(init)
    saveat = diffrax.SaveAt(ts=p.ts, fn=lambda t, y, args: end_outputs(t, y, args))
    dt0 = None if isinstance(p.controller, diffrax.StepTo) else p.dt0
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(vector_field), p.solver, p.t0, p.ts[-1], dt0, y0,
        args=scene, saveat=saveat, stepsize_controller=p.controller,
        max_steps=p.max_steps, throw=False, adjoint=_diffrax_adjoint(sim, y0),
    )
    out = sol.ys
    ok = statics_ok & (sol.result == diffrax.RESULTS.successful)
    return Histories(out["tension_a"], out["tension_b"], ok)
