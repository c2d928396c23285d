"""Derivative-safe elementary operations.

Every norm or square root that can be evaluated at zero (a node at rest in still
water, a zero-length segment) is written so that its *derivative* is finite there
too. A NaN in a Jacobian makes every Newton step of an implicit solver fail, so
physics code uses these helpers instead of ``jnp.linalg.norm``/``jnp.sqrt``.
"""

from __future__ import annotations

import jax.numpy as jnp

_TINY = 1e-300


def safe_norm(x, axis=-1, keepdims=False):
    """Euclidean norm whose gradient is 0 (not NaN) at ``x = 0``."""
    sq = jnp.sum(x * x, axis=axis, keepdims=keepdims)
    positive = sq > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, sq, 1.0)), 0.0)


def smooth_norm(x, eps, axis=-1, keepdims=False):
    """``sqrt(|x|² + eps²)``: a norm regularised at the origin (eps in x's unit)."""
    return jnp.sqrt(jnp.sum(x * x, axis=axis, keepdims=keepdims) + eps * eps)


def safe_unit(x, axis=-1):
    """``x/|x|`` with value and derivative 0 at ``x = 0``; also returns ``|x|``."""
    n = safe_norm(x, axis=axis, keepdims=True)
    unit = x / jnp.where(n > 0, n, 1.0)
    return unit, jnp.squeeze(n, axis=axis)


def abs_times(v, axis=-1):
    """``|v| v`` (quadratic drag): smooth, its Jacobian ``|v|(I + v̂v̂ᵀ)`` is 0 at rest."""
    return safe_norm(v, axis=axis, keepdims=True) * v
