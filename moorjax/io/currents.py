"""Readers for MoorDyn-C v2's current files (the ``Currents`` option).

MoorDyn v2 documents the option and its files in ``docs/inputs.rst``
(OPTIONS: ``Currents``) and ``docs/waterkinematics.rst`` ("Currents
(MoorDyn-C)"); each file sits in the deck's folder under a fixed name:

* ``Currents = 1`` (steady currents grid): ``current_profile.txt``. The first
  three lines are ignored; every further line is ``z ux [uy [uz]]`` with z [m]
  (z up, 0 at the still surface) and the velocity [m/s]; a missing uy or uz
  is 0. The velocity at a point is linearly interpolated in z between the
  nearest rows and held at the end values beyond them.
* ``Currents = 2`` (dynamic currents grid): ``current_profile_dynamic.txt``.
  Lines 1-4 are ignored, line 5 lists the depths z [m], line 6 is ignored, and
  every further line is ``t ux_1..ux_k [uy_1..uy_k [uz_1..uz_k]]`` (time [s],
  then all x components by depth, then y, then z; missing components are 0).
  Linear in z and t, held at the ends of both.
* ``Currents = 3, 4`` are not implemented in MoorDyn either.
* ``Currents = 5`` (4-D current grid): ``current_profile_4d.txt``
  (``docs/waterkinematics.rst``, "Currents = 5 (4D Current Grid)"). Line 1 is
  ``nx ny nz nt``, lines 2-5 the grid's x [m], y [m], z [m] and t [s] values,
  and every further line is ``x y z t ux uy uz``: the velocity [m/s] at one
  grid point, in any order. moorjax matches the coordinates to the grid by
  value and needs every grid point exactly once. Quadrilinear, held at the
  grid's edges (:class:`moorjax.model.GridCurrent`).

  Where MoorDyn's code (``construct4DCurrentGrid``, v2.7, commit 319ff99)
  differs from its docs, moorjax follows the docs and says so here: (1) the
  code starts reading rows at line 7, so the row on line 6 is dropped and its
  grid point keeps the velocity 0 (in MoorDyn's public ``wavekin_2`` and
  ``wavekin_4`` files the corner x = -50, y = -2, z = -30 m at t = 0); (2) it
  finds a row's grid point by comparing the coordinates as *text* with the
  header's, an unmatched one silently meaning the first grid value; (3) it
  resamples the times at the smallest time step from t = 0 and repeats the
  table past its last time. A file whose rows start on line 6, written with
  the header's spelling and with evenly spaced times from 0, is read alike by
  both except for (1).

Pure Python + numpy; no JAX.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import InputError
from .table import moordyn_file_lines, number_rows, row_numbers

__all__ = ["DeckCurrent", "read_current_profile", "read_dynamic_current_profile", "read_current_grid_4d",
           "CURRENT_FILES"]

#: ``Currents`` option value -> the file MoorDyn-C reads from the deck's folder.
CURRENT_FILES = {1: "current_profile.txt", 2: "current_profile_dynamic.txt", 5: "current_profile_4d.txt"}


@dataclass(frozen=True)
class DeckCurrent:
    """A current read from a MoorDyn current file.

    Attributes:
        mode: the deck's ``Currents`` value (1 steady profile, 2 dynamic profile,
            5 4-D grid).
        path: the file it came from.
        z: (k,) strictly increasing heights [m].
        velocity: (k, 3) [m/s] for mode 1; (n_t, k, 3) [m/s] for mode 2;
            (nx, ny, k, n_t, 3) [m/s] for mode 5.
        t: (n_t,) strictly increasing times [s] for modes 2 and 5, else ``None``.
        x, y: (nx,), (ny,) strictly increasing grid coordinates [m] for mode 5,
            else ``None``.
    """

    mode: int
    path: str
    z: np.ndarray
    velocity: np.ndarray
    t: np.ndarray | None = None
    x: np.ndarray | None = None
    y: np.ndarray | None = None


def _check_increasing(path, linenos, values, name, unit):
    for i in range(1, len(values)):
        if not values[i] > values[i - 1]:
            raise InputError(
                f"{path}:{linenos[i]}: {name} = {values[i]!r} {unit} is not greater than the previous "
                f"{values[i - 1]!r} {unit}; MoorDyn interpolates in {name} and needs them strictly "
                "increasing")


def _read_lines(path: Path, origin: str) -> list[str]:
    return moordyn_file_lines(path, origin, "current")


def read_current_profile(path, origin: str = "") -> DeckCurrent:
    """Read a ``current_profile.txt`` (``Currents = 1``); see the module docstring.

    Args:
        path: the file.
        origin: where the deck asked for it (``deck:line``), for messages.
    """
    path = Path(path)
    lines = _read_lines(path, origin or str(path))
    z, u, where = [], [], []
    for lineno, raw, vals in number_rows(str(path), lines, 4, "steady current row 'z ux [uy [uz]]'"):
        if len(vals) < 2:
            raise InputError(f"{path}:{lineno}: steady current row {raw.strip()!r} has {len(vals)} "
                             "number(s); expected 'z [m] ux [m/s] [uy [m/s] [uz [m/s]]]'")
        z.append(vals[0])
        u.append((vals[1:4] + [0.0, 0.0])[:3])
        where.append(lineno)
    if not z:
        raise InputError(f"{path}: no current rows after the 3 header lines; expected rows "
                         "'z [m] ux [m/s] [uy [m/s] [uz [m/s]]]'")
    _check_increasing(str(path), where, z, "z", "m")
    return DeckCurrent(1, str(path), np.asarray(z, float), np.asarray(u, float))


def read_dynamic_current_profile(path, origin: str = "") -> DeckCurrent:
    """Read a ``current_profile_dynamic.txt`` (``Currents = 2``); see the module docstring."""
    path = Path(path)
    lines = _read_lines(path, origin or str(path))
    if len(lines) < 7:
        raise InputError(f"{path}: {len(lines)} lines; a dynamic current file has 4 ignored lines, "
                         "the depths on line 5, an ignored line 6 and then 't ux.. [uy.. [uz..]]' rows")
    z = row_numbers(str(path), 5, lines[4], "depths row (line 5)")
    if not z:
        raise InputError(f"{path}:5: the depths row is empty; expected the heights z [m] of the profile")
    _check_increasing(str(path), [5] * len(z), z, "z", "m")
    k = len(z)
    ts, us, where = [], [], []
    for lineno, _, vals in number_rows(str(path), lines, 7, "dynamic current row"):
        if len(vals) not in (1 + k, 1 + 2 * k, 1 + 3 * k):
            raise InputError(
                f"{path}:{lineno}: dynamic current row has {len(vals)} numbers; with {k} depths expected "
                f"{1 + k} (t, ux), {1 + 2 * k} (t, ux, uy) or {1 + 3 * k} (t, ux, uy, uz)")
        comp = np.zeros((3, k))
        n_c = (len(vals) - 1) // k
        comp[:n_c] = np.asarray(vals[1:]).reshape(n_c, k)
        ts.append(vals[0])
        us.append(comp.T)
        where.append(lineno)
    if not ts:
        raise InputError(f"{path}: no time rows after line 6")
    _check_increasing(str(path), where, ts, "t", "s")
    return DeckCurrent(2, str(path), np.asarray(z, float), np.asarray(us, float), np.asarray(ts, float))


def read_current_grid_4d(path, origin: str = "") -> DeckCurrent:
    """Read a ``current_profile_4d.txt`` (``Currents = 5``); see the module docstring."""
    path = Path(path)
    lines = _read_lines(path, origin or str(path))
    if len(lines) < 6:
        raise InputError(f"{path}: {len(lines)} lines; a 4-D current file has 'nx ny nz nt' on line 1, "
                         "the x, y, z, t grid values on lines 2-5 and then 'x y z t ux uy uz' rows")
    counts = row_numbers(str(path), 1, lines[0], "grid size row 'nx ny nz nt'")
    if len(counts) < 4 or any(c < 1 or c != int(c) for c in counts[:4]):
        raise InputError(f"{path}:1: grid size row {lines[0].strip()!r}; expected four whole numbers "
                         "'nx ny nz nt' >= 1")
    sizes = [int(c) for c in counts[:4]]
    axes = []
    for k, (name, unit, n) in enumerate(zip("xyzt", ("m", "m", "m", "s"), sizes)):
        vals = row_numbers(str(path), 2 + k, lines[1 + k], f"grid {name} row (line {2 + k})")
        if len(vals) != n:
            raise InputError(f"{path}:{2 + k}: grid {name} row has {len(vals)} values; line 1 says "
                             f"n{name} = {n}")
        _check_increasing(str(path), [2 + k] * n, vals, name, unit)
        axes.append(np.asarray(vals, float))
    u = np.zeros(tuple(sizes) + (3,))
    seen = np.zeros(tuple(sizes), dtype=int)
    for lineno, _, vals in number_rows(str(path), lines, 6, "4-D current row 'x y z t ux uy uz'"):
        if len(vals) != 7:
            raise InputError(f"{path}:{lineno}: 4-D current row has {len(vals)} numbers; expected 7: "
                             "'x [m] y [m] z [m] t [s] ux [m/s] uy [m/s] uz [m/s]'")
        index = []
        for name, unit, ax, v in zip("xyzt", ("m", "m", "m", "s"), axes, vals[:4]):
            tol = 1e-9 * max(1.0, float(np.max(np.abs(ax))))
            hit = np.flatnonzero(np.abs(ax - v) <= tol)
            if hit.size == 0:
                raise InputError(f"{path}:{lineno}: {name} = {v!r} {unit} is not one of the grid's {name} "
                                 f"values on line {2 + 'xyzt'.index(name)}")
            index.append(int(hit[0]))
        index = tuple(index)
        if seen[index]:
            raise InputError(f"{path}:{lineno}: grid point (x, y, z, t) = {tuple(vals[:4])} is given again "
                             f"(first on line {seen[index]})")
        seen[index] = lineno
        u[index] = vals[4:]
    missing = np.argwhere(seen == 0)
    if missing.size:
        first = tuple(float(ax[i]) for ax, i in zip(axes, missing[0]))
        raise InputError(f"{path}: {len(missing)} of the {seen.size} grid points have no row, the first "
                         f"(x, y, z, t) = {first}; give one 'x y z t ux uy uz' row for each")
    x, y, z, t = axes
    return DeckCurrent(5, str(path), z, u, t, x, y)
