"""Construction-time validation (the first of moorjax's three error tiers).

Checks run only on concrete values: under ``jit``/``vmap``/``grad`` the values are
tracers and the check is skipped (runtime values are guarded with
``eqx.error_if`` where it matters instead).
"""

from __future__ import annotations

import numpy as np
import jax


def _concrete(value):
    if isinstance(value, jax.core.Tracer):
        return None
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None


def check_finite(value, name: str, unit: str):
    v = _concrete(value)
    if v is not None and not np.all(np.isfinite(v)):
        raise ValueError(f"{name} = {value} {unit} is not finite; expected a finite number")


def check_positive(value, name: str, unit: str):
    check_finite(value, name, unit)
    v = _concrete(value)
    if v is not None and not np.all(v > 0):
        raise ValueError(f"{name} = {value} {unit} must be > 0")


def check_nonnegative(value, name: str, unit: str):
    check_finite(value, name, unit)
    v = _concrete(value)
    if v is not None and not np.all(v >= 0):
        raise ValueError(f"{name} = {value} {unit} must be >= 0")
