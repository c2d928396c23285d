"""Bundled examples: MoorDyn v2 decks with the fairlead motion each was made for.

- ``oc3_catenary``: an OC3-style 902 m catenary chain-like line in 320 m of water,
  135 m on the seabed (the project's reference case A), its fairlead surging
  5 m with a 10 s period.
- ``taut_polyester``: a 110 m taut, slightly buoyant polyester-like line in 80 m
  of water (reference case B; linear EA as in the MoorDyn deck), its fairlead
  surging 2 m with an 8 s period: slack and snap loads every cycle.

Both come from the project's shared reference set (MoorDyn 2.7.2 decks). Each
deck ships with ``<name>_motion.csv`` (written by :mod:`moorjax.examples.motions`
from the decks' sine paths), which ``moorjax simulate example:NAME`` uses unless
``--motion`` says otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources


@dataclass(frozen=True)
class Example:
    """A bundled example: its deck, its motion and what it shows."""

    name: str
    shows: str
    #: fairlead surge x(t) = x0 + amplitude·sin(2πt/period), y, z fixed [m, s]
    point: int
    x0: float
    y0: float
    z0: float
    amplitude: float
    period: float

    @property
    def deck(self) -> str:
        return _path(f"{self.name}.dat")

    @property
    def motion(self) -> str:
        return _path(f"{self.name}_motion.csv")


_EXAMPLES = (
    Example(
        "oc3_catenary",
        "OC3-style 902 m chain catenary, 320 m deep, 135 m on the seabed; fairlead "
        "surge 5 m / 10 s: tension 0.1-1.9 MN, the touchdown point moving",
        point=2, x0=-5.2, y0=0.0, z0=-70.0, amplitude=5.0, period=10.0,
    ),
    Example(
        "taut_polyester",
        "110 m taut buoyant polyester-like line, 80 m deep; fairlead surge 2 m / 8 s: "
        "goes slack and snaps to ~2 MN every cycle",
        point=2, x0=0.0, y0=0.0, z0=-5.0, amplitude=2.0, period=8.0,
    ),
)

EXAMPLES = tuple(e.name for e in _EXAMPLES)


def _path(filename: str) -> str:
    return str(resources.files(__name__).joinpath(filename))


def example(name: str) -> Example:
    """The bundled example ``name`` (raises ``ValueError`` listing the valid names)."""
    for e in _EXAMPLES:
        if e.name == name:
            return e
    raise ValueError(f"unknown example {name!r}; bundled examples: {', '.join(EXAMPLES)}")


def example_path(name: str) -> str:
    """Filesystem path of a bundled deck (``name`` without ``.dat``)."""
    return example(name).deck


def example_motion_path(name: str) -> str:
    """Filesystem path of the motion CSV a bundled deck was made for."""
    return example(name).motion
