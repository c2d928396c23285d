"""The ``BODIES`` section: rigid bodies that points are fixed in.

Columns ``ID Attachment X0 Y0 Z0 r0 p0 y0 Mass CG I Volume CdA Ca``; ``CG``,
``I``, ``CdA`` and ``Ca`` take ``|``-separated values.
"""

from __future__ import annotations

import math

from ._lexer import (
    FLOAT_RE,
    NONFINITE_RE,
    Context,
    Row,
    Section,
    check_constraint,
    check_ids_sequential,
    integer,
    number,
    require_columns,
)
from ._records import DeckBody


_BODY_COLUMNS = ("ID", "Attachment", "X0", "Y0", "Z0", "r0", "p0", "y0", "Mass", "CG", "I", "Volume", "CdA", "Ca")

_BODY_KINDS: dict[str, str] = {
    **{w: "fixed" for w in ("FIXED", "FIX", "ANCHOR")},
    **{w: "coupled" for w in ("COUPLED", "CPLD", "VESSEL", "VES")},
    **{w: "coupled_pinned" for w in ("COUPLEDPINNED", "CPLDPIN", "VESSELPINNED", "VESPIN")},
    "FREE": "free",
}


def _pipe_numbers(
    ctx: Context, row: Row, index: int, what: str, field: str, unit: str, counts: tuple[int, ...],
    constraint: str, meaning: str,
) -> tuple[float, ...]:
    """Parse ``a|b|c`` (no spaces) with a count in ``counts``; each part a finite number."""
    token = row.tokens[index]
    parts = token.split("|")
    expected = " or ".join(str(c) for c in counts)
    if len(parts) not in counts:
        raise ctx.error(
            row.lineno,
            f"{what}: {field} = {token!r} has {len(parts)} value(s); expected {expected} numbers "
            f"separated by '|' without spaces ({meaning}) in {unit}",
        )
    values = []
    for part in parts:
        if NONFINITE_RE.match(part) or (FLOAT_RE.match(part) and not math.isfinite(float(part))):
            raise ctx.error(row.lineno, f"{what}: {field} = {token!r}: {part} {unit} must be a finite number")
        if not FLOAT_RE.match(part):
            raise ctx.error(
                row.lineno,
                f"{what}: {field} = {token!r}: {part!r} is not a number; expected {expected} numbers "
                f"separated by '|' ({meaning}) in {unit}",
            )
        value = float(part)
        check_constraint(ctx, row.lineno, what, field, token if len(parts) == 1 else f"{token!r}: {part}",
                          unit, value, constraint)
        values.append(value)
    return tuple(values)


def _parse_body(ctx: Context, row: Row) -> DeckBody:
    what = "BODIES row"
    require_columns(ctx, row, what, _BODY_COLUMNS)
    t = row.tokens
    bid = integer(ctx, row, 0, what, "ID")
    what = f"BODIES id {bid}"
    kind = _BODY_KINDS.get(t[1].upper())
    if kind is None:
        raise ctx.error(
            row.lineno,
            f"{what}: Attachment = {t[1]!r} is not a known body type; expected one of Fixed, "
            "Coupled (Vessel), Free, CoupledPinned (VesselPinned)",
        )
    position = tuple(number(ctx, row, i, what, f, "m") for i, f in ((2, "X0"), (3, "Y0"), (4, "Z0")))
    orientation = tuple(number(ctx, row, i, what, f, "deg") for i, f in ((5, "r0"), (6, "p0"), (7, "y0")))
    mass = number(ctx, row, 8, what, "Mass", "kg", "nonneg")
    cg = _pipe_numbers(ctx, row, 9, what, "CG", "m", (1, 3), "any", "z, or x|y|z")
    if len(cg) == 1:
        cg = (0.0, 0.0, cg[0])
    inertia = _pipe_numbers(ctx, row, 10, what, "I", "kg-m^2", (1, 3), "nonneg", "Ixx=Iyy=Izz, or Ixx|Iyy|Izz")
    if len(inertia) == 1:
        inertia = inertia * 3
    volume = number(ctx, row, 11, what, "Volume", "m^3", "nonneg")
    cda = _pipe_numbers(ctx, row, 12, what, "CdA", "m^2", (1, 2, 3, 6), "nonneg",
                        "all six, translation|rotation, x|y|z, or one per degree of freedom")
    if len(cda) == 1:
        cda = cda * 6
    elif len(cda) == 2:
        cda = (cda[0],) * 3 + (cda[1],) * 3
    elif len(cda) == 3:
        cda = cda * 2
    ca = _pipe_numbers(ctx, row, 13, what, "Ca", "[-]", (1, 3), "nonneg", "all three, or x|y|z")
    if len(ca) == 1:
        ca = ca * 3
    if len(t) > len(_BODY_COLUMNS):
        extra = t[len(_BODY_COLUMNS):]
        ctx.warn(row.lineno, f"{what}: {len(extra)} extra column(s) ignored: {' '.join(extra)}")
    return DeckBody(
        id=bid,
        attachment=kind,
        position=position,  # type: ignore[arg-type]
        orientation=orientation,  # type: ignore[arg-type]
        mass=mass,
        cg=cg,  # type: ignore[arg-type]
        inertia=inertia,  # type: ignore[arg-type]
        volume=volume,
        cda=cda,  # type: ignore[arg-type]
        ca=ca,  # type: ignore[arg-type]
        source_line=row.lineno,
    )


def parse_bodies(ctx: Context, sec: Section | None) -> dict[int, DeckBody]:
    """The ``BODIES`` section by id (1, 2, 3, ... in file order); empty without one."""
    if sec is None:
        return {}
    parsed = [_parse_body(ctx, row) for row in sec.rows]
    check_ids_sequential(ctx, "BODIES", [(b.id, b.source_line) for b in parsed])
    return {b.id: b for b in parsed}
