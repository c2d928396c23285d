"""How derivatives pass through the time integration: the adjoint policy.

:func:`diffrax_adjoint` turns a :class:`~moorjax.dynamics.settings.Settings`'
``adjoint`` and ``checkpoints`` into diffrax's adjoint;
:func:`structured_implicit_gradients` makes the implicit stages' derivatives use
the Newton's own block-tridiagonal solver. The second needs a patch of diffrax's
internals (diffrax has no option for it): it lives here alone, is written for
diffrax :data:`PATCHED_DIFFRAX` (``tests/test_gradients.py`` pins it), and fails
loudly, not silently, when diffrax changes under it.

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
import contextvars
import importlib
import threading

import diffrax
import jax
import numpy as np
import optimistix as optx

from ..linalg.banded_solver import BlockTridiagonalSolver

#: memory allowed for storing every step's solver state in reverse mode [bytes]
CHECKPOINT_BYTES = 512 * 2**20

ADJOINTS = ("checkpointed", "forward")


def check_adjoint(adjoint):
    if adjoint not in ADJOINTS:
        raise ValueError(f"unknown adjoint {adjoint!r}; choose one of {', '.join(ADJOINTS)}")


def diffrax_adjoint(settings, y0):
    """diffrax's adjoint for ``settings`` (its ``adjoint`` and ``checkpoints``) and
    the initial state ``y0`` (whose size decides whether the checkpoints fit)."""
    if settings.adjoint == "forward":
        return diffrax.ForwardMode()
    if settings.checkpoints > 0:
        # every step's loop state (y, solver and controller state) ~ a few copies of y
        state_bytes = 8 * sum(int(np.prod(x.shape)) for x in jax.tree_util.tree_leaves(y0))
        if settings.checkpoints * 8 * state_bytes <= CHECKPOINT_BYTES:
            return diffrax.RecursiveCheckpointAdjoint(checkpoints=settings.checkpoints)
    return diffrax.RecursiveCheckpointAdjoint()


def banded_jacobian(scene) -> bool:
    """Whether every line's dynamics Jacobian is block-tridiagonal (nodal mass)."""
    return all(line.banded_jacobian for line in scene.lines)


def banded(scene) -> bool:
    """Whether the structured implicit-function solves are exact for ``scene``:
    every line's Jacobian block-tridiagonal and no bodies (whose coupling to the
    lines' end nodes the band solver's body blocks leave out)."""
    return banded_jacobian(scene) and not scene.bodies


# -- the structured implicit-function solves (a patch of diffrax 0.7) --------

#: the diffrax version whose internals the patch below was written for
PATCHED_DIFFRAX = "0.7.2"
#: diffrax's modules that call ``optx.root_find`` for implicit stages (without an adjoint)
PATCHED_MODULES = ("diffrax._solver.runge_kutta", "diffrax._solver.implicit_euler")

_STRUCTURED = contextvars.ContextVar("moorjax_structured_implicit_gradients", default=False)
_INSTALL = threading.Lock()
_installed = []


class _StructuredOptimistix:
    """``optimistix`` as diffrax's implicit solvers see it. Inside
    :func:`structured_implicit_gradients` (in the tracing thread), ``root_find``
    differentiates with the root finder's own block-tridiagonal linear solver;
    elsewhere it is optimistix's own, called with the same arguments."""

    def __getattr__(self, name):
        return getattr(optx, name)

    @staticmethod
    def root_find(fn, solver, y0, args=None, options=None, *, adjoint=None, **kwargs):
        if adjoint is None and _STRUCTURED.get():
            ls = getattr(solver, "linear_solver", None)
            adjoint = (optx.ImplicitAdjoint(linear_solver=ls)
                       if isinstance(ls, BlockTridiagonalSolver) else optx.ImplicitAdjoint())
        if adjoint is None:
            return optx.root_find(fn, solver, y0, args, options, **kwargs)
        return optx.root_find(fn, solver, y0, args, options, adjoint=adjoint, **kwargs)


def _install():
    """Route diffrax's implicit stages through :class:`_StructuredOptimistix`
    (once per process; outside the context it changes nothing)."""
    with _INSTALL:
        if _installed:
            return
        proxy = _StructuredOptimistix()
        modules = [importlib.import_module(name) for name in PATCHED_MODULES]
        for m in modules:
            if getattr(m, "optx", None) is not optx:
                raise RuntimeError(
                    f"diffrax {diffrax.__version__}: {m.__name__} no longer calls optimistix as "
                    f"`optx` (moorjax's structured implicit gradients were written for diffrax "
                    f"{PATCHED_DIFFRAX}); update moorjax.dynamics.adjoint")
        for m in modules:
            m.optx = proxy
        _installed.append(proxy)


@contextlib.contextmanager
def structured_implicit_gradients(enabled: bool = True):
    """Trace diffrax's implicit solvers with structured implicit-function derivatives.

    diffrax 0.7 calls ``optimistix.root_find`` for every implicit stage without an
    ``adjoint``, so its derivative is solved by a dense LU (see the module notes).
    Within this context (which only matters while JAX *traces*, including the
    backward pass of a gradient), those calls get
    ``ImplicitAdjoint(linear_solver=<the Newton's block-tridiagonal solver>)``.
    Only for scenes whose Jacobian is block-tridiagonal (``enabled``, see
    :func:`banded`): otherwise the band solver would be inexact. The switch is a
    context variable, so other threads tracing at the same time are not affected.
    """
    if not enabled:
        yield
        return
    _install()
    token = _STRUCTURED.set(True)
    try:
        yield
    finally:
        _STRUCTURED.reset(token)
