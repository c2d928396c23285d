"""Parameter sweeps for ensembles (``moorjax ensemble --vary NAME=v1,v2,...``).

Names are those of :mod:`moorjax.model.parameters`.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

from ..model.parameters import check_name, set_parameter, valid_names


def parse_vary(spec: str) -> tuple[str, list[float]]:
    """``'Cd=1.2,1.6,2.0'`` -> ``('Cd', [1.2, 1.6, 2.0])`` (name checked)."""
    if "=" not in spec:
        raise ValueError(f"--vary {spec!r}: expected NAME=v1,v2,...; valid names: {valid_names()}")
    name, values = spec.split("=", 1)
    name = name.strip()
    check_name(name)
    out = []
    for v in values.split(","):
        try:
            out.append(float(v))
        except ValueError:
            raise ValueError(f"--vary {name}: {v!r} is not a number") from None
    if not out:
        raise ValueError(f"--vary {name}: no values")
    return name, out


def sweep(scene, varies: Sequence[tuple[str, Sequence[float]]]):
    """Members of a full-factorial sweep: (list of scenes, list of {name: value}).

    The first parameter varies slowest.
    """
    names = [n for n, _ in varies]
    if len(set(names)) != len(names):
        raise ValueError(f"a parameter is varied twice: {names}")
    members, table = [], []
    for combo in itertools.product(*[vals for _, vals in varies]):
        s = scene
        for name, value in zip(names, combo):
            s = set_parameter(s, name, value)
        members.append(s)
        table.append(dict(zip(names, combo)))
    return members, table
