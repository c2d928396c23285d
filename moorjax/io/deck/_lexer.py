"""Tokenising a deck: sections, rows, comments, and the field parsers every section uses.

A :class:`Context` carries the file name and the warnings collected so far and
builds the ``file:line:`` messages; :func:`split_sections` cuts the text into
its front matter and :class:`Section` s of tokenised :class:`Row` s; the field
parsers (:func:`number`, :func:`integer`, :func:`require_columns`, ...) turn
one token into a validated value or raise an :class:`~moorjax.io.errors.InputError`
naming the field, the value as written, its unit and what is expected.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ..errors import InputError


# (kind, keywords) in matching priority order; a header is the first kind whose
# keyword occurs in the upper-cased header line.
_SECTION_KEYWORDS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("LINE TYPES", ("LINE TYPES", "LINE DICTIONARY")),
    ("ROD TYPES", ("ROD TYPES", "ROD DICTIONARY")),
    ("BODIES", ("BODIES", "BODY LIST", "BODY PROPERTIES")),
    ("POINTS", ("POINTS", "POINT LIST", "POINT PROPERTIES", "CONNECTION PROPERTIES", "NODE PROPERTIES")),
    ("RODS", ("RODS", "ROD LIST", "ROD PROPERTIES")),
    ("LINES", ("LINES", "LINE LIST", "LINE PROPERTIES")),
    ("OPTIONS", ("OPTIONS",)),
    ("FAILURE", ("FAILURE",)),
    ("EXTERNAL LOADS", ("EXTERNAL LOADS",)),
    ("CONTROL", ("CONTROL",)),
    ("OUTPUTS", ("OUTPUT",)),
)

# sections whose rows follow the header directly (no names/units lines)
_NO_TABLE_HEADER = {"OPTIONS", "OUTPUTS", "UNKNOWN"}

COMMENT_RE = re.compile(r"[!#%]")
FLOAT_RE = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?\Z")
NONFINITE_RE = re.compile(r"[+-]?(?:nan|inf|infinity)\Z", re.IGNORECASE)


@dataclass
class Row:
    """One data row: its 1-based line number, its tokens (comment removed) and its text."""

    lineno: int
    tokens: list[str]
    text: str


@dataclass
class Section:
    """A section: its kind (``'LINE TYPES'``, ...), header text and line, its rows,
    and how many of its two table-header lines are still to be skipped."""

    kind: str
    header: str
    lineno: int
    rows: list[Row]
    pending_headers: int


class Context:
    """File name + collected warnings; builds ``file:line:`` messages."""

    def __init__(self, path: str):
        self.path = path
        self.warnings: list[str] = []

    def error(self, lineno: int | None, msg: str) -> InputError:
        where = f"{self.path}:{lineno}" if lineno is not None else self.path
        return InputError(f"{where}: {msg}")

    def warn(self, lineno: int | None, msg: str) -> None:
        where = f"{self.path}:{lineno}" if lineno is not None else self.path
        self.warnings.append(f"{where}: {msg}")


def _classify_header(upper: str) -> str | None:
    for kind, keywords in _SECTION_KEYWORDS:
        if any(k in upper for k in keywords):
            return kind
    return None


def _looks_like_data(tokens: list[str]) -> bool:
    return sum(1 for t in tokens if FLOAT_RE.match(t)) >= 2


def split_sections(text: str, ctx: Context) -> tuple[str, dict[str, Section]]:
    """Split the deck into front matter and sections (rows are tokenised)."""
    front: list[str] = []
    sections: dict[str, Section] = {}
    current: Section | None = None
    unknown_count = 0
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.rstrip()
        if "---" in line:
            upper = line.upper()
            if "NEED THIS LINE" in upper:
                break
            kind = _classify_header(upper)
            if kind is None:
                if current is None and not sections:
                    front.append(line)  # e.g. "---- MoorDyn Input File ----"
                    continue
                label = line.strip("- \t") or line.strip()
                ctx.warn(lineno, f"unknown section {label!r}: its rows are ignored")
                unknown_count += 1
                current = Section("UNKNOWN", label, lineno, [], 0)
                sections[f"UNKNOWN#{unknown_count}"] = current
                continue
            if kind in sections:
                first = sections[kind]
                raise ctx.error(
                    lineno,
                    f"second {kind} section (the first starts at line {first.lineno}); "
                    "expected each section once",
                )
            pending = 0 if kind in _NO_TABLE_HEADER else 2
            current = Section(kind, line.strip("- \t"), lineno, [], pending)
            sections[kind] = current
            continue
        if current is None:
            front.append(line)
            continue
        content = COMMENT_RE.split(line, maxsplit=1)[0]
        tokens = content.split()
        if not tokens:
            continue
        if current.pending_headers > 0:
            current.pending_headers -= 1
            if _looks_like_data(tokens):
                which = "column-names" if current.pending_headers == 1 else "units"
                ctx.warn(
                    lineno,
                    f"{current.kind}: expected the {which} header line here but found "
                    f"what looks like a data row ({content.strip()!r}); it is skipped "
                    "(each table section starts with two header lines)",
                )
            continue
        current.rows.append(Row(lineno, tokens, line))
    while front and not front[0].strip():
        front.pop(0)
    while front and not front[-1].strip():
        front.pop()
    return "\n".join(front), sections


def _fmt(token: str, unit: str) -> str:
    return f"{token} {unit}" if unit else token


def is_number(token: str) -> bool:
    return bool(FLOAT_RE.match(token))


def number(
    ctx: Context, row: Row, index: int, what: str, field: str, unit: str, constraint: str = "any"
) -> float:
    """Parse ``row.tokens[index]`` as a finite float obeying ``constraint``."""
    token = row.tokens[index]
    if NONFINITE_RE.match(token):
        raise ctx.error(row.lineno, f"{what}: {field} = {_fmt(token, unit)} must be a finite number")
    if not FLOAT_RE.match(token):
        raise ctx.error(
            row.lineno, f"{what}: {field} = {token!r} is not a number; expected a number in {unit or '[-]'}"
        )
    value = float(token)
    if not math.isfinite(value):
        raise ctx.error(row.lineno, f"{what}: {field} = {_fmt(token, unit)} must be a finite number")
    check_constraint(ctx, row.lineno, what, field, token, unit, value, constraint)
    return value


def check_constraint(ctx, lineno, what, field, token, unit, value, constraint):
    if constraint == "pos" and not value > 0:
        raise ctx.error(lineno, f"{what}: {field} = {_fmt(token, unit)} must be > 0")
    if constraint == "nonneg" and not value >= 0:
        raise ctx.error(lineno, f"{what}: {field} = {_fmt(token, unit)} must be >= 0")


def integer(ctx: Context, row: Row, index: int, what: str, field: str, constraint: str = "pos") -> int:
    """Parse ``row.tokens[index]`` as an integer (``'160'``, also ``'160.0'``)."""
    token = row.tokens[index]
    value: float | None = None
    if FLOAT_RE.match(token):
        value = float(token)
    if value is None or not math.isfinite(value) or value != int(value):
        raise ctx.error(row.lineno, f"{what}: {field} = {token!r} is not a whole number; expected an integer")
    ivalue = int(value)
    check_constraint(ctx, row.lineno, what, field, token, "", ivalue, constraint)
    return ivalue


def require_columns(ctx: Context, row: Row, what: str, names: tuple[str, ...]) -> None:
    if len(row.tokens) < len(names):
        missing = ", ".join(names[len(row.tokens) :])
        raise ctx.error(
            row.lineno,
            f"{what}: row has {len(row.tokens)} columns, expected {len(names)} "
            f"({' '.join(names)}); missing {missing}: {row.text.strip()!r}",
        )


def check_ids_sequential(ctx: Context, kind: str, items: list[tuple[int, int]]) -> None:
    """``items`` = [(id, lineno)] in file order; ids must be unique and 1, 2, 3, ..."""
    seen: dict[int, int] = {}
    for obj_id, lineno in items:
        if obj_id in seen:
            raise ctx.error(
                lineno, f"{kind}: duplicate id {obj_id} (already defined at line {seen[obj_id]})"
            )
        seen[obj_id] = lineno
    for expected, (obj_id, lineno) in enumerate(items, start=1):
        if obj_id != expected:
            raise ctx.error(
                lineno,
                f"{kind}: id {obj_id} out of sequence; expected {expected} "
                "(MoorDyn numbers rows 1, 2, 3, ... in file order and resolves references by row)",
            )
