"""A scene: the lines of a mooring system, the bodies they hold and their water.

The solver state is a tuple with one (n_i − 1, 6) array per line followed by one
1-D array per body (see :mod:`moorjax.body.rigid_body`). A scene without bodies
never traces body terms.
"""

from __future__ import annotations

import equinox as eqx
import numpy as np

from .ends import BodyEnd
from .environment import Environment
from .line import Line


class Scene(eqx.Module):
    """Lines (a tuple) in one environment, with optional floating bodies.

    Lines attach to body ``k`` through :class:`BodyEnd` (k) ends; the scene sets
    each such end's ``origin`` to the body's and checks that fairleads lie within
    a body's ``half_size`` when it has one.
    """

    lines: tuple[Line, ...]
    env: Environment
    bodies: tuple = ()

    def __init__(self, lines, env: Environment, bodies=()):
        lines = tuple(lines)
        bodies = tuple(bodies)
        if not lines:
            raise ValueError("a scene needs at least one line")
        labels = [ln.label for ln in lines]
        if len(set(labels)) != len(labels):
            raise ValueError(f"line labels must be unique, got {labels}")
        fixed = []
        for line in lines:
            for name in ("a", "b"):
                end = getattr(line, f"end_{name}")
                if not isinstance(end, BodyEnd):
                    continue
                if end.body >= len(bodies):
                    raise ValueError(
                        f"line {line.label!r} end {name.upper()} is attached to body {end.body}, "
                        f"but the scene has {len(bodies)} bod{'y' if len(bodies) == 1 else 'ies'}")
                body = bodies[end.body]
                if body.half_size is not None:
                    try:
                        p, h = np.asarray(end.point), np.asarray(body.half_size)
                    except Exception:  # noqa: BLE001 - traced values: no check
                        p = None
                    if p is not None and np.any(np.abs(p) > h * (1 + 1e-9)):
                        raise ValueError(
                            f"line {line.label!r} end {name.upper()}: fairlead {p.tolist()} m (body "
                            f"axes) is outside body {body.label!r} (half size {h.tolist()} m)")
                end = BodyEnd(end.body, end.point, body.origin)
                line = eqx.tree_at(lambda ln, n=name: getattr(ln, f"end_{n}"), line, end)
            fixed.append(line)
        self.lines = tuple(fixed)
        self.env = env
        self.bodies = bodies
