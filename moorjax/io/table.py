"""Reader for time tables: comma-separated files of a time column ``t`` and numbers.

One header row of column names, then one row per time; blank lines and lines
starting with ``#`` are skipped (so a ``# units: ...`` row is too). Column names
are matched case-insensitively and may be padded with spaces. The prescribed
motion (:mod:`moorjax.io.motion`) and measured tensions
(:func:`moorjax.identify.read_target`, :func:`moorjax.io.read_results`) are
such tables.

Reading is in two steps, so a caller can check the columns it needs before any
cell is parsed: :func:`read_table` reads the header, :meth:`Table.values` the
numbers. Every problem raises :class:`~moorjax.io.errors.InputError` naming
``file:line``, the column and the value.

Pure Python + numpy; no JAX.
"""

from __future__ import annotations

import csv
import io
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import InputError

__all__ = ["Table", "read_table"]

_FLOAT_RE = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?\Z")
_NONFINITE_RE = re.compile(r"[+-]?(?:nan|inf|infinity)\Z", re.IGNORECASE)


@dataclass(frozen=True)
class Table:
    """The header and the raw rows of a time table (see :func:`read_table`).

    Attributes:
        path: the file read.
        header_line: 1-based line number of the header row.
        header: the column names as written (spaces stripped).
        columns: lower-cased column name -> column index.
        rows: ``(line number, cells)`` of every data row.
    """

    path: str
    header_line: int
    header: tuple[str, ...]
    columns: dict[str, int]
    rows: tuple[tuple[int, tuple[str, ...]], ...]

    @property
    def found(self) -> str:
        """The column names, comma-separated (for messages)."""
        return ", ".join(self.header)

    def values(self) -> np.ndarray:
        """(rows, columns) float64 numbers of the data rows.

        Raises:
            InputError: fewer than two rows, a row with the wrong number of
                cells, a cell that is not a finite number, or times ``t`` that
                are not strictly increasing.
        """
        name, rows, ncol = self.path, self.rows, len(self.header)
        if len(rows) < 2:
            raise InputError(f"{name}: {len(rows)} data row(s); expected at least 2 (times and values)")
        data = np.empty((len(rows), ncol), dtype=np.float64)
        for i, (lineno, cells) in enumerate(rows):
            if len(cells) != ncol:
                raise InputError(
                    f"{name}:{lineno}: data row {i + 1} has {len(cells)} cells, expected {ncol} "
                    "(one per header column)"
                )
            for j, cell in enumerate(cells):
                where = f"{name}:{lineno}: data row {i + 1}, column {self.header[j]!r} = {cell!r}"
                if _NONFINITE_RE.match(cell):
                    raise InputError(f"{where} must be a finite number")
                if not _FLOAT_RE.match(cell):
                    raise InputError(f"{where} is not a number")
                value = float(cell)
                if not math.isfinite(value):
                    raise InputError(f"{where} must be a finite number")
                data[i, j] = value
        jt = self.columns["t"]
        bad = np.flatnonzero(~(np.diff(data[:, jt]) > 0))
        if bad.size:
            k = int(bad[0])
            raise InputError(
                f"{name}:{rows[k + 1][0]}: data row {k + 2}, column 't' = {rows[k + 1][1][jt]} s is not "
                f"greater than the previous time {rows[k][1][jt]} s (line {rows[k][0]}); times must be "
                "strictly increasing"
            )
        return data


    def by_column(self) -> dict[str, np.ndarray]:
        """``{column name as written ("t" for the time column): (rows,) values}`` (:meth:`values`)."""
        data = self.values()
        return {("t" if h.lower() == "t" else h): data[:, j] for j, h in enumerate(self.header)}


def row_numbers(path, lineno: int, raw: str, what: str) -> list[float]:
    """The finite numbers of one whitespace- or comma-separated row of a MoorDyn
    input file (current, wave and grid files); ``InputError`` names the file, the
    line, the row's meaning ``what`` and the bad token."""
    out = []
    for tok in raw.replace(",", " ").split():
        try:
            v = float(tok)
        except ValueError:
            raise InputError(f"{path}:{lineno}: {what}: {tok!r} is not a number (row {raw.strip()!r})") from None
        if not math.isfinite(v):
            raise InputError(f"{path}:{lineno}: {what}: {tok} must be a finite number")
        out.append(v)
    return out


def moordyn_file_lines(path: Path, origin: str, kind: str) -> list[str]:
    """The lines of a MoorDyn input file that a deck names by its fixed name
    (``kind``: "current", "wave"); ``origin`` is where the deck asked for it."""
    if not path.is_file():
        raise InputError(f"{origin}: the {kind} file {str(path)!r} does not exist (MoorDyn reads it "
                         "from the deck's folder under this fixed name)")
    return path.read_text(encoding="utf-8", errors="replace").splitlines()


def number_rows(path, lines: list[str], first: int, what: str):
    """``(line number, raw row, its numbers)`` for each non-blank line of ``lines``
    from line ``first`` (1-based) on, parsed by :func:`row_numbers`."""
    for lineno, raw in enumerate(lines[first - 1:], start=first):
        if raw.strip():
            yield lineno, raw, row_numbers(path, lineno, raw, what)


def read_table(path, expected: str = "t,...") -> Table:
    """Read the header and rows of a time table.

    Args:
        path: the CSV file (``str`` or :class:`os.PathLike`).
        expected: the header the caller expects (e.g. ``'t,P<id>_x,...'``),
            named in the message for an empty file.

    Raises:
        InputError: an empty file, a header column without a name, a column
            given twice, or no time column ``t``.
        OSError: the file cannot be read.
    """
    name = str(path)
    text = Path(path).read_text(encoding="utf-8-sig", errors="replace")
    records: list[tuple[int, tuple[str, ...]]] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        stripped = raw.strip()
        if not stripped or stripped.startswith("#"):
            continue
        cells = next(csv.reader(io.StringIO(raw)))
        records.append((lineno, tuple(c.strip() for c in cells)))
    if not records:
        raise InputError(f"{name}: the file is empty; expected a header row {expected!r} and data rows")

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
    if "t" not in columns:
        raise InputError(
            f"{name}:{header_line}: missing time column 't' [s]; found columns: {', '.join(header)}"
        )
    return Table(name, header_line, header, columns, tuple(records[1:]))
