"""Newton (chord) iterations of the implicit Runge–Kutta stages.

diffrax's Kvaerno methods are FSAL, so each implicit stage is solved in
*f-space*: the unknown is the stage derivative f_i = [ṙ, v̇] = [v, a]
([m/s, m/s²]), with the stage state y_i = ŷ_i + γ·h·f_i (ŷ_i: the explicit
part, γ: the tableau's diagonal, h: the step). diffrax's ``VeryChord`` measures
its iterates' change against ``atol + rtol·|f_i|`` — tolerances meant for the
state [m, m/s] applied to [m/s, m/s²], i.e. about 1/(γ·h) (≈ 400× at
h = 10 ms) tighter than the step-size controller asks of the state itself.
:class:`StageChord` measures the change of the stage *state*, γ·h·Δf_i, against
``atol + rtol·|y_i|`` in the controller's norm (Hairer & Wanner, Solving ODEs II,
IV.8: the Newton error is compared with the error tolerance of the state).
"""

from __future__ import annotations

import diffrax
import equinox as eqx
import equinox.internal as eqxi
import jax
import jax.numpy as jnp
import lineax as lx
import optimistix as optx
from equinox.internal import ω
from jax import lax
from diffrax._root_finder._verychord import _VeryChordState


class VeryChord(diffrax.VeryChord):
    """diffrax's very-chord Newton, allowed to iterate past its second iteration.

    With diffrax 0.7.2 and optimistix 0.1.0, ``VeryChord.terminate`` returns a
    "diverged" result code on every iteration after the second that has not yet
    converged, and optimistix stops its loop on any unsuccessful code. Newton
    thus got at most two iterations per stage, and every stage that needed a
    third was rejected and its step halved (upstream: optimistix#221, fixed by
    optimistix#230 / diffrax#754, not released yet). Here the failure code is
    reported only when the iteration really stops (divergence, linear-solve
    failure); otherwise Newton continues up to the solver's iteration limit.
    Measured: 40–55 % fewer steps and 1.4–1.8× less run time on the reference
    cases, same errors.
    """

    def terminate(self, fn, y, args, options, state, tags):
        stop, result = super().terminate(fn, y, args, options, state, tags)
        return stop, optx.RESULTS.where(stop, result, optx.RESULTS.successful)


def stage_arguments(args):
    """(ŷ_i, γ·h) from the arguments diffrax passes to an f-space stage solve,
    or None for any other layout (then the iteration falls back to f-space
    tolerances). diffrax 0.7 passes ``(stage_index, diagonal, vf, prod, t_i,
    ŷ_i, args, control)``; ``tests/test_speed_newton.py`` pins that layout."""
    if not (isinstance(args, tuple) and len(args) == 8):
        return None
    _, diagonal, _, _, _, y_partial, _, control = args
    return y_partial, diagonal * control


class StageChord(VeryChord):
    """:class:`VeryChord` whose convergence test measures the stage state.

    The iterate's change Δf_i is converted to the change of the stage state,
    γ·h·Δf_i, and compared with ``atol + rtol·|y_i|`` (y_i the new stage
    state) in ``norm`` — the scale the step-size controller measures the state
    on (:class:`~moorjax.dynamics.solvers.StateNorm`). Newton then stops once
    its remaining error is a fraction ``kappa`` of what the controller
    tolerates, instead of iterating (or failing) to a 1/(γ·h)-times tighter
    goal.

    With ``refresh_rate`` (e.g. 0.5; default None: never), an iteration that contracts slowly (rate
    ‖Δ_k‖/‖Δ_{k−1}‖ above it) rebuilds the iteration matrix I − γh·J at the
    current iterate: the matrix built at the start of the step can miss a force
    that switched on within it (a node landing on the seabed, a slack segment
    going taut). The rebuilt matrix serves the rest of that stage. Under
    ``vmap`` (ensembles) all members rebuild when any one contracts slowly (a
    fresh matrix never hurts a member). Measured: single runs of case A get
    cheaper (CPU 19.4 → 16.5 ms per simulated s), but a 10-member ensemble of
    case A cost 3.5× more per member than without it, so it is not the default.
    """

    refresh_rate: float | None = eqx.field(static=True, default=None)

    def init(self, fn, y, args, options, f_struct, aux_struct, tags):
        if "init_state" in options or stage_arguments(args) is None:
            return super().init(fn, y, args, options, f_struct, aux_struct, tags)
        if isinstance(self.linear_solver, StageFactorSolver):
            # the lines' own factors instead of a linearised operator for the
            # solver to materialise
            linear = self.linear_solver.stage_init(y, args)
        else:
            # diffrax's Jacobian of the explicit first stage (zero diagonal) is
            # the identity: factor that, without differentiating the vector field
            relation = _identity_relation if explicit_start(fn) else _NoAux(fn)
            operator = lx.linearise(lx.JacobianLinearOperator(relation, y, args, tags=tags))
            linear = self.linear_solver.init(operator, options={})
        dtype = jnp.result_type(*jax.tree_util.tree_leaves(y))
        # one layout for both of diffrax's calls (they meet in a ``lax.cond``): the
        # solvers here work from their factors alone, the operator is a placeholder
        return _VeryChordState(
            linear_state=(lx.FunctionLinearOperator(_identity, jax.eval_shape(lambda: y)),
                          lax.stop_gradient(linear)),
            diff=jax.tree_util.tree_map(lambda a: jnp.full(a.shape, jnp.inf, a.dtype), y),
            diffsize=jnp.array(jnp.inf, dtype=dtype),
            diffsize_prev=jnp.array(1.0, dtype=dtype),
            result=optx.RESULTS.successful,
            step=jnp.array(0),
        )

    def step(self, fn, y, args, options, state, tags):
        stage = stage_arguments(args)
        if stage is None:
            return super().step(fn, y, args, options, state, tags)
        del options, tags
        y_partial, gamma_h = stage
        fx, aux = fn(y, args)
        jac, linear_state = state.linear_state
        linear_state = lax.stop_gradient(linear_state)
        sol = lx.linear_solve(jac, fx, self.linear_solver, state=linear_state, throw=False)
        diff = sol.value
        new_y = (y**ω - diff**ω).ω
        with jax.numpy_dtype_promotion("standard"):
            y_stage = (y_partial**ω + gamma_h * new_y**ω).ω
            scale = (self.atol + self.rtol * ω(y_stage).call(jnp.abs)).ω
            diffsize = self.norm((gamma_h * diff**ω / scale**ω).ω)
        if self.refresh_rate is not None:
            slow = (state.step >= 1) & (diffsize > self.refresh_rate * state.diffsize)

            def rebuild(_):
                if isinstance(self.linear_solver, StageFactorSolver):
                    return lax.stop_gradient(self.linear_solver.stage_init(new_y, args))
                op = lx.linearise(lx.JacobianLinearOperator(_NoAux(fn), new_y, args))
                return lax.stop_gradient(self.linear_solver.init(op, options={}))

            linear_state = lax.cond(eqxi.unvmap_any(slow), rebuild, lambda _: linear_state, None)
        new_state = type(state)(
            linear_state=(jac, linear_state),
            diff=diff,
            diffsize=diffsize,
            diffsize_prev=state.diffsize,
            result=optx.RESULTS.promote(sol.result),
            step=state.step + 1,
        )
        return new_y, new_state, aux


def explicit_start(fn) -> bool:
    """Whether diffrax asks for the iteration matrix it builds before its stage
    loop (``fn`` the stage relation of that call, a lambda of
    ``AbstractRungeKutta.step``; the one inside the loop is a lambda of its
    ``eval_f_jac``): for the ESDIRK methods (Kvaerno) the Jacobian of the
    explicit first stage, whose diagonal is zero, so the matrix is the identity.
    It serves only the first stage of a first step (or after a jump); diffrax
    builds the step's own matrix in its second stage. Formed from the relation
    itself, it cost a Jacobian of the vector field in every step, and a copy of
    that Jacobian in the compiled program (``benchmarks/README.md``, session
    35). ``tests/test_speed_newton.py`` pins diffrax's two calls."""
    return getattr(fn, "__qualname__", "") == "AbstractRungeKutta.step.<locals>.<lambda>"


def linearisation_evaluations(solver) -> int:
    """Vector-field evaluations per step of an implicit diffrax ``solver`` that
    are not Newton iterations (what ``simulate(count_newton=True)`` subtracts):
    the linearisation point of the step's iteration matrix (one); none where the
    lines factor their own stage matrix (:class:`StageFactorSolver`, from the
    elements' forces); diffrax's own chord also differentiates the relation of
    the explicit first stage (two; see :func:`explicit_start`)."""
    finder = getattr(solver, "root_finder", None)
    if isinstance(finder, StageChord):
        return 0 if isinstance(finder.linear_solver, StageFactorSolver) else 1
    return 2


def _identity_relation(y, args):
    del args
    return y


class _NoAux(eqx.Module):
    fn: object

    def __call__(self, y, args):
        return self.fn(y, args)[0]


def _identity(v):
    return v


class StageFactorSolver(lx.AbstractLinearSolver):
    """Newton's linear solve for lines whose elements factor their own stage
    matrix (:meth:`~moorjax.element.base.AbstractElement.stage_factor`: the
    Hermite element's mass form, :mod:`~moorjax.element.hermite_stage`).

    Its factors are built by :meth:`stage_init` from the stage's arguments (the
    scene, the time, the stage state and γ·h), which :class:`StageChord` passes
    it in place of a linearised operator: the vector field's dense Jacobian is
    never formed. Only for diffrax's f-space stages (``stage_arguments``)."""

    def stage_init(self, f_stage, args):
        """The per-line factors at the stage iterate ``f_stage`` (the stage
        derivative, diffrax's f-space unknown) of the stage ``args``."""
        from .vector_field import stage_factors

        stage = stage_arguments(args)
        if stage is None:
            raise ValueError("StageFactorSolver needs diffrax's f-space stage arguments")
        y_partial, gamma_h = stage
        t, scene = args[4], args[6]
        y = (y_partial**ω + gamma_h * f_stage**ω).ω
        return stage_factors(t, y, scene, gamma_h)

    def init(self, operator, options):
        raise NotImplementedError(
            "StageFactorSolver factors the stage matrix from the stage's arguments "
            "(StageChord.init), not from an operator")

    def compute(self, state, vector, options):
        del options
        value = tuple(f.solve(v) for f, v in zip(state, vector))
        return value, lx.RESULTS.successful, {}

    def transpose(self, state, options):
        raise NotImplementedError("StageFactorSolver is not transposed (Newton iterations "
                                  "are not differentiated)")

    def conj(self, state, options):
        return state, options

    def assume_full_rank(self):
        return True

    def allow_dependent_columns(self, operator):
        return False

    def allow_dependent_rows(self, operator):
        return False
