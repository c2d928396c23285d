"""Ordering of batched LAPACK calls, against a deadlock of jaxlib 0.10's CPU kernels.

jaxlib 0.10's LAPACK kernels (LU ``getrf``, SVD ``gesdd``, triangular solve
``trsm``, ...) split a batched call (one under ``vmap``) into chunks, queue them on
XLA:CPU's intra-op thread pool and block until they are done. XLA runs
independent operations of one program at the same time on that same pool. When
as many batched kernels as the pool has threads (the machine's cores: 2 on a
2-core machine) run at once, every thread waits for chunks that no thread is left
to run, and the process hangs with the CPU idle (seen in gdb: all pool threads in
``jax::ParallelBatchMap`` → ``BlockingCounter::Wait``). jaxlib 0.11.2 builds the
parallel path out; 0.10.2 is the newest on the package index here.

Two factorisations of the same matrix, or of independent ones, in one function
are exactly that: independent. :func:`after` makes one wait for the other, so
that at most one batched kernel of the function runs at a time. It costs one
element of each dependency and an addition, and the lost overlap (the kernels are
small). A larger pool (``PJRT_NPROC``) would make the hang rarer but made case A
15–25 % slower on 2 cores (interleaved runs, ``benchmarks/README.md``, session
21), so it is not set.

``tests/test_lapack_ordering.py`` checks compiled programs for batched LAPACK
calls that may still run at the same time.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np


def after(x, *deps):
    """``x`` (a pytree; its float arrays), computed only once every float array
    in ``deps`` is; the same for their derivatives.

    A data dependency XLA keeps: a negative zero computed from one element of
    each dependency (made finite) is added to every float array of ``x``;
    adding −0 leaves every value as it is, bit for bit (a +0 would turn −0 into
    +0). It carries into derivatives as well (a tangent or cotangent of ``x``
    waits for those of ``deps``) and adds nothing to their values.
    ``lax.optimization_barrier`` would not do: XLA:CPU removes it before it
    schedules, so it orders nothing at run time."""
    zeros = [-(jnp.abs(jnp.where(jnp.isfinite(e), e, 0.0)) * 0.0)
             for e in (jnp.ravel(d)[0] for d in jax.tree.leaves(deps) if _floats(d) and d.size)]
    if not zeros:
        return x
    zero = functools.reduce(jnp.add, zeros)

    return jax.tree.map(lambda a: a + zero.astype(a.dtype) if _floats(a) else a, x)


def _floats(a) -> bool:
    return isinstance(a, jax.Array | np.ndarray) and jnp.issubdtype(a.dtype, jnp.inexact)
