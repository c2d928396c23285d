"""Derivative-safe elementary operations.

Every norm or square root that can be evaluated at zero (a node at rest in still
water, a zero-length segment) is written so that its *derivative* is finite there
too. A NaN in a Jacobian makes every Newton step of an implicit solver fail, so
physics code uses these helpers instead of ``jnp.linalg.norm``/``jnp.sqrt``.

Also :func:`as_float`, how constructors take their numbers without an XLA op.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np


def as_float(x, shape=None):
    """``x`` as a float array (reshaped to ``shape``): a concrete value is
    converted by NumPy and placed on the device, a traced one by ``jnp``. Each eager
    ``jnp`` operation on concrete values is a small XLA program of its own,
    compiled (or loaded from the cache) once per process: tens of them in a
    scene's construction cost a new process a noticeable part of a second."""
    if isinstance(x, jax.core.Tracer):
        a = jnp.asarray(x, dtype=float)
        return a if shape is None else a.reshape(shape)
    a = np.asarray(x, dtype=float)
    # device_put, not jnp.asarray: the latter compiles a small copy program per shape
    return jax.device_put(a if shape is None else a.reshape(shape))


def safe_norm(x, axis=-1, keepdims=False):
    """Euclidean norm whose gradient is 0 (not NaN) at ``x = 0``.

    A NaN in ``x`` gives NaN (``sq·0``), never 0: a diverged state must stay
    visible to the failure checks that look for non-finite tensions."""
    sq = jnp.sum(x * x, axis=axis, keepdims=keepdims)
    positive = sq > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, sq, 1.0)), sq * 0.0)


def safe_unit(x, axis=-1):
    """``x/|x|``, 0 at ``x = 0`` with a finite derivative there (the identity); also returns ``|x|``."""
    n = safe_norm(x, axis=axis, keepdims=True)
    unit = x / jnp.where(n > 0, n, 1.0)
    return unit, jnp.squeeze(n, axis=axis)


def abs_times(v, axis=-1):
    """``|v| v`` (quadratic drag): smooth, its Jacobian ``|v|(I + v̂v̂ᵀ)`` is 0 at rest."""
    return safe_norm(v, axis=axis, keepdims=True) * v
