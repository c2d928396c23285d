"""MoorDyn body frames: where a point fixed in a body is, for a body pose.

MoorDyn v2 gives a body's pose as its reference point (X, Y, Z) [m] and three
angles (roll, pitch, yaw) — degrees in a deck, radians through the coupling
API and in moorjax motion files — and places a point given in body axes at

    r = (X, Y, Z) + R · p,    R = Rx(roll) · Ry(pitch) · Rz(yaw)

(intrinsic x–y′–z″ rotations, each right-handed: positive roll lowers the
starboard side −y, positive pitch lowers the bow +x, positive yaw turns the bow
towards +y). This is MoorDyn-C v2's ``Euler2Quat`` (checked against MoorDyn
2.7.2 in the tests). It is *not* the order of :func:`moorjax.body.rotation`
(Rz·Ry·Rx) used by moorjax's own rigid bodies; the two agree to first order in
the angles.

Pure numpy (no JAX): used when reading decks and motion files.
"""

from __future__ import annotations

import numpy as np

__all__ = ["moordyn_rotation", "body_point_positions", "body_point_velocities"]


def _axis_rotations(angles):
    """Rx, Ry, Rz (…, 3, 3) and their derivatives for angles (…, 3) [rad]."""
    a = np.asarray(angles, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    zero, one = np.zeros_like(a[..., 0]), np.ones_like(a[..., 0])

    def mat(rows):
        return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)

    cx, sx, cy, sy, cz, sz = c[..., 0], s[..., 0], c[..., 1], s[..., 1], c[..., 2], s[..., 2]
    rx = mat([[one, zero, zero], [zero, cx, -sx], [zero, sx, cx]])
    ry = mat([[cy, zero, sy], [zero, one, zero], [-sy, zero, cy]])
    rz = mat([[cz, -sz, zero], [sz, cz, zero], [zero, zero, one]])
    drx = mat([[zero, zero, zero], [zero, -sx, -cx], [zero, cx, -sx]])
    dry = mat([[-sy, zero, cy], [zero, zero, zero], [-cy, zero, -sy]])
    drz = mat([[-sz, -cz, zero], [cz, -sz, zero], [zero, zero, zero]])
    return (rx, ry, rz), (drx, dry, drz)


def moordyn_rotation(angles) -> np.ndarray:
    """R = Rx(roll)·Ry(pitch)·Rz(yaw) (…, 3, 3) from angles (…, 3) [rad]."""
    (rx, ry, rz), _ = _axis_rotations(angles)
    return rx @ ry @ rz


def body_point_positions(poses, local) -> np.ndarray:
    """Global positions (…, 3) [m] of a body-fixed point.

    Args:
        poses: (…, 6) body poses: reference point x, y, z [m], then roll, pitch,
            yaw [rad].
        local: (3,) the point in body axes, relative to the reference point [m].
    """
    poses = np.asarray(poses, dtype=np.float64)
    p = np.asarray(local, dtype=np.float64).reshape(3)
    return poses[..., :3] + moordyn_rotation(poses[..., 3:]) @ p


def body_point_velocities(poses, rates, local) -> np.ndarray:
    """Velocities (…, 3) [m/s] of a body-fixed point: the time derivative of
    :func:`body_point_positions` for pose rates (…, 6) (ẋ, ẏ, ż [m/s], then the
    rates of roll, pitch, yaw [rad/s])."""
    poses = np.asarray(poses, dtype=np.float64)
    rates = np.asarray(rates, dtype=np.float64)
    p = np.asarray(local, dtype=np.float64).reshape(3)
    (rx, ry, rz), (drx, dry, drz) = _axis_rotations(poses[..., 3:])
    d_roll, d_pitch, d_yaw = (drx @ ry @ rz) @ p, (rx @ dry @ rz) @ p, (rx @ ry @ drz) @ p
    return (rates[..., :3] + d_roll * rates[..., 3:4] + d_pitch * rates[..., 4:5]
            + d_yaw * rates[..., 5:6])
