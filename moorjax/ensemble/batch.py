"""Stacking scenes of one structure into a batch (a leading ensemble axis).

Members of an ensemble may differ in any *array* value (EA, Cd, lengths, end
motions, initial states) but not in structure: segment counts, which force terms
exist (drag, added mass, seabed, current), end types and array shapes. Stacking
checks this and names the first field that differs.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np


class StructureMismatchError(ValueError):
    """Ensemble members that do not share one structure."""


def _is_array(x):
    return isinstance(x, (jax.Array, np.ndarray, np.generic))


def _as_array(x):
    """Python numbers count as 0-d arrays (they stack like them)."""
    if isinstance(x, (bool, int, float)) and not isinstance(x, bool):
        return np.asarray(x, dtype=float)
    return x


_FLOATING = {}


def _floating(x) -> bool:
    """Whether an array's dtype is a floating one (kept per dtype: checking an
    ensemble's members asks it for every leaf of every member)."""
    dt = np.result_type(x) if not hasattr(x, "dtype") else x.dtype
    try:
        return _FLOATING[dt]
    except KeyError:
        out = _FLOATING[dt] = bool(jnp.issubdtype(dt, jnp.floating))
        return out


def _alike(a, b) -> bool:
    """True when two pytrees certainly share one structure: equal tree
    definitions (node types, static fields, which optional terms exist) and
    leaves that agree in shape and in being floating point, or are equal where
    they are not arrays. False means "look closer" (:func:`structure_difference`
    finds and names the difference). The members of an ensemble are compared
    with the first one this way: 199 comparisons of case A scenes take 15 ms,
    37 ms field by field (0.45 s before the dtype checks were kept per dtype)."""
    try:
        la, ta = jax.tree_util.tree_flatten(a)
        lb, tb = jax.tree_util.tree_flatten(b)
        if len(la) != len(lb) or not bool(ta == tb):
            return False
        for x, y in zip(la, lb):
            x, y = _as_array(x), _as_array(y)
            if _is_array(x) and _is_array(y):
                if np.shape(x) != np.shape(y) or _floating(x) != _floating(y):
                    return False
            elif _is_array(x) or _is_array(y) or not bool(x == y):
                return False
        return True
    except Exception:  # e.g. an array among the static fields: compare field by field
        return False


def structure_difference(a, b, path: str = "member") -> str | None:
    """The first structural difference between two pytrees, as text (``None`` if none).

    Array leaves may differ in value but not in shape or dtype; everything else
    (module types, static fields such as ``n_segments``, present/absent optional
    terms) must be equal.
    """
    if _alike(a, b):
        return None
    return _difference(a, b, path)


def _difference(a, b, path):
    """:func:`structure_difference`, field by field."""
    a, b = _as_array(a), _as_array(b)
    if a is None or b is None:
        if (a is None) != (b is None):
            return f"{path}: present in one member, absent (None) in the other"
        return None
    if _is_array(a) or _is_array(b):
        if not (_is_array(a) and _is_array(b)):
            return f"{path}: an array in one member, {type(b if _is_array(a) else a).__name__} in the other"
        if a.shape != b.shape:
            return f"{path}: shape {a.shape} vs {b.shape}"
        if _floating(a) != _floating(b):
            return f"{path}: dtype {a.dtype} vs {b.dtype}"
        return None
    if type(a) is not type(b):
        return f"{path}: {type(a).__name__} vs {type(b).__name__}"
    if isinstance(a, eqx.Module):
        for f in dataclasses.fields(a):
            va, vb = getattr(a, f.name, None), getattr(b, f.name, None)
            sub = f"{path}.{f.name}"
            if f.metadata.get("static", False):
                if va != vb:
                    return f"{sub}: {va!r} vs {vb!r}"
            else:
                d = _difference(va, vb, sub)
                if d:
                    return d
        return None
    if isinstance(a, (tuple, list)):
        if len(a) != len(b):
            return f"{path}: {len(a)} vs {len(b)} items"
        for i, (x, y) in enumerate(zip(a, b)):
            d = _difference(x, y, f"{path}[{i}]")
            if d:
                return d
        return None
    if isinstance(a, dict):
        if set(a) != set(b):
            return f"{path}: keys {sorted(a)} vs {sorted(b)}"
        for k in a:
            d = _difference(a[k], b[k], f"{path}[{k!r}]")
            if d:
                return d
        return None
    if a != b:
        return f"{path}: {a!r} vs {b!r}"
    return None


def stack(members: Sequence, name: str = "member"):
    """Stack pytrees of one structure along a new leading axis.

    Raises :class:`StructureMismatchError` naming the first differing field, e.g.
    ``member.lines[0].n_segments: 20 vs 40``.
    """
    members = list(members)
    if not members:
        raise ValueError("an ensemble needs at least one member")
    first = members[0]
    for i, m in enumerate(members[1:], start=1):
        d = structure_difference(first, m, name)
        if d is not None:
            raise StructureMismatchError(
                f"ensemble members 0 and {i} differ in structure at {d}; members may "
                "differ only in array values (segment counts, force terms, end types "
                "and array shapes must be the same)"
            )
    return jax.tree_util.tree_map(_stacked, *members)


def _stacked(*xs):
    """One leaf of every member, stacked. Concrete arrays of one dtype are
    stacked on the host and placed once (100 members of case A: 30 ms instead of
    0.29 s of eager device operations); anything else (Python numbers, weakly
    typed or traced values, mixed dtypes) as ``jnp.stack`` would."""
    if all(isinstance(x, np.ndarray) or (isinstance(x, jax.Array) and not x.weak_type
                                         and not isinstance(x, jax.core.Tracer)) for x in xs):
        dtypes = {x.dtype for x in xs}
        if len(dtypes) == 1:
            return jnp.asarray(np.stack([np.asarray(x) for x in xs]), dtype=dtypes.pop())
    return jnp.stack([jnp.asarray(x) for x in xs])


def size(batch) -> int:
    """Number of members of a stacked batch (its leading axis)."""
    leaves = [x for x in jax.tree_util.tree_leaves(batch) if _is_array(x)]
    if not leaves:
        raise ValueError("a batch needs at least one array leaf")
    n = {int(np.shape(x)[0]) if np.ndim(x) else -1 for x in leaves}
    if len(n) != 1 or -1 in n:
        raise ValueError(f"batch leaves disagree on the leading (member) axis: sizes {sorted(n)}")
    return n.pop()


def member(batch, i: int):
    """Member ``i`` of a stacked batch."""
    return jax.tree_util.tree_map(lambda x: x[i] if _is_array(x) else x, batch)


def take(batch, index):
    """Members ``index`` (an integer array) of a stacked batch, still stacked."""
    index = np.asarray(index)
    return jax.tree_util.tree_map(lambda x: x[index] if _is_array(x) else x, batch)


def first(result, n: int, n_padded: int):
    """The first ``n`` members of a padded batch of results: leaves whose leading
    axis has the ``n_padded`` members are cut to ``n``, others (shared fields,
    scalars) kept."""
    if n == n_padded:
        return result
    return jax.tree_util.tree_map(
        lambda x: x[:n] if isinstance(x, jax.Array) and x.ndim and x.shape[0] == n_padded else x,
        result,
    )
