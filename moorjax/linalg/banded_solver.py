"""A lineax solver for Jacobians of line states: coloured JVPs + block Thomas.

The Jacobian of a line's equations couples each node only to its neighbours, so
it is block-tridiagonal with one b×b block per node pair (b = dofs per node: 3 in
statics, 6 = position + velocity in dynamics). Nodes k, k+3, k+6, … never share a
row, so **3·b Jacobian-vector products recover the whole band whatever the number
of nodes** (a graph colouring of the band); the band is then factored by the block
Thomas algorithm in O(n·b³) and each Newton iteration solves in O(n·b²).

Operator layout: the operator's input (and output) pytree must have leaves of
shape (n_i, b) with one common b. Leaves are stacked along the node axis in leaf
order; consecutive leaves (e.g. several lines of a system) do not couple, which
the band then simply contains as zero blocks.

If the true Jacobian is *not* block-tridiagonal (e.g. the consistent mass matrix
makes M⁻¹K dense), the colouring aliases far couplings into the band and the
solve becomes an approximate (chord) Newton step; the residual check of the
nonlinear solver still decides convergence.
"""

from __future__ import annotations

from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.tree_util as jtu
import lineax as lx
from jaxtyping import Array

from . import block_tridiagonal as btd


class _State(eqx.Module):
    lower: Array
    diag: Array
    upper: Array
    lu: btd.BlockTridiagonalLU
    treedef: Any = eqx.field(static=True)
    sizes: tuple = eqx.field(static=True)


def _flatten(tree, sizes):
    leaves = jtu.tree_leaves(tree)
    return jnp.concatenate([jnp.reshape(x, (n, -1)) for x, n in zip(leaves, sizes)], axis=0)


def _unflatten(flat, treedef, sizes):
    bounds = [0]
    for n in sizes:
        bounds.append(bounds[-1] + n)
    parts = [flat[a:b] for a, b in zip(bounds[:-1], bounds[1:])]
    return jtu.tree_unflatten(treedef, parts)


def band_of(fn_mv, in_structure):
    """The block-tridiagonal band (lower, diag, upper), each (N, b, b), of a linear map.

    ``fn_mv`` is a linear function of a pytree matching ``in_structure`` (leaves
    (n_i, b)); it is evaluated on 3·b coloured seed vectors (vmapped).
    """
    leaves, treedef = jtu.tree_flatten(in_structure)
    sizes = tuple(int(x.shape[0]) for x in leaves)
    widths = {int(x.shape[1]) for x in leaves}
    if len(widths) != 1 or any(len(x.shape) != 2 for x in leaves):
        raise ValueError(
            "block-tridiagonal solver needs operator leaves of shape (n_i, b) with one b; "
            f"got {[x.shape for x in leaves]}"
        )
    (b,) = widths
    n = sum(sizes)
    dtype = leaves[0].dtype
    node = jnp.arange(n)
    colour = node % 3
    # seed[c, d] has ones at dof d of every node of colour c
    seeds = (colour[None, None, :, None] == jnp.arange(3)[:, None, None, None]) & (
        jnp.arange(b)[None, :, None, None] == jnp.arange(b)[None, None, None, :]
    )
    seeds = seeds.astype(dtype).reshape(3 * b, n, b)
    cols = jax.vmap(lambda s: _flatten(fn_mv(_unflatten(s, treedef, sizes)), sizes))(seeds)
    cols = cols.reshape(3, b, n, b)  # (colour, input dof, output node, output dof)

    def blocks(src_node):
        # J[i, :, src, :]: column dof d of node src is in cols[src % 3, d, i, :]
        blk = cols[src_node % 3, :, node, :]  # (n, b_in, b_out)
        return jnp.swapaxes(blk, -1, -2)  # (n, b_out, b_in)

    diag = blocks(node)
    lower = blocks(jnp.maximum(node - 1, 0)).at[0].set(0.0)
    upper = blocks(jnp.minimum(node + 1, n - 1)).at[-1].set(0.0)
    return lower, diag, upper, treedef, sizes


class BlockTridiagonalSolver(lx.AbstractLinearSolver):
    """lineax solver exploiting the block-banded Jacobian of line states (O(n))."""

    def init(self, operator, options):
        del options
        lower, diag, upper, treedef, sizes = band_of(operator.mv, operator.in_structure())
        lu = btd.factor(lower, diag, upper)
        return _State(lower, diag, upper, lu, treedef, sizes)

    def compute(self, state: _State, vector, options):
        del options
        x = btd.solve(state.lu, _flatten(vector, state.sizes))
        return _unflatten(x, state.treedef, state.sizes), lx.RESULTS.successful, {}

    def transpose(self, state: _State, options):
        del options
        t = lambda a: jnp.swapaxes(a, -1, -2)  # noqa: E731
        lower = jnp.concatenate([jnp.zeros_like(state.upper[:1]), t(state.upper[:-1])], axis=0)
        upper = jnp.concatenate([t(state.lower[1:]), jnp.zeros_like(state.lower[:1])], axis=0)
        diag = t(state.diag)
        lu = btd.factor(lower, diag, upper)
        return _State(lower, diag, upper, lu, state.treedef, state.sizes), {}

    def conj(self, state: _State, options):
        return state, {}

    def assume_full_rank(self):
        return True

    def allow_dependent_columns(self, operator):
        return False

    def allow_dependent_rows(self, operator):
        return False
