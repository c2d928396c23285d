"""The ``LINE TYPES`` section: one :class:`DeckLineType` per row, nonlinear-EA tables read.

Columns ``TypeName Diam Mass/m EA BA/-zeta EI Cd Ca CdAx CaAx`` [+ ``Cl dF cF``].
EA is a number [N] or the name of a ``strain tension`` table next to the deck;
the viscoelastic (``a|b``) and Syrope forms are refused with what is missing.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..errors import InputError
from ._lexer import (
    COMMENT_RE,
    FLOAT_RE,
    NONFINITE_RE,
    Context,
    Row,
    Section,
    is_number,
    number,
    require_columns,
)
from ._records import DeckLineType


_LINE_TYPE_COLUMNS = ("TypeName", "Diam", "Mass/m", "EA", "BA/-zeta", "EI", "Cd", "Ca", "CdAx", "CaAx")


def _resolve_side_file(ctx: Context, token: str) -> Path:
    """A side file named in the deck, relative to the deck's folder."""
    p = Path(token)
    if not p.is_absolute():
        p = Path(ctx.path).parent / p
    return p


def _read_ea_table(ctx: Context, row: Row, what: str, token: str) -> tuple[tuple[float, float], ...]:
    """Read a MoorDyn nonlinear-stiffness file: header lines, then ``strain tension`` rows."""
    path = _resolve_side_file(ctx, token)
    if not path.is_file():
        raise ctx.error(
            row.lineno,
            f"{what}: EA = {token!r} is neither a number in N nor an existing stiffness-table "
            f"file (looked for {str(path)!r}); expected EA > 0 in N or a file of "
            "'strain tension' rows",
        )
    where = str(path)
    origin = f"EA table of {what} ({ctx.path}:{row.lineno})"
    pairs: list[tuple[float, float]] = []
    lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    for lineno, raw in enumerate(lines, start=1):
        tokens = COMMENT_RE.split(raw, maxsplit=1)[0].split()
        if not tokens:
            continue
        numeric = len(tokens) >= 2 and all(
            FLOAT_RE.match(t) or NONFINITE_RE.match(t) for t in tokens[:2]
        )
        if not numeric:
            if pairs or (tokens and (FLOAT_RE.match(tokens[0]) or NONFINITE_RE.match(tokens[0]))):
                raise InputError(
                    f"{where}:{lineno}: {origin}: row {raw.strip()!r} is not two numbers; "
                    "expected 'strain [-] tension [N]'"
                )
            continue  # header line
        strain, tension = float(tokens[0]), float(tokens[1])
        if not (math.isfinite(strain) and math.isfinite(tension)):
            raise InputError(
                f"{where}:{lineno}: {origin}: strain = {tokens[0]} [-], tension = {tokens[1]} N "
                "must be finite numbers"
            )
        if tension < 0:
            raise InputError(
                f"{where}:{lineno}: {origin}: tension = {tokens[1]} N at strain {tokens[0]} "
                "must be >= 0"
            )
        if pairs and not strain > pairs[-1][0]:
            raise InputError(
                f"{where}:{lineno}: {origin}: strain = {tokens[0]} [-] is not greater than the "
                f"previous strain {pairs[-1][0]!r}; strain must be strictly increasing"
            )
        if pairs and tension < pairs[-1][1]:
            ctx.warn(
                row.lineno,
                f"{what}: EA table {str(path)!r} line {lineno}: tension {tokens[1]} N is lower "
                f"than at the previous strain ({pairs[-1][1]!r} N): negative stiffness",
            )
        pairs.append((strain, tension))
    if len(pairs) < 2:
        raise InputError(
            f"{where}: {origin}: found {len(pairs)} 'strain tension' rows; expected at least 2"
        )
    return tuple(pairs)


def _parse_line_type(ctx: Context, row: Row) -> DeckLineType:
    what = "LINE TYPES row"
    require_columns(ctx, row, what, _LINE_TYPE_COLUMNS)
    t = row.tokens
    name = t[0]
    what = f"LINE TYPES {name!r}"
    diameter = number(ctx, row, 1, what, "Diam", "m", "pos")
    mass = number(ctx, row, 2, what, "Mass/m", "kg/m", "pos")

    ea_tok = t[3]
    ea: float | None = None
    ea_table = None
    if ea_tok.upper().startswith("SYROPE:"):
        raise ctx.error(
            row.lineno,
            f"{what}: EA = {ea_tok!r}: the Syrope polyester model is not supported yet. moorjax lacks "
            "(1) the load-path-dependent working curves (the original working curve OWC table and "
            "the LINEAR/QUADRATIC/EXP curve with k1, k2 from the Syrope file), (2) the history "
            "state per segment (highest and current mean tension, initialised from the SYROPE IC "
            "section's Tmax0, Tmean0) and (3) the viscoelastic dynamic branch EA_d = EA_Dc + "
            "EA_D_Lm*mean_load in series with the static one (an extra internal strain per "
            "segment in the state). Expected one EA in N or a stiffness-table file",
        )
    if "|" in ea_tok:
        n_parts = len(ea_tok.split("|"))
        form = ("EA_s|EA_d: constant dynamic stiffness" if n_parts == 2
                else "EA_s|EA_Dc|EA_D_Lm: load-dependent dynamic stiffness" if n_parts == 3
                else f"{n_parts} '|'-separated values")
        raise ctx.error(
            row.lineno,
            f"{what}: EA = {ea_tok!r} ({form}): MoorDyn's viscoelastic line model is not supported "
            "yet. moorjax lacks the second (dynamic) spring-dashpot branch of each segment: an "
            "internal strain per segment in the dynamic state with its own rate equation, the "
            "dynamic stiffness EA_d (and, for three values, its dependence on the running mean "
            "tension, EA_d = EA_Dc + EA_D_Lm*mean_load) and the dynamic damping BA_d from "
            "'BA_s|BA_d'. Expected one EA in N or a stiffness-table file",
        )
    if is_number(ea_tok) or NONFINITE_RE.match(ea_tok):
        ea = number(ctx, row, 3, what, "EA", "N", "pos")
    else:
        ea_table = _read_ea_table(ctx, row, what, ea_tok)

    ba_tok = t[4]
    if "|" in ba_tok:
        raise ctx.error(
            row.lineno,
            f"{what}: BA/-zeta = {ba_tok!r}: static|dynamic damping (BA_s|BA_d) belongs to "
            "MoorDyn's viscoelastic line model, which is not supported yet (moorjax lacks the "
            "dynamic spring-dashpot branch per segment); expected one number (N-s, or -zeta if "
            "negative)",
        )
    if not (is_number(ba_tok) or NONFINITE_RE.match(ba_tok)) and _resolve_side_file(ctx, ba_tok).is_file():
        raise ctx.error(
            row.lineno, f"{what}: BA/-zeta = {ba_tok!r}: tabulated damping is not supported yet"
        )
    ba = number(ctx, row, 4, what, "BA/-zeta", "N-s", "any")

    ei_tok = t[5]
    if not (is_number(ei_tok) or NONFINITE_RE.match(ei_tok)) and _resolve_side_file(ctx, ei_tok).is_file():
        raise ctx.error(row.lineno, f"{what}: EI = {ei_tok!r}: tabulated bending stiffness is not supported yet")
    ei = number(ctx, row, 5, what, "EI", "N-m^2", "nonneg")  # > 0: bending (io/build.py)

    cd = number(ctx, row, 6, what, "Cd", "[-]", "nonneg")
    ca = number(ctx, row, 7, what, "Ca", "[-]", "nonneg")
    cd_ax = number(ctx, row, 8, what, "CdAx", "[-]", "nonneg")
    ca_ax = number(ctx, row, 9, what, "CaAx", "[-]", "nonneg")

    if len(t) > 10:
        cl = number(ctx, row, 10, what, "Cl", "[-]", "nonneg")
        for i, field in ((11, "dF"), (12, "cF")):
            if len(t) > i:
                number(ctx, row, i, what, field, "[-]", "nonneg")
        if cl > 0:
            ctx.warn(row.lineno, f"{what}: Cl = {t[10]} [-]: vortex-induced vibration is not supported yet (ignored)")
        if len(t) > 13:
            ctx.warn(row.lineno, f"{what}: {len(t) - 13} extra column(s) after cF ignored: {' '.join(t[13:])}")

    return DeckLineType(
        name=name,
        diameter=diameter,
        mass_per_length=mass,
        ea=ea,
        ea_table=ea_table,
        ba=ba,
        ei=ei,
        cd=cd,
        ca=ca,
        cd_axial=cd_ax,
        ca_axial=ca_ax,
        source_line=row.lineno,
    )


def parse_line_types(ctx: Context, sec: Section | None) -> dict[str, DeckLineType]:
    """The ``LINE TYPES`` section (required, at least one row; names unique), by name in file order."""
    if sec is None:
        raise ctx.error(None, "required section LINE TYPES (or LINE DICTIONARY) is missing")
    if not sec.rows:
        raise ctx.error(sec.lineno, "LINE TYPES: the section has no rows; expected at least one line type")
    line_types: dict[str, DeckLineType] = {}
    for row in sec.rows:
        lt = _parse_line_type(ctx, row)
        if lt.name in line_types:
            raise ctx.error(
                row.lineno,
                f"LINE TYPES: duplicate type name {lt.name!r} (already defined at line "
                f"{line_types[lt.name].source_line})",
            )
        line_types[lt.name] = lt
    return line_types
