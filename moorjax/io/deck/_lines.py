"""The ``LINES`` section: lines between two points, of a type from ``LINE TYPES``.

Columns ``ID LineType AttachA AttachB UnstrLen NumSegs LineOutputs``; an end is
a point id (``3``, ``P3``); rod ends and bodies are refused with the reason.
``LineOutputs`` flags that moorjax does not write, or that are no MoorDyn flag,
are warned about by name (:mod:`moorjax.io.line_outputs`).
"""

from __future__ import annotations

import re

from ..line_outputs import NOT_WRITTEN, WRITTEN, split_flags
from ._lexer import Context, Row, Section, check_ids_sequential, integer, number, require_columns
from ._records import DeckLine, DeckLineType, DeckPoint


_POINT_REF_RE = re.compile(r"(?:P|POINT|C|CON|CONNECT)?(\d+)\Z", re.IGNORECASE)
_ROD_REF_RE = re.compile(r"(?:R|ROD)\d+[AB]?\Z", re.IGNORECASE)
_BODY_REF_RE = re.compile(r"(?:B|BODY|TURBINE)\d+\Z", re.IGNORECASE)


_LINE_COLUMNS = ("ID", "LineType", "AttachA", "AttachB", "UnstrLen", "NumSegs", "LineOutputs")


def _parse_attachment_ref(ctx: Context, row: Row, index: int, what: str, field: str) -> int:
    token = row.tokens[index]
    m = _POINT_REF_RE.match(token)
    if m:
        pid = int(m.group(1))
        if pid <= 0:
            raise ctx.error(row.lineno, f"{what}: {field} = {token!r}: point ids start at 1")
        return pid
    if _ROD_REF_RE.match(token):
        raise ctx.error(
            row.lineno, f"{what}: {field} = {token!r}: lines attached to rod ends are not supported yet"
        )
    if _BODY_REF_RE.match(token):
        raise ctx.error(
            row.lineno,
            f"{what}: {field} = {token!r}: a line end names a point, not a body; add a POINTS row "
            "with Attachment Body<n> and coordinates in the body's axes, and give its id (e.g. 3 or P3)",
        )
    raise ctx.error(
        row.lineno, f"{what}: {field} = {token!r} is not a point id; expected a point id such as 1 or P1"
    )


def _check_outputs(ctx: Context, row: Row, what: str, text: str) -> None:
    """Warn about ``LineOutputs`` flags moorjax does not write, by name."""
    _, missing, unknown = split_flags(text)
    if missing:
        names = ", ".join(f"{f} ({NOT_WRITTEN[f]})" for f in missing)
        ctx.warn(row.lineno, f"{what}: LineOutputs = {text!r}: {names} not written by moorjax "
                             f"(it writes {', '.join(WRITTEN)})")
    if unknown:
        ctx.warn(row.lineno, f"{what}: LineOutputs = {text!r}: {', '.join(repr(c) for c in unknown)} "
                             f"not a MoorDyn line output flag (ignored, as MoorDyn does); expected "
                             f"letters of {WRITTEN + ''.join(NOT_WRITTEN)} or -")


def _parse_line(ctx: Context, row: Row) -> DeckLine:
    what = "LINES row"
    require_columns(ctx, row, what, _LINE_COLUMNS)
    t = row.tokens
    lid = integer(ctx, row, 0, what, "ID")
    what = f"LINES id {lid}"
    a = _parse_attachment_ref(ctx, row, 2, what, "AttachA")
    b = _parse_attachment_ref(ctx, row, 3, what, "AttachB")
    length = number(ctx, row, 4, what, "UnstrLen", "m", "pos")
    nseg = integer(ctx, row, 5, what, "NumSegs", "pos")
    if len(t) > 7:
        ctx.warn(row.lineno, f"{what}: {len(t) - 7} extra column(s) ignored: {' '.join(t[7:])}")
    _check_outputs(ctx, row, what, t[6])
    return DeckLine(
        id=lid,
        line_type=t[1],
        point_a=a,
        point_b=b,
        length=length,
        n_segments=nseg,
        outputs=t[6],
        source_line=row.lineno,
    )


def parse_lines(
    ctx: Context,
    sec: Section | None,
    line_types: dict[str, DeckLineType],
    points: dict[int, DeckPoint],
) -> tuple[DeckLine, ...]:
    """The ``LINES`` section (required, at least one row), each row's type and
    points checked; warns about points and line types no line uses."""
    if sec is None:
        raise ctx.error(None, "required section LINES (or LINE PROPERTIES / LINE LIST) is missing")
    if not sec.rows:
        raise ctx.error(sec.lineno, "LINES: the section has no rows; expected at least one line")
    lines: list[DeckLine] = []
    for row in sec.rows:
        ln = _parse_line(ctx, row)
        what = f"LINES id {ln.id}"
        if ln.line_type not in line_types:
            known = ", ".join(repr(n) for n in line_types)
            raise ctx.error(
                row.lineno, f"{what}: LineType = {ln.line_type!r} is not defined in LINE TYPES (known: {known})"
            )
        for field, pid, tok in (("AttachA", ln.point_a, row.tokens[2]), ("AttachB", ln.point_b, row.tokens[3])):
            if pid not in points:
                known = ", ".join(str(i) for i in points) or "none - no POINTS section rows"
                raise ctx.error(
                    row.lineno, f"{what}: {field} = {tok!r}: no point with id {pid} (known point ids: {known})"
                )
        if ln.point_a == ln.point_b:
            raise ctx.error(
                row.lineno,
                f"{what}: AttachA = {row.tokens[2]!r} and AttachB = {row.tokens[3]!r} are the same point "
                f"{ln.point_a}; expected two different points",
            )
        lines.append(ln)
    check_ids_sequential(ctx, "LINES", [(ln.id, ln.source_line) for ln in lines])

    used = {ln.point_a for ln in lines} | {ln.point_b for ln in lines}
    for p in points.values():
        if p.id not in used:
            ctx.warn(p.source_line, f"POINTS id {p.id}: no line is attached to this point")
    unused_types = [n for n in line_types if n not in {ln.line_type for ln in lines}]
    for n in unused_types:
        ctx.warn(line_types[n].source_line, f"LINE TYPES {n!r}: not used by any line")
    return tuple(lines)
