"""Lines of one structure, computed as one vmapped call.

XLA inlines every traced call: a scene of three identical chains traced line by
line compiles three copies of the line's static solve, and inside a body's
Newton iteration (where each solve also appears linearised) the copies multiply.
:func:`map_lines` groups the lines that differ only in their values (same
element, segment count, end types, axial law, ...; the label does not count),
stacks each group and maps the function over it with ``vmap``: one traced copy
per structure. The answers are the same as one call per line (a vmapped
``while_loop`` runs until its last member is done; members already done keep
their values).
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..linalg.ordering import after


def _stackable(x):
    return eqx.is_array(x) or isinstance(x, (float, int, complex, np.generic))


def _signature(tree):
    """What must be equal for two pytrees to stack: structure, array shapes and
    dtypes, and every other leaf's value."""
    leaves, treedef = jax.tree_util.tree_flatten(tree, is_leaf=lambda x: x is None)
    sig = tuple(("array", tuple(np.shape(x)), str(jnp.result_type(x))) if _stackable(x)
                else ("value", type(x).__name__, repr(x)) for x in leaves)
    return treedef, sig


def _line_key(line):
    """The line's structure without its label (a name, not structure)."""
    parts = []
    for f in dataclasses.fields(line):
        if f.name == "label":
            continue
        value = getattr(line, f.name)
        parts.append((f.name, value) if f.metadata.get("static") else (f.name, _signature(value)))
    return type(line), tuple(parts)


def _key(line, args=()):
    try:
        key = (_line_key(line), _signature(args))
        hash(key)
        return key
    except TypeError:  # an unhashable static value: no grouping for this line
        return object()


def line_groups(lines, *per_line) -> list[list[int]]:
    """Indices of the lines (with their arguments ``per_line``) grouped by
    structure, in first-appearance order."""
    groups: dict = {}
    for i, line in enumerate(lines):
        groups.setdefault(_key(line, tuple(a[i] for a in per_line)), []).append(i)
    return list(groups.values())


def _stack(trees):
    return jax.tree_util.tree_map(
        lambda *xs: jnp.stack(xs) if _stackable(xs[0]) else xs[0], *trees,
        is_leaf=lambda x: x is None)


def _unstack(tree, i):
    return jax.tree_util.tree_map(lambda x: x[i] if eqx.is_array(x) else x, tree)


def map_lines(fn, lines, *per_line):
    """``tuple(fn(line, *args) for line, *args in zip(lines, *per_line))``, with
    the lines of one structure (and arguments of one structure) computed by one
    vmapped call. ``fn`` must be vmappable (``lax`` loops, no Python branching on
    values). A group of one is called directly.

    The groups run one after the other (:func:`~moorjax.linalg.ordering.after`,
    values unchanged): a line's solve or dynamics factorises, and two batched
    LAPACK calls running at once can hang jaxlib 0.10's CPU thread pool."""
    lines = tuple(lines)
    per_line = [tuple(a) for a in per_line]
    out = [None] * len(lines)
    previous = None  # the last group's answers
    for members in line_groups(lines, *per_line):
        rows = [tuple(a[i] for a in per_line) for i in members]
        group = [lines[i] for i in members]
        if previous is not None:
            group, rows = after((group, rows), previous)
        if len(members) == 1:
            out[members[0]] = fn(group[0], *rows[0])
            previous = out[members[0]]
            continue
        # every member rebuilt with the first one's static fields (labels differ)
        treedef = jax.tree_util.tree_structure(group[0], is_leaf=lambda x: x is None)
        same = [jax.tree_util.tree_unflatten(
            treedef, jax.tree_util.tree_leaves(line, is_leaf=lambda x: x is None))
            for line in group]
        batched = eqx.filter_vmap(fn)(_stack(same), *_stack(rows))
        for k, i in enumerate(members):
            out[i] = _unstack(batched, k)
        previous = batched
    return tuple(out)
