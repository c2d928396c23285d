"""Reader for MoorDyn-C v2's bathymetry file (the ``SeafloorFile`` option).

MoorDyn v2 documents the file in ``docs/inputs.rst`` ("Seafloor/Bathymetry
File"): the first line holds the numbers of grid points along x and y, the
second the x coordinates [m], the third the y coordinates [m], and every
further line ``x y z``: the seabed height z [m] (z up, 0 at the still surface,
so negative) at grid point (x, y), whose x and y must be values of lines 2 and
3. Outside the grid the depth of the nearest grid edge holds; inside, MoorDyn
interpolates bilinearly.

MoorDyn resolves a relative path against its working directory (its own tests
run from ``tests/`` and name ``Mooring/3D_seafloor/...``); moorjax looks next
to the deck first and then in the deck folder's parents.

Pure Python + numpy; no JAX.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import InputError

__all__ = ["DeckSeafloor", "read_seafloor", "find_seafloor_file"]


@dataclass(frozen=True)
class DeckSeafloor:
    """A bathymetry grid: ``z[i, j]`` is the seabed height [m] at (x[i], y[j])."""

    path: str
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray


def find_seafloor_file(token: str, deck_path: str) -> Path | None:
    p = Path(token)
    if p.is_absolute():
        return p if p.is_file() else None
    folder = Path(deck_path).resolve().parent
    for base in (folder, *folder.parents):
        if (base / p).is_file():
            return base / p
    return None


def _floats(path, lineno, raw, what, count=None):
    try:
        vals = [float(t) for t in raw.replace(",", " ").split()]
    except ValueError:
        raise InputError(f"{path}:{lineno}: {what}: {raw.strip()!r} is not a list of numbers") from None
    if not all(math.isfinite(v) for v in vals):
        raise InputError(f"{path}:{lineno}: {what}: values must be finite numbers")
    if count is not None and len(vals) != count:
        raise InputError(f"{path}:{lineno}: {what}: {len(vals)} values, expected {count}")
    return vals


def read_seafloor(path) -> DeckSeafloor:
    """Read a MoorDyn-C bathymetry file; see the module docstring."""
    path = Path(path)
    lines = [(i, ln) for i, ln in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(),
                                             start=1) if ln.strip()]
    if len(lines) < 4:
        raise InputError(f"{path}: {len(lines)} non-blank lines; a bathymetry file has 'nx ny', the x "
                         "values, the y values, then 'x y z' rows")
    (l0, r0), (l1, r1), (l2, r2) = lines[:3]
    nx, ny = _floats(path, l0, r0, "'num_x_points num_y_points'", 2)
    if nx != int(nx) or ny != int(ny) or nx < 1 or ny < 1:
        raise InputError(f"{path}:{l0}: grid sizes {r0.strip()!r} must be whole numbers >= 1")
    nx, ny = int(nx), int(ny)
    xs = np.asarray(_floats(path, l1, r1, "x grid values [m]", nx))
    ys = np.asarray(_floats(path, l2, r2, "y grid values [m]", ny))
    for arr, name, ln in ((xs, "x", l1), (ys, "y", l2)):
        if arr.size > 1 and not np.all(np.diff(arr) > 0):
            raise InputError(f"{path}:{ln}: the {name} grid values [m] must be strictly increasing")
    z = np.full((nx, ny), np.nan)
    for lineno, raw in lines[3:]:
        x, y, zz = _floats(path, lineno, raw, "'x y z' row", 3)
        i = np.flatnonzero(np.isclose(xs, x, rtol=0, atol=1e-9 * max(1.0, abs(x))))
        j = np.flatnonzero(np.isclose(ys, y, rtol=0, atol=1e-9 * max(1.0, abs(y))))
        if i.size != 1 or j.size != 1:
            raise InputError(f"{path}:{lineno}: point ({x!r}, {y!r}) m is not on the grid of lines "
                             f"{l1}-{l2}; every row's x and y must be grid values")
        z[i[0], j[0]] = zz
    missing = np.argwhere(np.isnan(z))
    if missing.size:
        i, j = missing[0]
        raise InputError(f"{path}: no depth for grid point ({float(xs[i])!r}, {float(ys[j])!r}) m "
                         f"({len(missing)} of {nx * ny} grid points missing)")
    return DeckSeafloor(str(path), xs, ys, z)
