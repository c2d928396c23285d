"""Reader for prescribed-motion CSV files (the path of each coupled point and body).

Format: a comma-separated file with one header row, then one row per time::

    t,P2_x,P2_y,P2_z,P2_vx,P2_vy,P2_vz
    0.00,-5.2,0.0,-70.0,3.14159,0.0,0.0
    0.01,-5.1686,0.0,-70.0,3.14153,0.0,0.0

* ``t`` [s]: strictly increasing, finite, at least two rows;
* for each requested point id ``<id>``: ``P<id>_x``, ``P<id>_y``, ``P<id>_z`` [m]
  (required) and optionally ``P<id>_vx``, ``P<id>_vy``, ``P<id>_vz`` [m/s]
  (all three or none);
* for each requested (coupled) body id ``<id>``: its 6-DOF pose
  ``B<id>_x``, ``B<id>_y``, ``B<id>_z`` [m] (reference point) and
  ``B<id>_roll``, ``B<id>_pitch``, ``B<id>_yaw`` [rad] (MoorDyn's angles, see
  :mod:`moorjax.io.frames`; radians as in MoorDyn's coupling calls, while a deck
  gives its r0, p0, y0 in degrees), and optionally all six rates
  ``B<id>_vx``, ``B<id>_vy``, ``B<id>_vz`` [m/s], ``B<id>_vroll``,
  ``B<id>_vpitch``, ``B<id>_vyaw`` [rad/s] (time derivatives of those
  coordinates).

Column names are matched case-insensitively and may be padded with spaces;
blank lines and lines starting with ``#`` are skipped.  Columns that are not
needed give an :class:`~moorjax.io.errors.InputWarning`.  Every problem raises
:class:`~moorjax.io.errors.InputError` naming ``file:line``, the column and
the value.

Pure Python + numpy; no JAX.
"""

from __future__ import annotations

import csv
import io
import math
import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import InputError, InputWarning

__all__ = ["Motion", "read_motion"]

_POSE = ("x", "y", "z", "roll", "pitch", "yaw")
_FLOAT_RE = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?\Z")
_NONFINITE_RE = re.compile(r"[+-]?(?:nan|inf|infinity)\Z", re.IGNORECASE)


@dataclass(frozen=True)
class Motion:
    """Prescribed motion of coupled points and bodies, sampled at times ``t``.

    Arrays are float64 and read-only.

    Attributes:
        t: (nt,) sample times [s], strictly increasing, finite, nt >= 2.
        positions: point id -> (nt, 3) positions x, y, z [m].
        velocities: point id -> (nt, 3) velocities [m/s], or ``None`` when the
            file has no velocity columns for that point.
        path: the file read.
        body_poses: body id -> (nt, 6) poses x, y, z [m], roll, pitch, yaw [rad].
        body_rates: body id -> (nt, 6) their time derivatives [m/s, rad/s], or
            ``None`` when the file has no rate columns for that body.
    """

    t: np.ndarray
    positions: dict[int, np.ndarray]
    velocities: dict[int, np.ndarray | None]
    path: str
    body_poses: dict[int, np.ndarray] = field(default_factory=dict)
    body_rates: dict[int, np.ndarray | None] = field(default_factory=dict)


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=np.float64)
    a.flags.writeable = False
    return a


def _ids(values, what: str) -> list[int]:
    ids: list[int] = []
    for i in values:
        if isinstance(i, bool) or not isinstance(i, (int, np.integer)):
            raise TypeError(f"{what} must be integers, got {i!r}")
        if int(i) not in ids:
            ids.append(int(i))
    return ids


def read_motion(path, point_ids: Sequence[int], body_ids: Sequence[int] = ()) -> Motion:
    """Read a prescribed-motion CSV for the given coupled point and body ids.

    Args:
        path: the CSV file (``str`` or :class:`os.PathLike`).
        point_ids: ids of the points whose motion is needed (e.g. the coupled
            points of a deck); duplicates are ignored.
        body_ids: ids of the bodies whose 6-DOF motion is needed (the coupled
            bodies of a deck); duplicates are ignored.

    Returns:
        The :class:`Motion`.

    Raises:
        InputError: empty file, missing ``t``, point or body columns (the
            message lists what is missing and what was found), partial velocity
            triplets or body-rate sextets, duplicated columns, rows with the wrong number of cells,
            non-numeric or non-finite cells, fewer than two rows, or times that
            are not strictly increasing.
        OSError: the file cannot be read.
    """
    ids = _ids(point_ids, "point_ids")
    bids = _ids(body_ids, "body_ids")

    name = str(path)
    text = Path(path).read_text(encoding="utf-8-sig", errors="replace")

    # (file line number, cells) for every non-blank, non-comment line
    records: list[tuple[int, list[str]]] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        stripped = raw.strip()
        if not stripped or stripped.startswith("#"):
            continue
        cells = next(csv.reader(io.StringIO(raw)))
        records.append((lineno, [c.strip() for c in cells]))
    if not records:
        raise InputError(f"{name}: the file is empty; expected a header row 't,P<id>_x,...' and data rows")

    header_line, header = records[0]
    columns: dict[str, int] = {}
    for j, col in enumerate(header):
        key = col.lower()
        if not key:
            raise InputError(f"{name}:{header_line}: header column {j + 1} has no name")
        if key in columns:
            raise InputError(
                f"{name}:{header_line}: column {col!r} appears twice (columns {columns[key] + 1} and {j + 1})"
            )
        columns[key] = j
    found = ", ".join(header)

    if "t" not in columns:
        raise InputError(f"{name}:{header_line}: missing time column 't' [s]; found columns: {found}")

    wanted: list[str] = ["t"]
    pos_cols: dict[int, list[int]] = {}
    vel_cols: dict[int, list[int] | None] = {}
    missing: list[str] = []
    for pid in ids:
        names = [f"P{pid}_{c}" for c in ("x", "y", "z")]
        lacking = [n for n in names if n.lower() not in columns]
        missing.extend(lacking)
        if not lacking:
            pos_cols[pid] = [columns[n.lower()] for n in names]
        wanted.extend(names)
        vnames = [f"P{pid}_{c}" for c in ("vx", "vy", "vz")]
        present = [n for n in vnames if n.lower() in columns]
        if present and len(present) < 3:
            absent = [n for n in vnames if n.lower() not in columns]
            raise InputError(
                f"{name}:{header_line}: point {pid} has velocity column(s) {', '.join(present)} "
                f"but not {', '.join(absent)}; give all three of {', '.join(vnames)} [m/s] or none"
            )
        vel_cols[pid] = [columns[n.lower()] for n in vnames] if present else None
        wanted.extend(present)
    if missing:
        raise InputError(
            f"{name}:{header_line}: missing column(s) {', '.join(missing)} [m] for point id(s) "
            f"{', '.join(str(i) for i in ids)}; found columns: {found}"
        )

    pose_cols: dict[int, list[int]] = {}
    rate_cols: dict[int, list[int] | None] = {}
    missing = []
    for bid in bids:
        names = [f"B{bid}_{c}" for c in _POSE]
        lacking = [n for n in names if n.lower() not in columns]
        missing.extend(lacking)
        if not lacking:
            pose_cols[bid] = [columns[n.lower()] for n in names]
        wanted.extend(names)
        rnames = [f"B{bid}_v{c}" for c in _POSE]
        present = [n for n in rnames if n.lower() in columns]
        if present and len(present) < 6:
            absent = [n for n in rnames if n.lower() not in columns]
            raise InputError(
                f"{name}:{header_line}: body {bid} has rate column(s) {', '.join(present)} "
                f"but not {', '.join(absent)}; give all six of {', '.join(rnames)} "
                "[m/s, rad/s] or none"
            )
        rate_cols[bid] = [columns[n.lower()] for n in rnames] if present else None
        wanted.extend(present)
    if missing:
        raise InputError(
            f"{name}:{header_line}: missing column(s) {', '.join(missing)} for body id(s) "
            f"{', '.join(str(i) for i in bids)} (x, y, z [m] of the reference point; roll, pitch, "
            f"yaw [rad]); found columns: {found}"
        )

    extra = [col for col in header if col.lower() not in {w.lower() for w in wanted}]
    if extra:
        requested = f"requested point ids: {', '.join(str(i) for i in ids) or 'none'}"
        if bids:
            requested += f"; body ids: {', '.join(str(i) for i in bids)}"
        warnings.warn(
            f"{name}:{header_line}: column(s) {', '.join(extra)} not used ({requested})",
            InputWarning,
            stacklevel=2,
        )

    rows = records[1:]
    if len(rows) < 2:
        raise InputError(f"{name}: {len(rows)} data row(s); expected at least 2 (times and positions)")

    ncol = len(header)
    data = np.empty((len(rows), ncol), dtype=np.float64)
    for i, (lineno, cells) in enumerate(rows):
        if len(cells) != ncol:
            raise InputError(
                f"{name}:{lineno}: data row {i + 1} has {len(cells)} cells, expected {ncol} (one per header column)"
            )
        for j, cell in enumerate(cells):
            if _NONFINITE_RE.match(cell):
                raise InputError(
                    f"{name}:{lineno}: data row {i + 1}, column {header[j]!r} = {cell!r} must be a finite number"
                )
            if not _FLOAT_RE.match(cell):
                raise InputError(f"{name}:{lineno}: data row {i + 1}, column {header[j]!r} = {cell!r} is not a number")
            value = float(cell)
            if not math.isfinite(value):
                raise InputError(
                    f"{name}:{lineno}: data row {i + 1}, column {header[j]!r} = {cell!r} must be a finite number"
                )
            data[i, j] = value

    t = data[:, columns["t"]]
    steps = np.diff(t)
    bad = np.flatnonzero(~(steps > 0))
    if bad.size:
        k = int(bad[0])
        raise InputError(
            f"{name}:{rows[k + 1][0]}: data row {k + 2}, column 't' = {rows[k + 1][1][columns['t']]} s is not greater than "
            f"the previous time {rows[k][1][columns['t']]} s (line {rows[k][0]}); times must be strictly increasing"
        )

    positions = {pid: _frozen(data[:, pos_cols[pid]]) for pid in ids}
    velocities = {pid: (None if vel_cols[pid] is None else _frozen(data[:, vel_cols[pid]])) for pid in ids}
    body_poses = {bid: _frozen(data[:, pose_cols[bid]]) for bid in bids}
    body_rates = {bid: (None if rate_cols[bid] is None else _frozen(data[:, rate_cols[bid]])) for bid in bids}
    return Motion(t=_frozen(t), positions=positions, velocities=velocities, path=name,
                  body_poses=body_poses, body_rates=body_rates)
