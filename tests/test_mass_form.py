"""W in mass form (moorjax.linalg.mass_form): its stage matrix solved through the
3×3 velocity system equals a dense solve of I − c·W, on lines stacked along the
row axis."""

import jax.numpy as jnp
import numpy as np
import pytest

from moorjax.linalg.mass_form import MassFormW


def _dense(lower, diag, upper):
    n, b = diag.shape[0], diag.shape[-1]
    a = np.zeros((n * b, n * b))
    for i in range(n):
        a[i * b:(i + 1) * b, i * b:(i + 1) * b] = diag[i]
        if i > 0:
            a[i * b:(i + 1) * b, (i - 1) * b:i * b] = lower[i]
        if i < n - 1:
            a[i * b:(i + 1) * b, (i + 1) * b:(i + 2) * b] = upper[i]
    return a


def _drawn_w(rng, rows_per_line):
    """Two or more lines' W stacked: SPD masses, symmetric restoring stiffness
    and damping between neighbours (as a line in tension has), zero couplings
    across line boundaries."""
    n = sum(rows_per_line)
    mass = np.empty((n, 3, 3))
    for i in range(n):
        a = rng.normal(size=(3, 3))
        mass[i] = 50.0 * np.eye(3) + a @ a.T
    def band(scale):
        seg = rng.normal(size=(n + 1, 3, 3)) * scale
        seg = -(seg @ np.swapaxes(seg, -1, -2))  # negative semi-definite per segment
        # free node i sits between segments i and i + 1
        lower, upper, diag = -seg[:-1].copy(), -seg[1:].copy(), seg[:-1] + seg[1:]
        lower[0] = 0.0
        upper[-1] = 0.0
        start = np.cumsum([0] + list(rows_per_line))[:-1]
        for s in start[1:]:  # lines do not couple
            lower[s] = 0.0
            upper[s - 1] = 0.0
        return lower, diag, upper
    k_r, k_v = band(30.0), band(3.0)
    return MassFormW(mass=jnp.asarray(mass), mass_inv=jnp.asarray(np.linalg.inv(mass)),
                     k_r=tuple(map(jnp.asarray, k_r)), k_v=tuple(map(jnp.asarray, k_v)))


@pytest.mark.parametrize("rows_per_line", [(1,), (5,), (7, 1, 4)])
@pytest.mark.parametrize("c", [1e-3, 0.05, 2.0])
def test_stage_solve_and_product_against_dense(rows_per_line, c):
    rng = np.random.default_rng(sum(rows_per_line) + int(c * 1000))
    w = _drawn_w(rng, rows_per_line)
    dense_w = _dense(*[np.asarray(x) for x in w.bands()])
    n = sum(rows_per_line)
    x = rng.normal(size=(n, 6))
    np.testing.assert_allclose(np.asarray(w.matvec(jnp.asarray(x))).ravel(), dense_w @ x.ravel(),
                               rtol=1e-12, atol=1e-12 * np.abs(dense_w).max())
    b = rng.normal(size=(n, 6))
    got = np.asarray(w.factor(c).solve(jnp.asarray(b))).ravel()
    want = np.linalg.solve(np.eye(6 * n) - c * dense_w, b.ravel())
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-11 * np.abs(want).max())


def test_bands_have_the_second_order_layout():
    """Position rows of W are [0, I]; velocity rows M⁻¹[K_r, K_v]."""
    w = _drawn_w(np.random.default_rng(3), (4,))
    lower, diag, upper = (np.asarray(x) for x in w.bands())
    np.testing.assert_array_equal(diag[:, :3, :3], 0.0)
    np.testing.assert_array_equal(diag[:, :3, 3:], np.broadcast_to(np.eye(3), (4, 3, 3)))
    np.testing.assert_array_equal(lower[:, :3], 0.0)
    np.testing.assert_array_equal(upper[:, :3], 0.0)
    m_inv = np.linalg.inv(np.asarray(w.mass))
    np.testing.assert_allclose(diag[:, 3:, :3], m_inv @ np.asarray(w.k_r[1]), rtol=1e-12)
    np.testing.assert_allclose(upper[:, 3:, 3:], m_inv @ np.asarray(w.k_v[2]), rtol=1e-12, atol=1e-15)
