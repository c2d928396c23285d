"""Gauss–Newton (Fisher) approximation of the covariance of fitted parameters.

Model of the measurements: T̂_i = T_i(θ) + ε_i with independent Gaussian errors
of variance σ_e²/w_i in experiment e. Linearising T about the fit θ̂ gives the
Fisher information

    F = Σ_e (1/σ_e²) Σ_i w_i ∇T_i ∇T_iᵀ,          Cov(θ̂) ≈ F⁻¹,

the Gauss–Newton approximation of the inverse Hessian of the log-likelihood
(exact for a model linear in θ). σ_e is given (``noise``, in N) or estimated from
the experiment's weighted residuals with p·n_e/n degrees of freedom removed. The
Jacobian ∇T (samples × parameters) comes from forward-mode differentiation
(:class:`diffrax.ForwardMode`): one forward run with p tangents, instead of one
reverse pass per sample.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .objective import tangent, tensions_and_jacobian, with_values


def jacobian(exp, names, values, sim):
    """Model tensions (k, m) [N], ok, and their Jacobian (k, m, p) [N per SI unit]."""
    scene = with_values(exp.scene, names, values)
    tans = [tangent(scene, n) for n in names]
    stacked = jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *tans)
    exp_v = eqx.tree_at(lambda e: e.scene, exp, scene)
    m, ok, jac = tensions_and_jacobian(exp_v, sim.with_adjoint("forward"), stacked)
    return np.asarray(m), bool(ok), np.moveaxis(np.asarray(jac), 0, -1)


def gauss_newton_covariance(experiments, names, values, sims, noise=None):
    """Covariance (p×p, SI units) of the fitted ``values`` of ``names``.

    Args:
        experiments, sims: the experiments of the fit and their simulation settings.
        noise: measurement noise std [N], scalar or one per experiment; default:
            estimated from the residuals (then a noise-free fit gives ~0).

    Returns NaN entries when the Fisher matrix is singular (a parameter the data
    do not determine) or a simulation fails.
    """
    p = len(names)
    n_total = sum(int(np.count_nonzero(np.asarray(e.sqrt_weight))) for e in experiments)
    if noise is not None:
        noise = np.broadcast_to(np.asarray(noise, dtype=float), (len(experiments),))
    fisher = np.zeros((p, p))
    for k, (exp, sim) in enumerate(zip(experiments, sims)):
        m, ok, jac = jacobian(exp, names, values, sim)
        if not ok or not np.all(np.isfinite(jac)):
            return np.full((p, p), np.nan)
        # weights w_i up to a constant: sqrt_weight² = w/(s²Σw)
        w = np.asarray(exp.sqrt_weight) ** 2
        w = w / np.max(w)
        inside = w > 0
        resid = m - np.asarray(exp.data)
        n_e = int(np.count_nonzero(inside))
        if noise is None:
            dof = max(n_e - p * n_e / n_total, 1.0)
            var = float(np.sum(w * resid**2) / dof)
        else:
            var = float(noise[k]) ** 2
        jw = (jac * np.sqrt(w)[..., None]).reshape(-1, p)
        if var == 0.0:
            return np.zeros((p, p))
        fisher += jw.T @ jw / var
    try:
        cov = np.linalg.inv(fisher)
    except np.linalg.LinAlgError:
        return np.full((p, p), np.nan)
    return 0.5 * (cov + cov.T)
