"""Reading a whole deck: sections in order, cross-checked, into a :class:`Deck`."""

from __future__ import annotations

import warnings
from pathlib import Path

from ..currents import CURRENT_FILES, read_current_grid_4d, read_current_profile, read_dynamic_current_profile
from ..waves import read_deck_waves
from ..errors import InputWarning
from ..seafloor import read_seafloor
from ._bodies import parse_bodies
from ._lexer import Context, Section, split_sections
from ._line_types import parse_line_types
from ._lines import parse_lines
from ._options import parse_options
from ._points import check_seabed, parse_points
from ._records import Deck


def parse_deck(text: str, path: str = "<string>") -> Deck:
    """Parse and validate the text of a MoorDyn v2 deck.

    Args:
        text: the whole file content.
        path: name used in messages; also the base for relative side files
            (nonlinear-EA tables are looked up next to it).

    Returns:
        The :class:`Deck`.  Warnings are in ``Deck.warnings`` and also emitted
        with :func:`warnings.warn` (category
        :class:`~moorjax.io.errors.InputWarning`).

    Raises:
        InputError: on any malformed, inconsistent or unsupported content; the
            message starts with ``path:line:``.
    """
    ctx = Context(str(path))
    try:
        return _parse(text, ctx)
    finally:
        # also when raising: a warning often explains the error
        for msg in ctx.warnings:
            warnings.warn(msg, InputWarning, stacklevel=3)


def read_deck(path) -> Deck:
    """Read and validate a MoorDyn v2 deck file.

    Args:
        path: the deck file (``str`` or :class:`os.PathLike`).  Side files
            (nonlinear-EA tables) are resolved relative to its folder.

    Raises:
        InputError: malformed, inconsistent or unsupported content.
        OSError: the file cannot be read.
    """
    p = Path(path)
    text = p.read_text(encoding="utf-8", errors="replace")
    return parse_deck(text, str(path))


def _parse(text: str, ctx: Context) -> Deck:
    title, sections = split_sections(text, ctx)
    if not sections:
        raise ctx.error(
            None,
            "no sections found; expected section header lines such as "
            "'---------- LINE TYPES ----------' (is this a MoorDyn v2 input file?)",
        )

    # OPTIONS first: WtrDpth is needed to check the points
    options: dict[str, float | str] = {}
    option_lines: dict[str, int] = {}
    if "OPTIONS" in sections:
        options, option_lines = parse_options(ctx, sections["OPTIONS"])
    current = _read_current(ctx, options, option_lines)
    waves = _read_waves(ctx, options, option_lines)
    seafloor = read_seafloor(options["SeafloorFile"]) if "SeafloorFile" in options else None
    _check_unsupported(ctx, sections)

    if "LINE TYPES" not in sections and "LINES" not in sections:
        found = ", ".join(sorted(sections)) or "none"
        raise ctx.error(
            None,
            f"the deck has no LINE TYPES and no LINES section (sections found: {found}), so no mooring "
            "lines; MoorDyn accepts such a deck and only moves its bodies and points, but moorjax models "
            "lines and has nothing to solve without them; add a LINES section and the LINE TYPES it uses",
        )
    line_types = parse_line_types(ctx, sections.get("LINE TYPES"))
    bodies = parse_bodies(ctx, sections.get("BODIES"))
    points = parse_points(ctx, sections.get("POINTS"), bodies)
    check_seabed(ctx, points, bodies, options, option_lines)
    lines = parse_lines(ctx, sections.get("LINES"), line_types, points)
    return Deck(
        path=ctx.path,
        title=title,
        line_types=line_types,
        points=points,
        lines=lines,
        options=options,
        warnings=tuple(ctx.warnings),
        bodies=bodies,
        current=current,
        seafloor=seafloor,
        waves=waves,
    )


def _read_current(ctx: Context, options: dict[str, float | str], option_lines: dict[str, int]):
    """The current of ``Currents`` 1, 2 or 5: the file MoorDyn-C reads from the deck's folder."""
    mode = int(options.get("Currents", 0))
    if not mode:
        return None
    origin = f"{ctx.path}:{option_lines['Currents']}: OPTIONS: Currents = {mode}"
    side = Path(ctx.path).parent / CURRENT_FILES[mode]
    reader = {1: read_current_profile, 2: read_dynamic_current_profile, 5: read_current_grid_4d}[mode]
    return reader(side, origin)


def _read_waves(ctx: Context, options: dict[str, float | str], option_lines: dict[str, int]):
    """The wave components of ``WaveKin`` 2, 3 or 7, from the files MoorDyn-C reads
    from the deck's folder (:mod:`moorjax.io.waves`)."""
    mode = int(options.get("WaveKin", 0))
    if mode in (0, 1):  # 1: external kinematics, given at run time (build_scene's waves)
        return None
    origin = f"{ctx.path}:{option_lines['WaveKin']}: OPTIONS: WaveKin = {mode}"
    return read_deck_waves(Path(ctx.path).parent, mode, float(options.get("dtWave", 0.25)), origin)


def _check_unsupported(ctx: Context, sections: dict[str, Section]) -> None:
    """Rows of object sections moorjax cannot simulate raise; ignored ones warn."""
    for kind, what in (
        ("RODS", "rods"),
        ("FAILURE", "line failures"),
        ("EXTERNAL LOADS", "external loads"),
    ):
        sec = sections.get(kind)
        if sec is not None and sec.rows:
            raise ctx.error(
                sec.rows[0].lineno,
                f"{kind}: {what} are not supported yet (row {sec.rows[0].text.strip()!r}); "
                "remove the rows or the section",
            )
    for kind, what in (("ROD TYPES", "rod types"), ("CONTROL", "control channels"), ("OUTPUTS", "output channels")):
        sec = sections.get(kind)
        if sec is not None and sec.rows:
            ctx.warn(sec.lineno, f"{kind}: {len(sec.rows)} {what} row(s) ignored (not supported yet)")
