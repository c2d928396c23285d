"""Named parameters of a scene, for sweeps (``moorjax ensemble --vary``).

A name applies to every line (``Cd``) or to one line by its deck id
(``L2.Cd``); environment names (``depth``, ``kBot``, ...) apply to the scene.
Setting a value never changes structure, so all members of a sweep share one
compiled function. A term the scene does not have (e.g. ``Cd`` of a line type
built without drag) cannot be varied: the error says so.

Note: MoorDyn's ``BA < 0`` (a damping *ratio*) is converted to a coefficient
when the deck is read; varying ``EA`` does not recompute it.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Callable

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..model.axial import LinearEA


@dataclass(frozen=True)
class Parameter:
    doc: str
    unit: str
    where: Callable  # line -> leaf, or env -> leaf
    scope: str  # "line" or "env"
    positive: bool  # > 0 required (else >= 0)


def _need(obj, what, line_label):
    if obj is None:
        raise ValueError(f"line {line_label} has no {what} term, so it cannot be varied")
    return obj


def _ea(line):
    axial = line.line_type.axial
    if not isinstance(axial, LinearEA):
        raise ValueError(
            f"line {line.label}: EA can only be varied for a linear EA law, not {type(axial).__name__}"
        )
    return axial.ea


PARAMETERS: dict[str, Parameter] = {
    "EA": Parameter("axial stiffness", "N", _ea, "line", True),
    "BA": Parameter("internal damping coefficient", "N·s", lambda ln: ln.line_type.damping, "line", False),
    "Cd": Parameter("normal drag coefficient", "-",
                    lambda ln: _need(ln.line_type.drag, "drag", ln.label).cd_normal, "line", False),
    "CdAx": Parameter("axial drag coefficient", "-",
                      lambda ln: _need(ln.line_type.drag, "drag", ln.label).cd_axial, "line", False),
    "Ca": Parameter("normal added-mass coefficient", "-",
                    lambda ln: _need(ln.line_type.added_mass, "added-mass", ln.label).ca_normal,
                    "line", False),
    "CaAx": Parameter("axial added-mass coefficient", "-",
                      lambda ln: _need(ln.line_type.added_mass, "added-mass", ln.label).ca_axial,
                      "line", False),
    "d": Parameter("volume-equivalent diameter", "m", lambda ln: ln.line_type.diameter, "line", True),
    "mass": Parameter("mass per unit length", "kg/m",
                      lambda ln: ln.line_type.mass_per_length, "line", True),
    "length": Parameter("unstretched line length", "m", lambda ln: ln.length, "line", True),
    "depth": Parameter("water depth", "m", lambda env: env.depth, "env", True),
    "rho": Parameter("water density", "kg/m³", lambda env: env.rho, "env", True),
    "kBot": Parameter("seabed stiffness", "Pa/m",
                      lambda env: _need(env.seabed, "seabed", "-").stiffness, "env", False),
    "cBot": Parameter("seabed damping", "Pa·s/m",
                      lambda env: _need(env.seabed, "seabed", "-").damping, "env", False),
}


def valid_names() -> str:
    return ", ".join(f"{k} [{p.unit}]" for k, p in PARAMETERS.items())


def _split(name: str):
    """'L2.Cd' -> ('2', 'Cd'); 'Cd' -> (None, 'Cd')."""
    if "." in name and name.startswith("L"):
        label, base = name[1:].split(".", 1)
        return label, base
    return None, name


def check_name(name: str, scene=None) -> None:
    label, base = _split(name)
    if base not in PARAMETERS:
        raise ValueError(
            f"unknown parameter {name!r}; valid names (optionally prefixed L<id>. for one "
            f"line): {valid_names()}"
        )
    if label is not None:
        if PARAMETERS[base].scope != "line":
            raise ValueError(f"{base} is an environment parameter; it takes no line prefix")
        if scene is not None and label not in [ln.label for ln in scene.lines]:
            raise ValueError(
                f"parameter {name!r}: the scene has no line {label}; lines: "
                + ", ".join(ln.label for ln in scene.lines)
            )


def set_parameter(scene, name: str, value: float):
    """A copy of ``scene`` with parameter ``name`` set to ``value`` (SI units)."""
    check_name(name, scene)
    label, base = _split(name)
    p = PARAMETERS[base]
    value = float(value)
    ok = np.isfinite(value) and (value > 0 if p.positive else value >= 0)
    if not ok:
        rel = "> 0" if p.positive else ">= 0"
        raise ValueError(f"{name} = {value} {p.unit} must be finite and {rel}")
    if p.scope == "env":
        p.where(scene.env)  # raises if the term is absent
        return eqx.tree_at(lambda s: p.where(s.env), scene, jnp.asarray(value))
    for i, line in enumerate(scene.lines):
        if label is None or line.label == label:
            p.where(line)
            scene = eqx.tree_at(lambda s, i=i: p.where(s.lines[i]), scene, jnp.asarray(value))
    return scene


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
