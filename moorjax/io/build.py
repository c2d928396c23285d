"""From a parsed MoorDyn deck to a moorjax :class:`Scene`.

MoorDyn conventions kept (so a deck means the same in both codes):

- ``Diam`` is the volume-equivalent diameter (buoyancy, drag, added mass).
- ``BA/-zeta``: BA ≥ 0 is an internal damping coefficient [N·s]; BA < 0 means a
  fraction ζ = −BA of each segment's critical damping, BA = ζ·(L/N)·√(EA·m),
  evaluated with the segment count actually used (``--segments`` included).
- ``Cd`` acts on the frontal area d·l, ``CdAx`` on the surface area π·d·l.
- ``Ca``/``CaAx`` multiply the displaced mass ρ·A·l.
- Seabed: ``kBot`` [Pa/m] and ``cBot`` [Pa·s/m] on d·l; ``FrictionCoefficient``
  > 0 adds smoothed Coulomb friction (slip velocity 0.01 m/s).
- Coupled points hold their deck position unless a motion is given.

Scene structure follows the deck: no drag / added mass terms when their
coefficients are all zero, no seabed term when every line is buoyant.
"""

from __future__ import annotations

import numpy as np

from ..model import (
    AddedMass,
    Environment,
    FixedEnd,
    Line,
    LinearEA,
    LineType,
    MorisonDrag,
    Seabed,
    SeabedFriction,
    TabulatedEA,
    TabulatedPath,
)
from ..model.scene import Scene
from .deck import Deck, options_with_defaults
from .errors import InputError


def _axial(dt):
    if dt.ea_table is not None:
        strain, tension = zip(*dt.ea_table)
        return TabulatedEA(strain, tension)
    return LinearEA(dt.ea)


def _line_type(dt, length, n_segments):
    axial = _axial(dt)
    ba = dt.ba
    if ba < 0:
        ba = -ba * (length / n_segments) * np.sqrt(float(axial.nominal_ea()) * dt.mass_per_length)
    drag = MorisonDrag(dt.cd, dt.cd_axial) if (dt.cd > 0 or dt.cd_axial > 0) else None
    added = AddedMass(dt.ca, dt.ca_axial) if (dt.ca > 0 or dt.ca_axial > 0) else None
    return LineType(dt.diameter, dt.mass_per_length, axial, ba, drag, added)


def coupled_point_ids(deck: Deck) -> list[int]:
    """Ids of the deck's coupled (caller-driven) points, in file order."""
    return [p.id for p in deck.points.values() if p.attachment == "coupled"]


def build_scene(deck: Deck, segments: int | None = None, motion=None) -> Scene:
    """A :class:`Scene` from a deck.

    Args:
        deck: from :func:`moorjax.io.read_deck`.
        segments: overrides every line's segment count.
        motion: optional :class:`moorjax.io.Motion` driving coupled points.
    """
    if segments is not None and (int(segments) != segments or segments < 1):
        raise InputError(f"--segments = {segments} must be an integer >= 1")
    opts = options_with_defaults(deck)
    depth, rho, g = float(opts["WtrDpth"]), float(opts["rho"]), float(opts["g"])
    if depth <= 0:
        raise InputError(f"{deck.path}: WtrDpth = {depth} m must be > 0")

    ends = {}
    for p in deck.points.values():
        if p.attachment == "coupled" and motion is not None and p.id in motion.positions:
            ends[p.id] = TabulatedPath(motion.t, motion.positions[p.id], motion.velocities[p.id])
        else:
            ends[p.id] = FixedEnd(p.position)

    lines, weights = [], []
    for dl in deck.lines:
        n = int(segments) if segments is not None else dl.n_segments
        dt = deck.line_types[dl.line_type]
        lt = _line_type(dt, dl.length, n)
        weights.append(float(lt.wet_weight(rho, g)))
        lines.append(Line(lt, dl.length, n, ends[dl.point_a], ends[dl.point_b], label=str(dl.id)))

    seabed = None
    if any(w > 0 for w in weights):
        mu = float(opts.get("FrictionCoefficient") or 0.0)
        friction = SeabedFriction(mu) if mu > 0 else None
        seabed = Seabed(float(opts["kBot"]), float(opts["cBot"]), friction)
    env = Environment(depth, rho, g, seabed=seabed)
    return Scene(lines, env)
