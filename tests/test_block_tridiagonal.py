"""The block-tridiagonal kernels: small products written out term by term, the
factorisation and the solve against dense linear algebra."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from moorjax.linalg import block_tridiagonal as btd


@pytest.mark.parametrize("width", [1, 3, 6, btd.UNROLLED_WIDTH + 2])
def test_small_products_equal_einsum(width):
    rng = np.random.default_rng(width)
    a = rng.normal(size=(2, 5, width, width))
    b = rng.normal(size=(2, 5, width, width))
    x = rng.normal(size=(2, 5, width))
    np.testing.assert_allclose(btd.bmv(a, x), np.einsum("mnij,mnj->mni", a, x), rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(btd.bmm(a, b), a @ b, rtol=1e-13, atol=1e-13)
    # under vmap and differentiated, as the ensembles and the gradients use them
    np.testing.assert_allclose(jax.vmap(btd.bmv)(a, x), np.einsum("mnij,mnj->mni", a, x), rtol=1e-13, atol=1e-13)
    g = jax.grad(lambda m: jnp.sum(btd.bmv(m, x) ** 2))(a)
    g_ref = jax.grad(lambda m: jnp.sum(jnp.einsum("mnij,mnj->mni", m, x) ** 2))(a)
    np.testing.assert_allclose(g, g_ref, rtol=1e-12, atol=1e-12)


def _dense(lower, diag, upper):
    n, b = diag.shape[:2]
    m = np.zeros((n * b, n * b))
    for i in range(n):
        m[i * b:(i + 1) * b, i * b:(i + 1) * b] = diag[i]
        if i:
            m[i * b:(i + 1) * b, (i - 1) * b:i * b] = lower[i]
            m[(i - 1) * b:i * b, i * b:(i + 1) * b] = upper[i - 1]
    return m


@pytest.mark.parametrize("factor", [btd.factor, btd.factor3])
def test_factor_and_solve_match_a_dense_solve(factor):
    rng = np.random.default_rng(0)
    n, b = 9, 3
    lower, upper = rng.normal(size=(n, b, b)), rng.normal(size=(n, b, b))
    diag = rng.normal(size=(n, b, b)) + 8.0 * np.eye(b)  # diagonally dominant: no pivoting needed
    rhs = rng.normal(size=(n, b))
    x = btd.solve(factor(lower, diag, upper), rhs)
    x_ref = np.linalg.solve(_dense(lower, diag, upper), rhs.reshape(-1)).reshape(n, b)
    np.testing.assert_allclose(x, x_ref, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(btd.matvec(lower, diag, upper, x_ref), rhs, rtol=1e-11, atol=1e-11)
