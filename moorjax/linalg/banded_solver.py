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

    def _init_band(self, operator):
        return self.factor_bands(*band_of(operator.mv, operator.in_structure()))

    def factor_bands(self, lower, diag, upper, treedef, sizes):
        """The solver state of the block-tridiagonal matrix with these bands (as
        :func:`band_of` returns them), for :meth:`compute`."""
        lu = btd.factor(lower, diag, upper)
        return _State(lower, diag, upper, lu, treedef, sizes)

    def _compute_band(self, state: _State, vector):
        x = btd.solve(state.lu, _flatten(vector, state.sizes))
        return _unflatten(x, state.treedef, state.sizes)

    def _transpose_band(self, state: _State):
        t = lambda a: jnp.swapaxes(a, -1, -2)  # noqa: E731
        lower = jnp.concatenate([jnp.zeros_like(state.upper[:1]), t(state.upper[:-1])], axis=0)
        upper = jnp.concatenate([t(state.lower[1:]), jnp.zeros_like(state.lower[:1])], axis=0)
        diag = t(state.diag)
        lu = btd.factor(lower, diag, upper)
        return _State(lower, diag, upper, lu, state.treedef, state.sizes)

    # -- the lineax interface: bands plus dense blocks for 1-D leaves ---------
    def init(self, operator, options):
        del options
        structure = operator.in_structure()
        leaves, treedef = jtu.tree_flatten(structure)
        if all(len(x.shape) == 2 for x in leaves):
            return self._init_band(operator)
        return _init_loose(self, operator, leaves, treedef)

    def compute(self, state, vector, options):
        del options
        if isinstance(state, _LooseState):
            return _compute_loose(self, state, vector)
        return self._compute_band(state, vector), lx.RESULTS.successful, {}

    def transpose(self, state, options):
        del options
        if isinstance(state, _LooseState):
            return _transpose_loose(self, state), {}
        return self._transpose_band(state), {}

    def conj(self, state: _State, options):
        return state, {}

    def assume_full_rank(self):
        return True

    def allow_dependent_columns(self, operator):
        return False

    def allow_dependent_rows(self, operator):
        return False


class _ReducedState(eqx.Module):
    lower: Array  # the full 6×6 band, kept for the transpose
    diag: Array
    upper: Array
    p_inv: Array  # (N, 3, 3) inverses of the position-row diagonal blocks
    gain: Array  # (N, 3, 3) P⁻¹Q
    coupling: tuple  # R band (lower, diag, upper), (N, 3, 3) each
    lu: btd.BlockTridiagonalLU  # of the reduced 3×3 velocity system
    treedef: Any = eqx.field(static=True)
    sizes: tuple = eqx.field(static=True)


class SecondOrderBandSolver(BlockTridiagonalSolver):
    """Block-tridiagonal solve specialised to first-order forms of 2nd-order systems.

    For a state of node-major [position(3), velocity(3)] rows, an implicit stage
    matrix ``I − c·J`` of ``ṙ = v, v̇ = a(r, v)`` has position rows ``P x_i + Q v_i``
    with P, Q 3×3 *block-diagonal* (here P = I, Q = −cI): each node's position row
    only touches the node itself. Eliminating the positions leaves a
    block-tridiagonal system in the velocities with **3×3** blocks,
    ``(S − R P⁻¹Q) v = b₂ − R P⁻¹ b₁``, then ``x = P⁻¹(b₁ − Q v)``. Factoring 3×3
    blocks with cofactor inverses is several times cheaper than 6×6 blocks with
    LAPACK pivots. The band itself still comes from the 18 coloured JVPs.

    Requires operator leaves (n_i, 6) in that layout (as :mod:`moorjax.dynamics`
    builds them). Couplings of position rows to neighbouring nodes, if any, are
    ignored, which turns the Newton step into a chord step; the nonlinear solver's
    convergence test still guards the result. The transpose (needed by reverse-mode
    adjoints: the implicit-function derivative of each stage) is reduced the same
    way (see :meth:`transpose`).
    """

    def factor_bands(self, lower, diag, upper, treedef, sizes):
        if diag.shape[-1] != 6:
            raise ValueError(f"SecondOrderBandSolver needs 6 dofs per node (r, v); got {diag.shape[-1]}")
        p_inv = btd.inv3(diag[:, :3, :3])
        gain = btd.bmm(p_inv, diag[:, :3, 3:])
        r_l, r_d, r_u = lower[:, 3:, :3], diag[:, 3:, :3], upper[:, 3:, :3]
        # neighbour gains: node i-1 for the lower block, node i+1 for the upper
        g_prev = jnp.concatenate([jnp.zeros_like(gain[:1]), gain[:-1]], axis=0)
        g_next = jnp.concatenate([gain[1:], jnp.zeros_like(gain[:1])], axis=0)
        s_l = lower[:, 3:, 3:] - btd.bmm(r_l, g_prev)
        s_d = diag[:, 3:, 3:] - btd.bmm(r_d, gain)
        s_u = upper[:, 3:, 3:] - btd.bmm(r_u, g_next)
        lu = btd.factor3(s_l, s_d, s_u)
        return _ReducedState(lower, diag, upper, p_inv, gain, (r_l, r_d, r_u), lu, treedef, sizes)

    def _compute_band(self, state, vector):
        if isinstance(state, _State):  # transposed general operator
            return super()._compute_band(state, vector)
        if isinstance(state, _ReducedTransposed):
            return self._compute_transposed(state, vector)
        b = _flatten(vector, state.sizes)
        u = btd.bmv(state.p_inv, b[:, :3])
        rhs = b[:, 3:] - btd.matvec(*state.coupling, u)
        vel = btd.solve(state.lu, rhs)
        pos = u - btd.bmv(state.gain, vel)
        x = jnp.concatenate([pos, vel], axis=-1)
        return _unflatten(x, state.treedef, state.sizes)

    def _transpose_band(self, state):
        """The transposed stage system, reduced to 3×3 blocks like the forward one.

        Reverse mode through an implicit stage solves Aᵀx = b. With
        A = [[P, Q], [R, S]] (P, Q node-local),
        ``(S − R P⁻¹Q)ᵀ x₂ = b₂ − (P⁻¹Q)ᵀ b₁`` and ``x₁ = P⁻ᵀ(b₁ − Rᵀ x₂)``.
        """
        if isinstance(state, _ReducedTransposed):
            return state.original
        if isinstance(state, _State):
            return super()._transpose_band(state)
        gain = state.gain
        r_l, r_d, r_u = state.coupling
        g_prev = jnp.concatenate([jnp.zeros_like(gain[:1]), gain[:-1]], axis=0)
        g_next = jnp.concatenate([gain[1:], jnp.zeros_like(gain[:1])], axis=0)
        s_l = state.lower[:, 3:, 3:] - btd.bmm(r_l, g_prev)
        s_d = state.diag[:, 3:, 3:] - btd.bmm(r_d, gain)
        s_u = state.upper[:, 3:, 3:] - btd.bmm(r_u, g_next)
        lu = btd.factor3(*_transpose_band(s_l, s_d, s_u))
        return _ReducedTransposed(_t(state.p_inv), _t(gain), _transpose_band(r_l, r_d, r_u), lu,
                                  state, state.treedef, state.sizes)

    def _compute_transposed(self, state, vector):
        b = _flatten(vector, state.sizes)
        rhs = b[:, 3:] - btd.bmv(state.gain_t, b[:, :3])
        vel = btd.solve(state.lu, rhs)
        pos = btd.bmv(state.p_inv_t, b[:, :3] - btd.matvec(*state.coupling_t, vel))
        x = jnp.concatenate([pos, vel], axis=-1)
        return _unflatten(x, state.treedef, state.sizes)


def _t(a):
    return jnp.swapaxes(a, -1, -2)


def _transpose_band(lower, diag, upper):
    """Bands of Mᵀ from those of a block-tridiagonal M (conventions of ``btd``)."""
    lo = jnp.concatenate([jnp.zeros_like(upper[:1]), _t(upper[:-1])], axis=0)
    up = jnp.concatenate([_t(lower[1:]), jnp.zeros_like(lower[:1])], axis=0)
    return lo, _t(diag), up


class _ReducedTransposed(eqx.Module):
    p_inv_t: Array  # (N, 3, 3) P⁻ᵀ
    gain_t: Array  # (N, 3, 3) (P⁻¹Q)ᵀ
    coupling_t: tuple  # bands of Rᵀ
    lu: btd.BlockTridiagonalLU  # of (S − R P⁻¹Q)ᵀ
    original: Any  # the forward state (transpose of the transpose)
    treedef: Any = eqx.field(static=True)
    sizes: tuple = eqx.field(static=True)


# -- 1-D leaves (floating bodies): dense blocks beside the band ----------------
#
# A body's state is a short 1-D leaf coupled to the lines only through their
# fairlead nodes. Its block of the Jacobian is taken exactly (one JVP per body
# state entry) and solved by a dense LU; the couplings between the body and the
# lines are left out of the Newton matrix (a block-Jacobi approximation). The
# Newton iteration then contracts at a rate of about (c·dt)²·k/M — the fairleads'
# stiffness against the body's mass, small for a moored hull — and its residual
# test still decides convergence. Exact gradients (reverse mode through implicit
# stages) need the exact Jacobian: use ``linear_solver="dense"`` for those.


class _BandOperator:
    """The operator restricted to the 2-D leaves (1-D leaves held at zero)."""

    def __init__(self, operator, leaves, treedef, band_idx):
        self._op, self._leaves, self._treedef, self._band = operator, leaves, treedef, band_idx

    def in_structure(self):
        return tuple(self._leaves[i] for i in self._band)

    def mv(self, band_vec):
        full = [jnp.zeros(x.shape, x.dtype) for x in self._leaves]
        for i, v in zip(self._band, band_vec):
            full[i] = v
        out = jtu.tree_leaves(self._op.mv(jtu.tree_unflatten(self._treedef, full)))
        return tuple(out[i] for i in self._band)


class _LooseState(eqx.Module):
    band: Any
    blocks: tuple  # (lu, piv) per 1-D leaf
    transposed: bool = eqx.field(static=True)
    band_idx: tuple = eqx.field(static=True)
    loose_idx: tuple = eqx.field(static=True)
    treedef: Any = eqx.field(static=True)


def _init_loose(solver, operator, leaves, treedef):
    band_idx = tuple(i for i, x in enumerate(leaves) if len(x.shape) == 2)
    loose_idx = tuple(i for i, x in enumerate(leaves) if len(x.shape) == 1)
    if len(band_idx) + len(loose_idx) != len(leaves):
        raise ValueError(f"structured Newton solve: leaves must be (n, 6) line states or 1-D body "
                         f"states; got shapes {[x.shape for x in leaves]}")
    band = solver._init_band(_BandOperator(operator, leaves, treedef, band_idx)) if band_idx else None
    blocks = []
    for i in loose_idx:
        n = leaves[i].shape[0]

        def column(e, i=i):
            full = [jnp.zeros(x.shape, x.dtype) for x in leaves]
            full[i] = e
            return jtu.tree_leaves(operator.mv(jtu.tree_unflatten(treedef, full)))[i]

        blocks.append(dense_lu(column, n, leaves[i].dtype))
    return _LooseState(band, tuple(blocks), False, band_idx, loose_idx, treedef)


def dense_lu(apply, n, dtype):
    """LU factors ``(lu, pivots)`` of the n×n matrix A given by its action
    ``apply(e) = A·e`` on an (n,) vector: the n columns in one vmapped call."""
    cols = jax.vmap(apply)(jnp.eye(n, dtype=dtype))  # row k: A·e_k
    return jax.scipy.linalg.lu_factor(cols.T)


def _compute_loose(solver, state, vector):
    vec = jtu.tree_leaves(vector)
    out = [None] * len(vec)
    if state.band is not None:
        xb = solver._compute_band(state.band, tuple(vec[i] for i in state.band_idx))
        for i, x in zip(state.band_idx, jtu.tree_leaves(xb)):
            out[i] = x
    trans = 1 if state.transposed else 0
    for i, blk in zip(state.loose_idx, state.blocks):
        out[i] = jax.scipy.linalg.lu_solve(blk, vec[i], trans=trans)
    return jtu.tree_unflatten(state.treedef, out), lx.RESULTS.successful, {}


def _transpose_loose(solver, state):
    band = None if state.band is None else solver._transpose_band(state.band)
    return _LooseState(band, state.blocks, not state.transposed, state.band_idx,
                       state.loose_idx, state.treedef)
