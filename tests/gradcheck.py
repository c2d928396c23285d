"""One helper for the suite's gradient checks against central differences.

A jit of ``value_and_grad`` is one compiled program: it gives the gradient and
the values the differences need (and any further values a test wants), where
``jax.grad`` plus plain calls would compile two or three.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np


def gradient_and_central_difference(fn, x, h):
    """``(grad, fd, value)`` of a scalar ``fn`` at ``x``: the derivative along
    component ``i`` when ``h`` is a sequence (one step per component; ``grad``
    and ``fd`` are then lists), else of a scalar argument; ``value(x)`` evaluates
    ``fn`` with the same compiled program."""
    compiled = jax.jit(jax.value_and_grad(fn))

    def value_and_grad(z):  # one argument type (a float64 array), so one compilation
        return compiled(jnp.asarray(z, jnp.float64))

    def value(z):
        return float(value_and_grad(z)[0])

    g = value_and_grad(x)[1]
    if np.ndim(h) == 0:  # h a number, or a sequence of them (not an array for jnp)
        return float(g), (value(x + h) - value(x - h)) / (2 * h), value
    grads, fds = [], []
    for i, hi in enumerate(h):
        e = jnp.zeros(jnp.shape(x)).at[i].set(hi)
        grads.append(float(g[i]))
        fds.append((value(x + e) - value(x - e)) / (2 * hi))
    return grads, fds, value
