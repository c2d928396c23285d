"""A scene: the lines of a mooring system and the environment they share.

The system state is a pytree: a tuple with one :class:`LineState` per line (a
floating body's state will sit beside them).
"""

from __future__ import annotations

import equinox as eqx

from .environment import Environment
from .line import Line


class Scene(eqx.Module):
    """Lines (a tuple) in one environment."""

    lines: tuple[Line, ...]
    env: Environment

    def __init__(self, lines, env: Environment):
        lines = tuple(lines)
        if not lines:
            raise ValueError("a scene needs at least one line")
        labels = [ln.label for ln in lines]
        if len(set(labels)) != len(labels):
            raise ValueError(f"line labels must be unique, got {labels}")
        self.lines = lines
        self.env = env
