"""TabulatedPath: its lookup (arithmetic on a uniform grid, binary search
otherwise) against SciPy's cubic Hermite spline, at drawn times, the samples
themselves and just outside the table."""

import jax
import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline

from moorjax.model.ends import TabulatedPath


def _times(kind, rng):
    if kind == "uniform":  # times written as decimals: 0.05 is not exact
        return np.round(np.arange(0.0, 12.0 + 1e-9, 0.05), 10)
    if kind == "offset":
        return 3.7 + 0.25 * np.arange(41)
    return np.cumsum(rng.uniform(0.01, 0.4, 60))  # irregular


@pytest.mark.parametrize("kind", ["uniform", "offset", "irregular"])
def test_lookup_matches_the_hermite_spline(kind):
    rng = np.random.default_rng(7)
    t = _times(kind, rng)
    r = np.stack([np.sin(1.3 * t), 0.2 * t**2, np.cos(0.7 * t)], axis=-1) + rng.normal(0, 0.01, (t.size, 3))
    v = rng.normal(0, 1.0, (t.size, 3))
    path = TabulatedPath(t, r, v)
    assert path.uniform == (kind != "irregular")
    oracle = CubicHermiteSpline(t, r, v, extrapolate=True)
    span = t[-1] - t[0]
    probes = np.concatenate([
        rng.uniform(t[0], t[-1], 300),  # drawn
        t,  # the samples themselves (an interval boundary each)
        t[1:-1] * (1 + 1e-15), t[1:-1] * (1 - 1e-15),  # a rounding either side
        [t[0] - 0.01 * span, t[-1] + 0.01 * span],  # the end cubics continue
    ])
    pos = jax.jit(jax.vmap(path.position))(probes)
    vel = jax.jit(jax.vmap(path.velocity))(probes)
    acc = jax.jit(jax.vmap(path.acceleration))(probes)
    scale = np.abs(r).max() + np.abs(v).max()
    np.testing.assert_allclose(pos, oracle(probes), atol=1e-11 * scale)
    np.testing.assert_allclose(vel, oracle(probes, 1), atol=1e-9 * scale)
    # the acceleration jumps at the samples: there the interval that starts at
    # the sample holds (as a binary search with side="right" finds it, and SciPy)
    at = np.concatenate([probes[:300 + t.size - 1], probes[-2:]])
    np.testing.assert_allclose(np.concatenate([acc[:300 + t.size - 1], acc[-2:]]), oracle(at, 2),
                               atol=1e-7 * scale)


def test_a_nearly_uniform_table_is_looked_up_exactly():
    """Times uniform only to 1e-6 of the interval still count as uniform; the
    neighbour check finds the right interval at every sample."""
    t = 0.1 * np.arange(101) + 1e-8 * np.sin(np.arange(101))
    r = np.stack([t, t**2, np.sin(t)], axis=-1)
    path = TabulatedPath(t, r)
    assert path.uniform
    oracle = CubicHermiteSpline(t, r, np.asarray(path.v))
    probes = np.concatenate([t, t[:-1] + 0.5e-8, np.linspace(t[0], t[-1], 997)])
    np.testing.assert_allclose(jax.vmap(path.position)(probes), oracle(probes), atol=1e-12)
