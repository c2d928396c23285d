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

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .errors import InputError, InputWarning
from .table import Table, read_table

__all__ = ["Motion", "read_motion"]


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


@dataclass(frozen=True)
class _Kind:
    """How the columns of one kind of object (point or body) are named and described."""

    noun: str  # "point", "body"
    prefix: str  # column prefix, "P" / "B"
    coords: tuple[str, ...]  # position columns; the rates are "v" + each
    rate_word: str  # "velocity" / "rate"
    count_word: str  # "three" / "six"
    rate_unit: str
    missing_note: str  # after the missing column names; {ids} is filled in


_POINT = _Kind("point", "P", ("x", "y", "z"), "velocity", "three", "[m/s]", " [m] for point id(s) {ids}")
_BODY = _Kind("body", "B", ("x", "y", "z", "roll", "pitch", "yaw"), "rate", "six", "[m/s, rad/s]",
              " for body id(s) {ids} (x, y, z [m] of the reference point; roll, pitch, yaw [rad])")


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
    table = read_table(path, "t,P<id>_x,...")
    pos_cols, vel_cols, wanted = _columns(table, _POINT, ids)
    pose_cols, rate_cols, body_wanted = _columns(table, _BODY, bids)
    wanted = {"t", *wanted, *body_wanted}

    extra = [col for col in table.header if col.lower() not in wanted]
    if extra:
        requested = f"requested point ids: {', '.join(str(i) for i in ids) or 'none'}"
        if bids:
            requested += f"; body ids: {', '.join(str(i) for i in bids)}"
        warnings.warn(
            f"{table.path}:{table.header_line}: column(s) {', '.join(extra)} not used ({requested})",
            InputWarning,
            stacklevel=2,
        )

    data = table.values()

    def take(cols):
        return None if cols is None else _frozen(data[:, cols])

    return Motion(
        t=_frozen(data[:, table.columns["t"]]),
        positions={pid: take(pos_cols[pid]) for pid in ids},
        velocities={pid: take(vel_cols[pid]) for pid in ids},
        path=table.path,
        body_poses={bid: take(pose_cols[bid]) for bid in bids},
        body_rates={bid: take(rate_cols[bid]) for bid in bids},
    )


def _columns(table: Table, kind: _Kind, ids: list[int]):
    """Column indices of each object's position and (optional) rate columns, and
    the lower-cased names of all the columns used."""
    columns, where = table.columns, f"{table.path}:{table.header_line}"
    pos_cols: dict[int, list[int]] = {}
    rate_cols: dict[int, list[int] | None] = {}
    wanted: list[str] = []
    missing: list[str] = []
    for i in ids:
        names = [f"{kind.prefix}{i}_{c}" for c in kind.coords]
        lacking = [n for n in names if n.lower() not in columns]
        missing.extend(lacking)
        if not lacking:
            pos_cols[i] = [columns[n.lower()] for n in names]
        wanted.extend(names)
        rnames = [f"{kind.prefix}{i}_v{c}" for c in kind.coords]
        present = [n for n in rnames if n.lower() in columns]
        if present and len(present) < len(rnames):
            absent = [n for n in rnames if n.lower() not in columns]
            raise InputError(
                f"{where}: {kind.noun} {i} has {kind.rate_word} column(s) {', '.join(present)} "
                f"but not {', '.join(absent)}; give all {kind.count_word} of {', '.join(rnames)} "
                f"{kind.rate_unit} or none"
            )
        rate_cols[i] = [columns[n.lower()] for n in rnames] if present else None
        wanted.extend(present)
    if missing:
        note = kind.missing_note.format(ids=", ".join(str(i) for i in ids))
        raise InputError(f"{where}: missing column(s) {', '.join(missing)}{note}; found columns: {table.found}")
    return pos_cols, rate_cols, [w.lower() for w in wanted]
