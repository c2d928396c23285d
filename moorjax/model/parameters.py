"""Named physical parameters of a scene (for sweeps, fits and the command line).

A name applies to every line (``Cd``) or to one line by its deck id
(``L2.Cd``); environment names (``depth``, ``kBot``, ...) apply to the scene.
Setting a value never changes structure, so all members of a sweep share one
compiled function. A term the scene does not have (e.g. ``Cd`` of a line type
built without drag) cannot be varied: the error says so.

Note: MoorDyn's ``BA < 0`` (a damping *ratio*) is converted to a coefficient
when the deck is read; varying ``EA`` does not recompute it.

Besides MoorDyn's column names there are aliases in the words of the
identification API (``Cd_normal`` = ``Cd``, ``Cd_axial`` = ``CdAx``,
``Ca_normal`` = ``Ca``, ``Ca_axial`` = ``CaAx``), the constants of the
load-dependent polyester laws (``alpha``, ``beta``, ``MBL``), end positions
(``xA`` … ``zB`` [m]: a fixed end's point or a sine path's centre) and the
components of a uniform current (``current_x`` … [m/s]). Components of a vector
are *signed* (any finite value).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .axial import Bilateral, LinearEA, PolyesterMBL, PolyesterWu
from .ends import FixedEnd, SinePath
from .environment import UniformCurrent


@dataclass(frozen=True)
class Parameter:
    doc: str
    unit: str
    where: Callable  # line -> leaf, or env -> leaf
    scope: str  # "line" or "env"
    positive: bool  # > 0 required (else >= 0)
    index: int | None = None  # component of a vector leaf (where(...) is the vector)
    signed: bool = False  # any finite value (overrides ``positive``)


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


def _polyester(line, what):
    axial = line.line_type.axial
    if isinstance(axial, Bilateral):
        axial = axial.law
    if not isinstance(axial, (PolyesterWu, PolyesterMBL)):
        raise ValueError(
            f"line {line.label}: {what} belongs to a load-dependent polyester law "
            f"(PolyesterWu or PolyesterMBL), not {type(axial).__name__}"
        )
    return axial


def _mbl(line):
    axial = _polyester(line, "MBL")
    return axial.mbl if isinstance(axial, PolyesterMBL) else axial.breaking_strength


def _end_point(line, end):
    e = line.end_a if end == "A" else line.end_b
    if isinstance(e, FixedEnd):
        return e.point
    if isinstance(e, SinePath):
        return e.center
    raise ValueError(
        f"line {line.label}: end {end} is a {type(e).__name__}; only a fixed end's point "
        "or a sine path's centre can be varied"
    )


def _uniform_current(env):
    cur = env.current
    if not isinstance(cur, UniformCurrent):
        what = "no current" if cur is None else f"a {type(cur).__name__}"
        raise ValueError(
            f"the scene has {what}; current_x/_y/_z vary a UniformCurrent (build the "
            "environment with current=UniformCurrent([ux, uy, uz]) to vary it)"
        )
    return cur.u


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
    # load-dependent polyester laws: EA(T) = MBL·(alpha + beta·T/MBL) (PolyesterMBL)
    # or RHOL·(alpha + beta·T/Bs)·1e6 (PolyesterWu, whose Bs is named MBL here)
    "alpha": Parameter("polyester stiffness constant alpha", "-",
                       lambda ln: _polyester(ln, "alpha").alpha, "line", True),
    "beta": Parameter("polyester load-dependence constant beta", "-",
                      lambda ln: _polyester(ln, "beta").beta, "line", False),
    "MBL": Parameter("minimum breaking load of a polyester law", "N", _mbl, "line", True),
}
# aliases (same leaves) in the words of the identification API
PARAMETERS["Cd_normal"] = PARAMETERS["Cd"]
PARAMETERS["Cd_axial"] = PARAMETERS["CdAx"]
PARAMETERS["Ca_normal"] = PARAMETERS["Ca"]
PARAMETERS["Ca_axial"] = PARAMETERS["CaAx"]
for _end in ("A", "B"):
    for _i, _c in enumerate("xyz"):
        PARAMETERS[f"{_c}{_end}"] = Parameter(
            f"{_c} of end {_end} (fixed point or sine-path centre)", "m",
            lambda ln, _end=_end: _end_point(ln, _end), "line", False, index=_i, signed=True,
        )
for _i, _c in enumerate("xyz"):
    PARAMETERS[f"current_{_c}"] = Parameter(
        f"{_c} component of a uniform current", "m/s", _uniform_current, "env", False,
        index=_i, signed=True,
    )


def valid_names() -> str:
    return ", ".join(f"{k} [{p.unit}]" for k, p in PARAMETERS.items())


def split_name(name: str):
    """A parameter name's line label and base name: 'L2.Cd' -> ('2', 'Cd'); 'Cd' -> (None, 'Cd')."""
    if "." in name and name.startswith("L"):
        label, base = name[1:].split(".", 1)
        return label, base
    return None, name




def check_name(name: str, scene=None) -> None:
    label, base = split_name(name)
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


def get_parameter(scene, name: str):
    """The value of parameter ``name`` (for a line-wide name, that of the first line)."""
    check_name(name, scene)
    label, base = split_name(name)
    p = PARAMETERS[base]
    if p.scope == "env":
        leaf = p.where(scene.env)
        return leaf if p.index is None else leaf[p.index]
    for line in scene.lines:
        if label is None or line.label == label:
            leaf = p.where(line)
            return leaf if p.index is None else leaf[p.index]


def set_parameter(scene, name: str, value):
    """A copy of ``scene`` with parameter ``name`` set to ``value`` (SI units).

    ``value`` may be a traced array (for gradients); concrete values are checked.
    """
    check_name(name, scene)
    label, base = split_name(name)
    p = PARAMETERS[base]
    if not isinstance(value, jax.core.Tracer):
        v = float(value)
        ok = np.isfinite(v) and (p.signed or (v > 0 if p.positive else v >= 0))
        if not ok:
            rel = "" if p.signed else (" and > 0" if p.positive else " and >= 0")
            raise ValueError(f"{name} = {v} {p.unit} must be finite{rel}")
    value = jnp.asarray(value, dtype=float)

    def new_leaf(old):
        return value if p.index is None else old.at[p.index].set(value)

    if p.scope == "env":
        old = p.where(scene.env)  # raises if the term is absent
        return eqx.tree_at(lambda s: p.where(s.env), scene, new_leaf(old))
    for i, line in enumerate(scene.lines):
        if label is None or line.label == label:
            old = p.where(line)
            scene = eqx.tree_at(lambda s, i=i: p.where(s.lines[i]), scene, new_leaf(old))
    return scene


