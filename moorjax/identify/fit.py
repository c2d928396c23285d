"""Fit free parameters of scenes to measured tension histories with an optax optimiser.

    result = fit([exp_small, exp_large], ["alpha", "beta", "Cd_normal", "Cd_axial"],
                 optimizer=optax.lbfgs(linesearch=None), steps=50)
    result.values, result.std, result.loss_history, result.grad_norm

The objective is the mean of the experiments' dimensionless misfits
(:mod:`moorjax.identify.experiment`); all experiments share the free parameters
(a lab campaign: one line, several amplitudes or periods). Each experiment's
misfit and its gradient come from one compiled reverse-mode pass
(:func:`~moorjax.identify.objective.misfit_and_gradient`), shared by all
experiments of the same structure and shapes.

The optimiser works on the unconstrained variables u of
:mod:`moorjax.identify.free`. Every step it proposes is checked before it is
taken (a safeguarded, monotone iteration): the step is halved until the loss is
finite and decreases sufficiently (Armijo, c = 1e-4); a step that cannot be made
good in ``max_backtracks`` halvings stops the fit at its last good values with
``status = "nonfinite"`` (a message naming the experiment that failed) or
``"stalled"`` (no decrease: a loss that is not smooth at that scale)
— it never returns NaN. The default optimiser is optax's L-BFGS
without its internal line search (the safeguard above is its line search, run on
the already compiled misfit, so no second compilation of the simulation is
needed); any optax ``GradientTransformation`` can be given (e.g.
``optax.adam(0.05)``).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax

from ..dynamics.integrate import first_bad_time
from ..model.parameters import PARAMETERS, get_parameter, split_name
from .covariance import gauss_newton_covariance
from .experiment import Experiment
from .free import as_free, make_transform
from .objective import contract, default_simulation, misfit_and_gradient, tangent, with_values


@dataclass
class FitResult:
    """Outcome of :func:`fit` (values in SI units).

    Attributes:
        names: free parameter names, in order.
        initial, values: start and fitted values {name: value}.
        loss_history: loss at the start and after every accepted step.
        initial_loss, final_loss: first and last entry of ``loss_history``.
        iterations: accepted optimiser steps.
        evaluations: misfit-and-gradient evaluations (all experiments count as one).
        grad_norm: |∇_u loss| at the end (u: the optimiser's unconstrained variables).
        gradient: ∂loss/∂p at the end, per SI unit of each parameter.
        covariance: Gauss–Newton (Fisher) covariance of the fitted values (p×p, SI);
            ``None`` if not computed.
        std: standard deviations {name: σ} from ``covariance``.
        experiment_losses: each experiment's misfit at the end.
        status: ``"converged"``, ``"max_steps"``, ``"nonfinite"``, ``"stalled"``.
        message: what stopped the fit, in words.
    """

    names: tuple
    initial: dict
    values: dict
    loss_history: np.ndarray
    iterations: int
    evaluations: int
    grad_norm: float
    gradient: np.ndarray
    covariance: np.ndarray | None
    std: dict | None
    experiment_losses: list
    status: str
    message: str
    settings: dict = field(default_factory=dict)

    @property
    def initial_loss(self) -> float:
        return float(self.loss_history[0])

    @property
    def final_loss(self) -> float:
        return float(self.loss_history[-1])

    @property
    def converged(self) -> bool:
        return self.status == "converged"

    def to_json(self) -> dict:
        """A JSON-ready summary (the ``moorjax fit`` output)."""
        params = {}
        for i, n in enumerate(self.names):
            base = PARAMETERS[split_name(n)[1]]
            params[n] = dict(
                initial=self.initial[n], fitted=self.values[n], unit=base.unit,
                std=None if self.std is None else self.std[n],
                gradient=float(self.gradient[i]),
            )
        return dict(
            params=params,
            initial_loss=self.initial_loss,
            final_loss=self.final_loss,
            iterations=self.iterations,
            evaluations=self.evaluations,
            grad_norm=self.grad_norm,
            status=self.status,
            message=self.message,
            loss_history=[float(x) for x in self.loss_history],
            experiment_losses=[float(x) for x in self.experiment_losses],
            covariance=None if self.covariance is None else np.asarray(self.covariance).tolist(),
            settings=self.settings,
        )


@dataclass
class _Evaluation:
    loss: float
    grad_u: np.ndarray
    grad_p: np.ndarray
    each: list
    problem: str | None


class _Objective:
    """Loss and gradient in u, evaluated experiment by experiment (compiled core)."""

    def __init__(self, experiments, transform, sims):
        self.experiments, self.transform, self.sims = experiments, transform, sims
        self.count = 0

    def __call__(self, u) -> _Evaluation:
        self.count += 1
        p = self.transform.to_physical(u)
        names = self.transform.names
        n_e = len(self.experiments)
        loss, grad_p, each, problem = 0.0, np.zeros(len(names)), [], None
        for exp, sim in zip(self.experiments, self.sims):
            scene = with_values(exp.scene, names, p)
            try:
                v, model, ok, g = misfit_and_gradient(eqx.tree_at(lambda e: e.scene, exp, scene), sim)
                v = float(v)
            except (eqx.EquinoxRuntimeError, jax.errors.JaxRuntimeError) as exc:
                # lineax refuses a singular solve while differentiating (e.g. the
                # implicit-function derivative of a static state with slack
                # segments): this point is as unusable as a failed simulation
                v, model, ok, g = np.inf, None, False, None
                first = str(exc).strip().splitlines()[0]
                problem = problem or (
                    f"experiment {exp.name!r}: the simulation or its derivative failed "
                    f"({first}) at {_fmt(names, p)}"
                )
            each.append(v)
            g_e = (np.array([contract(g, tangent(scene, n)) for n in names])
                   if np.isfinite(v) else None)
            if g_e is None or not np.all(np.isfinite(g_e)):
                if problem is None:
                    t_bad = None if model is None else first_bad_time(exp.ts, model)
                    what = ("the static equilibrium or the time integration failed"
                            if not bool(ok) else "the loss or its gradient is not finite")
                    when = f" (tensions not finite from t = {t_bad:g} s)" if t_bad is not None else ""
                    problem = f"experiment {exp.name!r}: {what}{when} at {_fmt(names, p)}"
                continue
            loss += v / n_e
            grad_p += g_e / n_e
        grad_u = grad_p * self.transform.derivative(u)
        if problem is not None:
            loss = np.inf
        return _Evaluation(loss, grad_u, grad_p, each, problem)


#: a proposed step that would lower the loss by less than this fraction of it, and
#: that no halving makes lower, means the fit has reached the loss's precision
_FLOOR = 1e-8


def _fmt(names, values):
    return ", ".join(f"{n} = {v:.6g}" for n, v in zip(names, values))


def default_optimizer():
    """optax L-BFGS without its own line search (the fit's safeguard does that)."""
    return optax.lbfgs(linesearch=None)



def _takes_grad_norm(callback) -> bool:
    """Whether a fit callback accepts the ``grad_norm`` keyword."""
    import inspect

    try:
        params = inspect.signature(callback).parameters.values()
    except (TypeError, ValueError):
        return False
    return any(p.name == "grad_norm" or p.kind is p.VAR_KEYWORD for p in params)

def fit(
    experiments,
    free,
    *,
    optimizer=None,
    steps: int = 100,
    dt: float | None = 0.01,
    solver: str = "kvaerno3",
    rtol: float = 1e-6,
    atol: float = 1e-6,
    gtol: float = 1e-10,
    ftol: float = 1e-10,
    xtol: float = 1e-8,
    max_backtracks: int = 8,
    covariance: bool = True,
    noise=None,
    callback=None,
) -> FitResult:
    """Fit free parameters to one or more experiments.

    Args:
        experiments: an :class:`Experiment` or a sequence (fitted jointly; each
            experiment's scene must contain every free parameter).
        free: names, :class:`Free` objects (start, bounds) or ``{name: start}``.
        optimizer: an optax ``GradientTransformation`` on the unconstrained
            variables (default :func:`default_optimizer`). Its proposed update is
            safeguarded (see the module notes).
        steps: maximum accepted steps.
        dt, solver, rtol, atol: simulation settings (fixed steps by default: the
            loss is then smooth and its gradient exact; see
            :mod:`moorjax.identify.response`).
        gtol: stop when |∇_u loss| ≤ gtol.
        ftol: stop when a step lowers the loss by less than ftol·loss twice in a row.
        xtol: stop when a step changes every u by less than xtol (relative).
        max_backtracks: halvings of a step before the fit gives up.
        covariance: compute the Gauss–Newton covariance at the end (forward
            mode: one compiled Jacobian per experiment structure).
        noise: measurement noise std [N] (scalar or one per experiment) for the
            covariance; default: estimated from each experiment's residuals.
        callback: called as ``callback(iteration, values_dict, loss)`` after each step,
            with ``grad_norm=`` |∇_u loss| as well where it takes that keyword.

    Raises:
        ValueError: bad free-parameter names, a parameter an experiment's scene
            lacks, bad bounds or starts.
        RuntimeError: the loss is not finite at the start values (the message names
            the experiment and what failed).
    """
    if isinstance(experiments, Experiment):
        experiments = [experiments]
    experiments = list(experiments)
    if not experiments:
        raise ValueError("give at least one experiment")
    if not all(isinstance(e, Experiment) for e in experiments):
        raise ValueError("experiments must be Experiment objects (see moorjax.identify.experiment)")
    if int(steps) < 0:
        raise ValueError(f"steps = {steps} must be >= 0")
    free = as_free(free)
    transform, u = make_transform(free, experiments[0].scene)
    for exp in experiments[1:]:
        for f in free:
            try:
                get_parameter(exp.scene, f.name)  # raises if the scene lacks the term
            except ValueError as exc:
                raise ValueError(f"experiment {exp.name!r}: {exc}") from None
    settings = dict(dt=dt, solver=solver, rtol=rtol, atol=atol)
    sims = [default_simulation(e, **settings) for e in experiments]
    objective = _Objective(experiments, transform, sims)
    names = transform.names
    p0 = transform.to_physical(u)
    initial = dict(zip(names, (float(x) for x in p0)))

    ev = objective(u)
    if ev.problem is not None or not np.isfinite(ev.loss):
        raise RuntimeError(f"the loss is not finite at the start values: {ev.problem}")

    optimizer = default_optimizer() if optimizer is None else optimizer
    optimizer = optax.with_extra_args_support(optimizer)
    update = jax.jit(optimizer.update)
    state = optimizer.init(jnp.asarray(u))
    history = [ev.loss]
    status, message = "max_steps", f"stopped after the maximum of {steps} steps"
    small_decrease = 0
    it = 0
    for it in range(1, int(steps) + 1):
        if np.linalg.norm(ev.grad_u) <= gtol:
            status, message = "converged", f"gradient norm {np.linalg.norm(ev.grad_u):.3g} <= gtol"
            it -= 1
            break
        g = jnp.asarray(ev.grad_u)
        try:
            d, new_state = update(g, state, jnp.asarray(u), value=jnp.asarray(ev.loss), grad=g)
        except TypeError as exc:
            if "value_fn" not in str(exc):
                raise
            raise ValueError(
                "the optimiser has its own line search (it needs `value_fn`); the fit "
                "already safeguards every step, so give it without one, e.g. "
                "optax.lbfgs(linesearch=None) (the default)"
            ) from None
        d = np.asarray(d)
        slope = float(np.dot(ev.grad_u, d))
        if not np.all(np.isfinite(d)):
            status = "nonfinite"
            message = f"the optimiser proposed a non-finite step at iteration {it}"
            it -= 1
            break
        if slope >= 0:  # not a descent direction: fall back to steepest descent
            d = -ev.grad_u * min(1.0, 1.0 / max(np.linalg.norm(ev.grad_u), 1e-300))
            slope = float(np.dot(ev.grad_u, d))
        alpha, accepted, last_problem = 1.0, None, None
        for _ in range(max_backtracks + 1):
            trial = objective(u + alpha * d)
            if trial.problem is None and np.isfinite(trial.loss) and \
                    trial.loss <= ev.loss + 1e-4 * alpha * slope:
                accepted = trial
                break
            last_problem = trial.problem or last_problem
            alpha *= 0.5
        if accepted is None:
            it -= 1
            if last_problem is not None:
                status = "nonfinite"
                message = (f"the loss became non-finite for every step tried from iteration {it + 1} "
                           f"({last_problem}); the fit stopped at its last good values")
                warnings.warn(message, RuntimeWarning, stacklevel=2)
            elif -slope <= _FLOOR * abs(ev.loss):
                status = "converged"
                message = (f"at the precision floor: the step proposed at iteration {it + 1} "
                           f"would lower the loss by {-slope:.2g} (< {_FLOOR:g} of it) and "
                           "no fraction of it lowers the computed loss")
            else:
                status = "stalled"
                message = (f"no fraction of the step proposed at iteration {it + 1} lowers the "
                           f"loss (predicted decrease {-slope:.3g}, {-slope / ev.loss:.2g} of it): "
                           "the loss is not smooth at this scale (e.g. seabed contact switching "
                           "on and off, steps retried after a failed Newton solve); the values "
                           "are the last, best ones"
                           )
                warnings.warn(message, RuntimeWarning, stacklevel=2)
            break
        du = alpha * d
        u = u + du
        state = new_state
        prev = ev.loss
        ev = accepted
        history.append(ev.loss)
        if callback is not None:
            values = dict(zip(names, (float(x) for x in transform.to_physical(u))))
            if _takes_grad_norm(callback):
                callback(it, values, ev.loss, grad_norm=float(np.linalg.norm(ev.grad_u)))
            else:
                callback(it, values, ev.loss)
        small_decrease = small_decrease + 1 if prev - ev.loss <= ftol * prev else 0
        if small_decrease >= 2:
            status, message = "converged", f"loss decrease below ftol = {ftol:g} (relative) twice"
            break
        if np.all(np.abs(du) <= xtol * np.maximum(1.0, np.abs(u))):
            status, message = "converged", f"step below xtol = {xtol:g}"
            break
        if ev.loss == 0.0:
            status, message = "converged", "loss is zero"
            break

    p = transform.to_physical(u)
    values = dict(zip(names, (float(x) for x in p)))
    cov = std = None
    if covariance:
        cov = gauss_newton_covariance(experiments, names, p, sims, noise=noise)
        std = {n: float(np.sqrt(max(cov[i, i], 0.0))) for i, n in enumerate(names)}
    return FitResult(
        names=names, initial=initial, values=values, loss_history=np.asarray(history),
        iterations=it, evaluations=objective.count, grad_norm=float(np.linalg.norm(ev.grad_u)),
        gradient=np.asarray(ev.grad_p), covariance=cov, std=std,
        experiment_losses=list(ev.each), status=status, message=message,
        settings=dict(settings, steps=int(steps), optimizer=_optimizer_name(optimizer)),
    )


def _optimizer_name(opt):
    return getattr(opt, "__name__", type(opt).__name__)
