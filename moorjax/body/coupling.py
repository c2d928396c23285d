"""Lines attached to bodies: fairlead kinematics in, mooring wrenches out.

A line end of type :class:`~moorjax.model.ends.BodyEnd` is a point fixed in a
body. Given the bodies' poses and velocities, :func:`attach` replaces each such
end by a :class:`~moorjax.model.ends.KinematicEnd` where the fairlead is now, so
that the line physics never needs to know about bodies; :func:`mooring_wrenches`
sums the forces the lines exert on their fairleads into a force and moment about
each body's centre of gravity.
"""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp

from ..model.ends import BodyEnd, KinematicEnd


def body_ends(line):
    """The (end name, BodyEnd) pairs of a line (``"a"``/``"b"``)."""
    return [(k, e) for k, e in (("a", line.end_a), ("b", line.end_b)) if isinstance(e, BodyEnd)]


def attach(lines, bodies, poses, velocities):
    """Lines with their fairleads placed at the bodies' current poses.

    Args:
        lines: tuple of lines; bodies: tuple of :class:`RigidBody`.
        poses, velocities: sequences of (6,) η and η̇ per body.
    """
    out = []
    for line in lines:
        changes = {}
        for name, end in body_ends(line):
            body = bodies[end.body]
            pos = body.point_position(poses[end.body], end.point)
            vel = body.point_velocity(poses[end.body], velocities[end.body], end.point)
            changes[f"end_{name}"] = KinematicEnd(pos, vel)
        out.append(dataclasses.replace(line, **changes) if changes else line)
    return tuple(out)


def mooring_wrenches(lines, bodies, poses, end_forces):
    """(6,) force and moment on each body from the lines [N, N·m].

    Args:
        lines: the scene's lines (with their :class:`BodyEnd` s, not attached).
        end_forces: per line, the (force_a, force_b) the line exerts on its ends.
    """
    points = [[] for _ in bodies]
    forces = [[] for _ in bodies]
    for line, (fa, fb) in zip(lines, end_forces):
        for name, end in body_ends(line):
            points[end.body].append(end.point)
            forces[end.body].append(fa if name == "a" else fb)
    out = []
    for k, body in enumerate(bodies):
        if not points[k]:
            out.append(jnp.zeros(6))
            continue
        out.append(body.wrench(poses[k], jnp.stack(points[k]), jnp.stack(forces[k])))
    return out
