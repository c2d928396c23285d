"""Bundled example decks (MoorDyn v2 format).

- ``oc3_catenary``: an OC3-style 902 m catenary chain-like line in 320 m of water,
  135 m on the seabed (the project's reference case A).
- ``taut_polyester``: a 110 m taut, slightly buoyant polyester-like line in 80 m
  of water (reference case B; linear EA as in the MoorDyn deck).

Both come from the project's shared reference set (MoorDyn 2.7.2 decks).
"""

from __future__ import annotations

from importlib import resources

EXAMPLES = ("oc3_catenary", "taut_polyester")


def example_path(name: str) -> str:
    """Filesystem path of a bundled deck (``name`` without ``.dat``)."""
    if name not in EXAMPLES:
        raise ValueError(f"unknown example {name!r}; bundled examples: {', '.join(EXAMPLES)}")
    return str(resources.files(__name__).joinpath(f"{name}.dat"))
