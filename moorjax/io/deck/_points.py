"""The ``POINTS`` section: line ends fixed, coupled, free or fixed in a body.

Columns ``ID Attachment X Y Z Mass Volume CdA Ca`` (MoorDyn v1's ``FX FY FZ``
before ``CdA`` are read and ignored with a warning).
"""

from __future__ import annotations

import re

from ..frames import body_point_positions
from ._lexer import (
    NONFINITE_RE,
    Context,
    Row,
    Section,
    check_ids_sequential,
    integer,
    is_number,
    number,
    require_columns,
)
from ._records import DeckBody, DeckPoint


_FIXED_WORDS = {"FIXED", "FIX", "ANCHOR"}
_COUPLED_WORDS = {"COUPLED", "CPLD", "VESSEL", "VES", "FAIRLEAD"}
_FREE_WORDS = {"FREE", "POINT", "CONNECT", "CON"}
_ATTACH_WORD_RE = re.compile(r"([A-Za-z_]*)(.*)\Z")


_POINT_COLUMNS = ("ID", "Attachment", "X", "Y", "Z", "Mass", "Volume", "CdA", "Ca")


def _parse_point(ctx: Context, row: Row) -> DeckPoint:
    what = "POINTS row"
    require_columns(ctx, row, what, _POINT_COLUMNS)
    t = row.tokens
    pid = integer(ctx, row, 0, what, "ID")
    what = f"POINTS id {pid}"

    word_tok = t[1]
    m = _ATTACH_WORD_RE.match(word_tok)
    word, rest = (m.group(1).upper(), m.group(2)) if m else ("", word_tok)
    if word in _FIXED_WORDS and not rest:
        attachment = "fixed"
    elif word in _COUPLED_WORDS and not rest:
        attachment = "coupled"
    elif word in _FREE_WORDS and not rest:
        attachment = "free"
    elif word == "BODY":
        if not re.fullmatch(r"\d+", rest) or int(rest) == 0:
            raise ctx.error(
                row.lineno,
                f"{what}: Attachment = {word_tok!r}: expected Body<n> with n the id of a BODIES row "
                "(1, 2, ...), e.g. Body1",
            )
        attachment = "body"
    elif word == "TURBINE":
        raise ctx.error(
            row.lineno,
            f"{what}: Attachment = {word_tok!r}: points attached to turbines are not supported yet; "
            "expected Fixed/Anchor, Coupled/Vessel or Body<n>",
        )
    else:
        raise ctx.error(
            row.lineno,
            f"{what}: Attachment = {word_tok!r} is not a known point type; expected one of "
            "Fixed, Anchor, Coupled, Vessel, Free (Point, Connect), Body<n>",
        )

    x = number(ctx, row, 2, what, "X", "m")
    y = number(ctx, row, 3, what, "Y", "m")
    z = number(ctx, row, 4, what, "Z", "m")
    mass = number(ctx, row, 5, what, "Mass", "kg", "nonneg")
    volume = number(ctx, row, 6, what, "Volume", "m^3", "nonneg")

    if len(t) >= 12 and all(is_number(s) or NONFINITE_RE.match(s) for s in t[7:12]):
        # v1 layout with external force columns: ... FX FY FZ CdA Ca
        forces = [number(ctx, row, i, what, f, "N") for i, f in ((7, "FX"), (8, "FY"), (9, "FZ"))]
        cda = number(ctx, row, 10, what, "CdA", "m^2", "nonneg")
        ca = number(ctx, row, 11, what, "Ca", "[-]", "nonneg")
        if any(f != 0 for f in forces):
            ctx.warn(row.lineno, f"{what}: external force (FX FY FZ) = {' '.join(t[7:10])} N is ignored")
        extra = t[12:]
    else:
        cda = number(ctx, row, 7, what, "CdA", "m^2", "nonneg")
        ca = number(ctx, row, 8, what, "Ca", "[-]", "nonneg")
        extra = t[9:]
    if extra:
        ctx.warn(row.lineno, f"{what}: {len(extra)} extra column(s) ignored: {' '.join(extra)}")

    return DeckPoint(
        id=pid,
        attachment=attachment,
        position=(x, y, z),
        mass=mass,
        volume=volume,
        cda=cda,
        ca=ca,
        source_line=row.lineno,
        body=int(rest) if attachment == "body" else None,
    )


def parse_points(ctx: Context, sec: Section | None, bodies: dict[int, DeckBody]) -> dict[int, DeckPoint]:
    """The ``POINTS`` section by id (1, 2, 3, ... in file order); a ``Body<n>`` must name a body."""
    points: dict[int, DeckPoint] = {}
    if sec is not None:
        parsed = [_parse_point(ctx, row) for row in sec.rows]
        check_ids_sequential(ctx, "POINTS", [(p.id, p.source_line) for p in parsed])
        points = {p.id: p for p in parsed}
    for p in points.values():
        if p.body is not None and p.body not in bodies:
            known = ", ".join(str(i) for i in bodies) or "none - no BODIES section rows"
            raise ctx.error(
                p.source_line,
                f"POINTS id {p.id}: Attachment = 'Body{p.body}': no body with id {p.body} "
                f"(known body ids: {known})",
            )
    for b in bodies.values():
        if not any(p.body == b.id for p in points.values()):
            ctx.warn(b.source_line, f"BODIES id {b.id}: no point is attached to this body")
    return points


def check_seabed(
    ctx: Context,
    points: dict[int, DeckPoint],
    bodies: dict[int, DeckBody],
    options: dict[str, float | str],
    option_lines: dict[str, int],
) -> None:
    """No point below ``WtrDpth`` (body points at their deck pose); without
    ``WtrDpth``, a warning where MoorDyn puts the seabed."""

    def global_z(p: DeckPoint) -> float:
        if p.body is None:
            return p.position[2]
        return float(body_point_positions(bodies[p.body].pose(), p.position)[2])

    depth = options.get("WtrDpth")
    if isinstance(depth, float):
        tol = 1e-6 * depth
        for p in points.values():
            z = global_z(p)
            if z < -depth - tol:
                where = "" if p.body is None else f" (global z of a point of body {p.body} at its deck pose)"
                raise ctx.error(
                    p.source_line,
                    f"POINTS id {p.id}: Z = {z!r} m{where} is below the seabed at "
                    f"z = -{depth!r} m (WtrDpth = {depth!r} m, line {option_lines['WtrDpth']}); "
                    "expected Z >= -WtrDpth",
                )
    elif points:
        lowest = min(global_z(p) for p in points.values())
        if lowest < 0:
            ctx.warn(
                None,
                f"OPTIONS: WtrDpth not given; MoorDyn puts the seabed at the lowest point, "
                f"z = {lowest!r} m (WtrDpth = {-lowest!r} m)",
            )
