"""The misfit of an experiment, its gradient and its Jacobian (compiled once per structure).

Both compiled functions take the *whole scene* as their differentiable input and
know nothing of which parameters are free: the gradient comes back as a
scene-shaped pytree (the derivative with respect to every array of the scene, in
one reverse pass), and a named parameter's derivative is its inner product with a
*tangent scene* that is 1 on the leaves the name sets (:func:`tangent`). So any
choice of free parameters — and the finite-difference checks of the tests —
reuses one compiled function per scene structure and simulation settings.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..model.parameters import set_parameter
from .experiment import Experiment
from ..dynamics.adjoint import banded, structured_implicit_gradients
from .response import Simulation, simulation, tension_histories


def _select(h, channels):
    cols = [(h.tension_a if end == "a" else h.tension_b)[:, i] for i, end in channels]
    return jnp.stack(cols, axis=-1)


def model_tensions(scene, exp: Experiment, sim: Simulation):
    """Simulated tensions (k, m) [N] of the experiment's channels, and the success flag."""
    h = tension_histories(scene, sim)
    return _select(h, exp.channels), h.ok


def _misfit(scene, data, sqrt_weight, channels, sim):
    h = tension_histories(scene, sim)
    model = _select(h, channels)
    finite = jnp.isfinite(model)
    # non-finite outputs (a failed solve) give an infinite misfit but zero
    # cotangents, so the backward pass stays finite
    r = jnp.where(finite, model - data, 0.0) * sqrt_weight
    value = jnp.where(h.ok & jnp.all(finite), jnp.sum(r * r), jnp.inf)
    return value, (model, h.ok)


# The compiled cores take the experiment's arrays, not the Experiment (whose name
# is static): experiments that differ only in values share one compilation.
@eqx.filter_jit
def _misfit_and_gradient(scene, data, sqrt_weight, channels, sim):
    diff, static = eqx.partition(scene, eqx.is_inexact_array)

    def f(d):
        return _misfit(eqx.combine(d, static), data, sqrt_weight, channels, sim)

    (value, (model, ok)), grad = jax.value_and_grad(f, has_aux=True)(diff)
    return value, model, ok, grad


def misfit_and_gradient(exp: Experiment, sim: Simulation):
    """(misfit J_e, model tensions (k, m), ok, dJ_e/dscene) — reverse mode, all scene arrays.

    ``dJ_e/dscene`` has the structure of the scene's inexact arrays (``None``
    elsewhere); a failed simulation gives ``J_e = inf`` and a finite gradient.
    """
    with structured_implicit_gradients(banded(exp.scene)):
        return _misfit_and_gradient(exp.scene, exp.data, exp.sqrt_weight, exp.channels, sim)


@eqx.filter_jit
def _tensions_and_jacobian(scene, channels, sim, tangents):
    diff, static = eqx.partition(scene, eqx.is_inexact_array)

    def model(d):
        h = tension_histories(eqx.combine(d, static), sim)
        return _select(h, channels), h.ok

    def one(t):
        (m, ok), (dm, _) = jax.jvp(model, (diff,), (t,))
        return m, ok, dm

    # the primal does not depend on the tangent: vmap computes it once
    m, ok, jac = jax.vmap(one)(tangents)
    return m[0], ok[0], jac


def tensions_and_jacobian(exp: Experiment, sim: Simulation, tangents):
    """Model tensions (k, m), ok and their derivatives (p, k, m) along p stacked
    tangent scenes (forward mode; give ``sim.with_adjoint("forward")``)."""
    with structured_implicit_gradients(banded(exp.scene)):
        return _tensions_and_jacobian(exp.scene, exp.channels, sim, tangents)


def tangent(scene, name: str):
    """Scene-shaped pytree of the inexact arrays: 1 where parameter ``name`` is set, else 0."""
    diff, static = eqx.partition(scene, eqx.is_inexact_array)
    zero = jax.tree_util.tree_map(jnp.zeros_like, diff)
    marked = set_parameter(eqx.combine(zero, static), name, 1.0)
    return eqx.partition(marked, eqx.is_inexact_array)[0]


def contract(grad, tang) -> float:
    """Inner product of two scene-shaped pytrees (None leaves skipped)."""
    leaves_g = jax.tree_util.tree_leaves(grad)
    leaves_t = jax.tree_util.tree_leaves(tang)
    return float(sum(jnp.sum(g * t) for g, t in zip(leaves_g, leaves_t)))


def with_values(scene, names, values):
    """A copy of ``scene`` with the named parameters set (checked, concrete values)."""
    for n, v in zip(names, values):
        scene = set_parameter(scene, n, float(v))
    return scene


def default_simulation(exp: Experiment, **settings) -> Simulation:
    """Fixed-step settings for an experiment's measurement times (see :func:`simulation`)."""
    return simulation(np.asarray(exp.ts), **settings)


def loss_and_gradient(experiments, names, values, **settings):
    """Joint misfit (mean of the experiments' J_e) and its gradient [per SI unit of each parameter].

    ``settings`` go to :func:`~moorjax.identify.response.simulation` (``dt``,
    ``solver``, ``rtol``, ``atol``). Returns ``(loss, gradient (p,), per-experiment
    misfits)``; a failed simulation gives ``inf`` and a zero gradient for it.
    """
    if isinstance(experiments, Experiment):
        experiments = [experiments]
    total, grad, each = 0.0, np.zeros(len(names)), []
    for exp in experiments:
        scene = with_values(exp.scene, names, values)
        exp_v = eqx.tree_at(lambda e: e.scene, exp, scene)
        try:
            v, _, _, g = misfit_and_gradient(exp_v, default_simulation(exp, **settings))
            v = float(v)
        except (eqx.EquinoxRuntimeError, jax.errors.JaxRuntimeError):
            v = np.inf  # a singular linear solve while differentiating (see fit.py)
        each.append(v)
        total += v / len(experiments)
        if np.isfinite(v):
            grad += np.array([contract(g, tangent(scene, n)) for n in names]) / len(experiments)
    return total, grad, each
