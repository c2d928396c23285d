"""The scene's equations of motion as a first-order ODE on a pytree.

Solver state: a tuple with one (n_i − 1, 6) array per line, the free nodes'
[position, velocity] side by side. This node-major layout keeps each line's
Jacobian block-tridiagonal (6×6 blocks), which the block-tridiagonal Newton solve
exploits; a system of several lines stacks into one larger band.
"""

from __future__ import annotations

import jax.numpy as jnp

from ..model.line import LineState


def pack(states) -> tuple:
    """Line states → solver state (tuple of (n−1, 6) arrays)."""
    return tuple(jnp.concatenate([s.r, s.v], axis=-1) for s in states)


def unpack(y) -> tuple:
    """Solver state → tuple of :class:`LineState`."""
    return tuple(LineState(r=q[..., :3], v=q[..., 3:]) for q in y)


def vector_field(t, y, scene):
    """dy/dt for every line: (velocity, acceleration) of the free nodes."""
    out = []
    for line, q in zip(scene.lines, y):
        r, v = line.nodes(t, LineState(r=q[:, :3], v=q[:, 3:]))
        acc = line.element.accelerations(line, scene.env, t, r, v)
        out.append(jnp.concatenate([q[:, 3:], acc], axis=-1))
    return tuple(out)


def end_outputs(t, y, scene, with_nodes: bool = False):
    """Forces on each line's end points at time t (and optionally node data).

    Returns a dict with ``force_a``, ``force_b`` (n_lines, 3) [N], ``tension_a``,
    ``tension_b`` (n_lines,) [N]; with ``with_nodes``, also ``positions`` and
    ``segment_tensions``: tuples with one (n+1, 3) [m] / (n,) [N] array per line.
    """
    fa, fb, pos, ten = [], [], [], []
    for line, q in zip(scene.lines, y):
        r, v = line.nodes(t, LineState(r=q[:, :3], v=q[:, 3:]))
        a, b = line.element.end_forces(line, scene.env, r, v)
        fa.append(a)
        fb.append(b)
        if with_nodes:
            pos.append(r)
            ten.append(line.element.segment_tensions(line, r, v))
    fa, fb = jnp.stack(fa), jnp.stack(fb)
    out = dict(
        force_a=fa,
        force_b=fb,
        tension_a=jnp.linalg.norm(fa, axis=-1),
        tension_b=jnp.linalg.norm(fb, axis=-1),
    )
    if with_nodes:
        out["positions"] = tuple(pos)
        out["segment_tensions"] = tuple(ten)
    return out
