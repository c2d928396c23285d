"""Reader for MoorDyn v2 input files ("decks") into plain, validated data.

The deck format (MoorDyn v2, also the v1 section names) is a plain-text file:

* free-text lines before the first section (kept as :attr:`Deck.title`);
* sections, each opened by a line containing ``---`` and a keyword
  (``LINE TYPES``/``LINE DICTIONARY``, ``POINTS``/``POINT PROPERTIES``/
  ``CONNECTION PROPERTIES``/``NODE PROPERTIES``, ``LINES``/``LINE PROPERTIES``,
  ``OPTIONS``, ``BODIES``, ``RODS``, ``ROD TYPES``, ``FAILURE``, ``OUTPUTS``,
  ``CONTROL``, ``EXTERNAL LOADS``);
* table sections have two header lines (column names, units) then one row per
  object; ``OPTIONS`` rows are ``value  name  [description]``;
* the file ends at a ``---`` line containing ``need this line`` or at EOF.

Values are whitespace-separated; ``!``, ``#`` and ``%`` start a comment.
Blank lines inside sections are skipped.

Only what moorjax can simulate is accepted: lines between ``Fixed``/``Anchor``,
``Coupled``/``Vessel`` and ``Free``/``Connect`` points and points fixed in
bodies (``Body1``, ...).
``BODIES`` rows of every kind (``fixed``, ``coupled``, ``free``,
``coupledpinned``) are read into :class:`DeckBody` records;
:func:`moorjax.io.build_scene` builds fixed and coupled ones and refuses the
others with the reason.  Currents (``Currents`` 1 and 2) are read from
MoorDyn's side files (:mod:`moorjax.io.currents`). Rods,
failures, external loads, wave kinematics and 4-D current grids raise
:class:`InputError` ("not supported yet"). ``SeafloorFile`` bathymetry
grids are read (:mod:`moorjax.io.seafloor`).
Everything is validated on reading; every error names ``file:line``, the
field, the value as written, its unit and what is expected.

Units are SI throughout (m, kg, N, s).  Axes follow MoorDyn: z up, z = 0 at the
free surface, seabed at z = -WtrDpth.

Pure Python + numpy; no JAX.
"""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from .currents import CURRENT_FILES, DeckCurrent, read_current_profile, read_dynamic_current_profile
from .errors import InputError, InputWarning
from .frames import body_point_positions
from .seafloor import DeckSeafloor, find_seafloor_file, read_seafloor

__all__ = [
    "DeckLineType",
    "DeckPoint",
    "DeckBody",
    "DeckLine",
    "Deck",
    "read_deck",
    "parse_deck",
    "options_with_defaults",
    "MOORDYN_DEFAULTS",
]


# ----------------------------------------------------------------------------
# Data
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class DeckLineType:
    """One row of ``LINE TYPES``: physical properties of a line.

    Attributes:
        name: type name used by ``LINES`` rows.
        diameter: volume-equivalent diameter [m] (buoyancy, drag, added mass).
        mass_per_length: mass per unit unstretched length, in air [kg/m].
        ea: axial stiffness EA [N]; ``None`` when tabulated (see ``ea_table``).
        ea_table: ``((strain [-], tension [N]), ...)`` with strictly increasing
            strain and non-negative tension, read from the file named in the EA
            column (path relative to the deck's folder); ``None`` for a scalar EA.
        ba: internal axial damping [N·s] if >= 0; if negative it is ``-zeta``,
            the damping as a fraction of critical (MoorDyn convention), kept as
            given.
        ei: bending stiffness [N·m²] (not simulated yet; > 0 gives a warning).
        cd: transverse drag coefficient [-], w.r.t. frontal area d·l.
        ca: transverse added-mass coefficient [-].
        cd_axial: tangential drag coefficient [-], w.r.t. surface area π·d·l.
        ca_axial: tangential added-mass coefficient [-].
        source_line: 1-based line number of the row in the deck.
    """

    name: str
    diameter: float
    mass_per_length: float
    ea: float | None
    ea_table: tuple[tuple[float, float], ...] | None
    ba: float
    ei: float
    cd: float
    ca: float
    cd_axial: float
    ca_axial: float
    source_line: int


@dataclass(frozen=True)
class DeckPoint:
    """One row of ``POINTS``: a line end held fixed, driven by the caller, free, or fixed in a body.

    Attributes:
        id: point number (1, 2, 3, ... in file order).
        attachment: ``'fixed'`` (Fixed/Anchor/Fix), ``'coupled'``
            (Coupled/Vessel/Ves/Cpld/Fairlead), ``'free'`` (Free/Point/
            Connect/Con: a point mass moved by its lines and loads; its
            position is the initial guess) or ``'body'`` (Body<n>).
        position: (x, y, z) [m], global frame; for coupled points the initial
            position; for body points the position in the body's axes relative
            to its reference point (X0, Y0, Z0) (see :meth:`Deck.point_position`
            for the global one).
        mass: point mass [kg].
        volume: displaced volume [m³].
        cda: drag coefficient times area [m²].
        ca: added-mass coefficient [-].
        source_line: 1-based line number of the row in the deck.
        body: id of the body a ``'body'`` point is fixed in, else ``None``.
    """

    id: int
    attachment: str
    position: tuple[float, float, float]
    mass: float
    volume: float
    cda: float
    ca: float
    source_line: int
    body: int | None = None


@dataclass(frozen=True)
class DeckBody:
    """One row of ``BODIES``: a rigid body that points (and so lines) are fixed in.

    Attributes:
        id: body number (1, 2, 3, ... in file order).
        attachment: ``'fixed'`` (Fixed/Fix/Anchor), ``'coupled'``
            (Coupled/Vessel/Ves/Cpld: pose driven by the caller), ``'free'``
            (Free: moved by its loads) or ``'coupled_pinned'``
            (CoupledPinned/VesselPinned/VesPin/CpldPin: position driven,
            rotation free).
        position: (X0, Y0, Z0) [m], the body reference point in the global
            frame (initial position of a coupled body).
        orientation: (r0, p0, y0) roll, pitch, yaw [deg] as written; the body
            axes are R = Rx(r0)·Ry(p0)·Rz(y0) (see :mod:`moorjax.io.frames`).
        mass: body mass [kg] (without attached points and rods).
        cg: (x, y, z) centre of gravity in body axes [m] (one value in the
            deck is z, x = y = 0).
        inertia: (Ixx, Iyy, Izz) [kg·m²] (one value in the deck is all three).
        volume: displaced volume [m³].
        cda: (6,) drag coefficient × area per degree of freedom, x, y, z then
            the three rotations [m²]: one value in the deck is all six, two
            are translation|rotation, three are x|y|z for both, or six.
        ca: (3,) added-mass coefficients [-] (one value is all three).
        source_line: 1-based line number of the row in the deck.

    Mass, CG, inertia, volume, CdA and Ca only matter to free bodies; MoorDyn
    ignores them for fixed and coupled ones, and so does moorjax.
    """

    id: int
    attachment: str
    position: tuple[float, float, float]
    orientation: tuple[float, float, float]
    mass: float
    cg: tuple[float, float, float]
    inertia: tuple[float, float, float]
    volume: float
    cda: tuple[float, float, float, float, float, float]
    ca: tuple[float, float, float]
    source_line: int

    def pose(self) -> tuple[float, ...]:
        """(6,) pose x, y, z [m], roll, pitch, yaw [rad] (the deck's r0, p0, y0 in radians)."""
        return (*self.position, *(math.radians(a) for a in self.orientation))


@dataclass(frozen=True)
class DeckLine:
    """One row of ``LINES``: a mooring line between two points.

    Attributes:
        id: line number (1, 2, 3, ... in file order).
        line_type: name of a :class:`DeckLineType`.
        point_a: id of the point at end A (anchor end, node 0).
        point_b: id of the point at end B (fairlead end, node N).
        length: unstretched length [m].
        n_segments: number of segments [-] (N + 1 nodes).
        outputs: MoorDyn line-output flags as written (``'-'`` for none).
        source_line: 1-based line number of the row in the deck.
    """

    id: int
    line_type: str
    point_a: int
    point_b: int
    length: float
    n_segments: int
    outputs: str
    source_line: int


@dataclass(frozen=True)
class Deck:
    """A parsed, validated MoorDyn v2 deck.

    Attributes:
        path: the file the deck came from (``'<string>'`` for :func:`parse_deck`
            without a path).
        title: the free text before the first section (lines joined by ``\\n``).
        line_types: type name -> :class:`DeckLineType`, in file order.
        points: point id -> :class:`DeckPoint`, in file order.
        lines: the :class:`DeckLine` rows, in file order.
        options: the ``OPTIONS`` given in the file, keyed by MoorDyn's canonical
            name (``'dtM'``, ``'tScheme'``, ``'g'`` [m/s²], ``'rho'`` [kg/m³],
            ``'WtrDpth'`` [m], ``'kBot'`` [Pa/m], ``'cBot'`` [Pa·s/m],
            ``'FrictionCoefficient'`` [-], ...; aliases such as ``kb``,
            ``rhoW``, ``ICthresh`` are mapped to them, names are matched
            case-insensitively).  Numbers are ``float``; ``tScheme`` is
            lower-cased text.  Unknown names are kept as written (float if
            numeric, else text) with a warning.  Missing options are *not*
            filled in: see :func:`options_with_defaults`.
        warnings: human-readable warnings (each also emitted with
            :func:`warnings.warn` as :class:`~moorjax.io.errors.InputWarning`).
        bodies: body id -> :class:`DeckBody`, in file order (empty without a
            ``BODIES`` section).
        current: the current of a deck with ``Currents`` 1 or 2, read from
            the file MoorDyn-C reads next to the deck
            (:mod:`moorjax.io.currents`); ``None`` without currents.
        seafloor: the bathymetry grid of a deck with ``SeafloorFile``
            (:mod:`moorjax.io.seafloor`); ``None`` for a flat seabed.
    """

    path: str
    title: str
    line_types: dict[str, DeckLineType]
    points: dict[int, DeckPoint]
    lines: tuple[DeckLine, ...]
    options: dict[str, float | str]
    warnings: tuple[str, ...]
    bodies: dict[int, DeckBody] = field(default_factory=dict)
    current: DeckCurrent | None = None
    seafloor: DeckSeafloor | None = None

    def point_position(self, point_id: int) -> tuple[float, float, float]:
        """Global position [m] of a point at the deck's initial poses (body
        points transformed by their body's X0..y0)."""
        p = self.points[point_id]
        if p.body is None:
            return p.position
        x, y, z = body_point_positions(self.bodies[p.body].pose(), p.position)
        return (float(x), float(y), float(z))


# ----------------------------------------------------------------------------
# MoorDyn options
# ----------------------------------------------------------------------------

#: MoorDyn-C v2 defaults for options missing from a deck (MoorDyn v2 input-file
#: documentation and MoorDyn-C source).  ``WtrDpth`` and ``dtM`` are special,
#: see :func:`options_with_defaults`.
MOORDYN_DEFAULTS: dict[str, float | str | None] = {
    "writeLog": 0.0,
    "dtM": None,  # MoorDyn-C: FLT_MAX, i.e. the step comes from CFL
    "CFL": 0.5,
    "tScheme": "rk2",
    "g": 9.80665,
    "rho": 1025.0,
    "WtrDpth": 0.0,  # deepened to the lowest point, see options_with_defaults
    "kBot": 3.0e6,
    "cBot": 3.0e5,
    "dtIC": 1.0,
    "TmaxIC": 120.0,
    "CdScaleIC": 5.0,
    "threshIC": 0.001,
    "ICgenDynamic": 0.0,
    "WaveKin": 0.0,
    "dtWave": 0.25,
    "waveKin_rampT": 0.0,
    "Currents": 0.0,
    "UnifyCurrentGrid": 1.0,
    "WriteUnits": 1.0,
    "FrictionCoefficient": 0.0,
    "FricDamp": 200.0,
    "StatDynFricScale": 1.0,
    "dtOut": 0.0,
    "disableOutput": 0.0,
    "disableOutTime": 0.0,
}

# lower-cased spelling -> canonical MoorDyn name
_OPTION_ALIASES: dict[str, str] = {name.lower(): name for name in MOORDYN_DEFAULTS}
_OPTION_ALIASES.update(
    {
        "dt": "dtM",
        "gravity": "g",
        "rhow": "rho",
        "wtrdnsty": "rho",
        "kb": "kBot",
        "cb": "cBot",
        "icdt": "dtIC",
        "ictmax": "TmaxIC",
        "icdfac": "CdScaleIC",
        "icthresh": "threshIC",
        "seafloorfile": "SeafloorFile",
    }
)

# MoorDyn-F-only options: unknown to MoorDyn-C, reported with a specific hint.
_MOORDYN_F_ONLY = {"waterkin", "mu_kt", "mu_ka", "mc", "cv", "inertialf", "inertialf_rampt", "outswitch"}

# canonical name -> (unit, constraint); constraint in {"pos", "nonneg", "any"}
_OPTION_RULES: dict[str, tuple[str, str]] = {
    "writeLog": ("[-]", "any"),
    "dtM": ("s", "pos"),
    "CFL": ("[-]", "pos"),
    "g": ("m/s^2", "nonneg"),  # MoorDyn runs g = 0 (weightless tests) and rho = 0 (in air)
    "rho": ("kg/m^3", "nonneg"),
    "WtrDpth": ("m", "pos"),
    "kBot": ("Pa/m", "nonneg"),
    "cBot": ("Pa-s/m", "nonneg"),
    "dtIC": ("s", "pos"),
    "TmaxIC": ("s", "nonneg"),
    "CdScaleIC": ("[-]", "pos"),
    "threshIC": ("[-]", "pos"),
    "ICgenDynamic": ("[-]", "any"),
    "WaveKin": ("[-]", "any"),
    "dtWave": ("s", "pos"),
    "waveKin_rampT": ("s", "nonneg"),
    "Currents": ("[-]", "any"),
    "UnifyCurrentGrid": ("[-]", "any"),
    "WriteUnits": ("[-]", "any"),
    "FrictionCoefficient": ("[-]", "nonneg"),
    "FricDamp": ("[-]", "nonneg"),
    "StatDynFricScale": ("[-]", "pos"),
    "dtOut": ("s", "nonneg"),
    "disableOutput": ("[-]", "any"),
    "disableOutTime": ("[-]", "any"),
}

_TSCHEME_RE = re.compile(
    r"(euler|leuler|heun|rk2|rk4|ab[234]|lab[234]|(beuler|midpoint|aca|wilson)\d*)\Z", re.IGNORECASE
)


def options_with_defaults(deck: Deck) -> dict[str, float | str | None]:
    """The deck's options completed with MoorDyn-C v2 defaults.

    Every key of :data:`MOORDYN_DEFAULTS` is present (plus any unknown option
    the deck kept).  Two entries differ from a plain lookup:

    * ``WtrDpth`` [m]: if the deck does not give it, MoorDyn starts from 0 and
      deepens the seabed to the lowest point, so the default is
      ``max(0, -min(z of all points))`` (body points at their global
      position, :meth:`Deck.point_position`).
    * ``dtM`` [s]: if not given it is ``None`` - MoorDyn-C then derives the step
      from ``CFL`` (its nominal default is FLT_MAX).

    Values: ``g`` 9.80665 m/s², ``rho`` 1025 kg/m³, ``kBot`` 3e6 Pa/m, ``cBot``
    3e5 Pa·s/m, ``tScheme`` ``'rk2'``, ``FrictionCoefficient`` 0,
    ``FricDamp`` 200, ``StatDynFricScale`` 1, ``dtIC`` 1 s, ``TmaxIC`` 120 s,
    ``CdScaleIC`` 5, ``threshIC`` 0.001, ``CFL`` 0.5, ...
    """
    out: dict[str, float | str | None] = dict(MOORDYN_DEFAULTS)
    if "WtrDpth" not in deck.options:
        zs = [deck.point_position(pid)[2] for pid in deck.points]
        out["WtrDpth"] = max(0.0, -min(zs)) if zs else 0.0
    out.update(deck.options)
    return out


# ----------------------------------------------------------------------------
# Sections
# ----------------------------------------------------------------------------

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

_COMMENT_RE = re.compile(r"[!#%]")
_FLOAT_RE = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?\Z")
_NONFINITE_RE = re.compile(r"[+-]?(?:nan|inf|infinity)\Z", re.IGNORECASE)

_FIXED_WORDS = {"FIXED", "FIX", "ANCHOR"}
_COUPLED_WORDS = {"COUPLED", "CPLD", "VESSEL", "VES", "FAIRLEAD"}
_FREE_WORDS = {"FREE", "POINT", "CONNECT", "CON"}
_ATTACH_WORD_RE = re.compile(r"([A-Za-z_]*)(.*)\Z")
_POINT_REF_RE = re.compile(r"(?:P|POINT|C|CON|CONNECT)?(\d+)\Z", re.IGNORECASE)
_ROD_REF_RE = re.compile(r"(?:R|ROD)\d+[AB]?\Z", re.IGNORECASE)
_BODY_REF_RE = re.compile(r"(?:B|BODY|TURBINE)\d+\Z", re.IGNORECASE)


@dataclass
class _Row:
    lineno: int
    tokens: list[str]
    text: str


@dataclass
class _Section:
    kind: str
    header: str
    lineno: int
    rows: list[_Row]
    pending_headers: int


class _Context:
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
    return sum(1 for t in tokens if _FLOAT_RE.match(t)) >= 2


def _split_sections(text: str, ctx: _Context) -> tuple[str, dict[str, _Section]]:
    """Split the deck into front matter and sections (rows are tokenised)."""
    front: list[str] = []
    sections: dict[str, _Section] = {}
    current: _Section | None = None
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
                current = _Section("UNKNOWN", label, lineno, [], 0)
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
            current = _Section(kind, line.strip("- \t"), lineno, [], pending)
            sections[kind] = current
            continue
        if current is None:
            front.append(line)
            continue
        content = _COMMENT_RE.split(line, maxsplit=1)[0]
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
        current.rows.append(_Row(lineno, tokens, line))
    while front and not front[0].strip():
        front.pop(0)
    while front and not front[-1].strip():
        front.pop()
    return "\n".join(front), sections


# ----------------------------------------------------------------------------
# Field parsing helpers
# ----------------------------------------------------------------------------


def _fmt(token: str, unit: str) -> str:
    return f"{token} {unit}" if unit else token


def _is_number(token: str) -> bool:
    return bool(_FLOAT_RE.match(token))


def _number(
    ctx: _Context, row: _Row, index: int, what: str, field: str, unit: str, constraint: str = "any"
) -> float:
    """Parse ``row.tokens[index]`` as a finite float obeying ``constraint``."""
    token = row.tokens[index]
    if _NONFINITE_RE.match(token):
        raise ctx.error(row.lineno, f"{what}: {field} = {_fmt(token, unit)} must be a finite number")
    if not _FLOAT_RE.match(token):
        raise ctx.error(
            row.lineno, f"{what}: {field} = {token!r} is not a number; expected a number in {unit or '[-]'}"
        )
    value = float(token)
    if not math.isfinite(value):
        raise ctx.error(row.lineno, f"{what}: {field} = {_fmt(token, unit)} must be a finite number")
    _check_constraint(ctx, row.lineno, what, field, token, unit, value, constraint)
    return value


def _check_constraint(ctx, lineno, what, field, token, unit, value, constraint):
    if constraint == "pos" and not value > 0:
        raise ctx.error(lineno, f"{what}: {field} = {_fmt(token, unit)} must be > 0")
    if constraint == "nonneg" and not value >= 0:
        raise ctx.error(lineno, f"{what}: {field} = {_fmt(token, unit)} must be >= 0")


def _integer(ctx: _Context, row: _Row, index: int, what: str, field: str, constraint: str = "pos") -> int:
    """Parse ``row.tokens[index]`` as an integer (``'160'``, also ``'160.0'``)."""
    token = row.tokens[index]
    value: float | None = None
    if _FLOAT_RE.match(token):
        value = float(token)
    if value is None or not math.isfinite(value) or value != int(value):
        raise ctx.error(row.lineno, f"{what}: {field} = {token!r} is not a whole number; expected an integer")
    ivalue = int(value)
    _check_constraint(ctx, row.lineno, what, field, token, "", ivalue, constraint)
    return ivalue


def _require_columns(ctx: _Context, row: _Row, what: str, names: tuple[str, ...]) -> None:
    if len(row.tokens) < len(names):
        missing = ", ".join(names[len(row.tokens) :])
        raise ctx.error(
            row.lineno,
            f"{what}: row has {len(row.tokens)} columns, expected {len(names)} "
            f"({' '.join(names)}); missing {missing}: {row.text.strip()!r}",
        )


# ----------------------------------------------------------------------------
# LINE TYPES
# ----------------------------------------------------------------------------

_LINE_TYPE_COLUMNS = ("TypeName", "Diam", "Mass/m", "EA", "BA/-zeta", "EI", "Cd", "Ca", "CdAx", "CaAx")


def _resolve_side_file(ctx: _Context, token: str) -> Path:
    p = Path(token)
    if not p.is_absolute():
        p = Path(ctx.path).parent / p
    return p


def _read_ea_table(ctx: _Context, row: _Row, what: str, token: str) -> tuple[tuple[float, float], ...]:
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
        tokens = _COMMENT_RE.split(raw, maxsplit=1)[0].split()
        if not tokens:
            continue
        numeric = len(tokens) >= 2 and all(
            _FLOAT_RE.match(t) or _NONFINITE_RE.match(t) for t in tokens[:2]
        )
        if not numeric:
            if pairs or (tokens and (_FLOAT_RE.match(tokens[0]) or _NONFINITE_RE.match(tokens[0]))):
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


def _parse_line_type(ctx: _Context, row: _Row) -> DeckLineType:
    what = "LINE TYPES row"
    _require_columns(ctx, row, what, _LINE_TYPE_COLUMNS)
    t = row.tokens
    name = t[0]
    what = f"LINE TYPES {name!r}"
    diameter = _number(ctx, row, 1, what, "Diam", "m", "pos")
    mass = _number(ctx, row, 2, what, "Mass/m", "kg/m", "pos")

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
    if _is_number(ea_tok) or _NONFINITE_RE.match(ea_tok):
        ea = _number(ctx, row, 3, what, "EA", "N", "pos")
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
    if not (_is_number(ba_tok) or _NONFINITE_RE.match(ba_tok)) and _resolve_side_file(ctx, ba_tok).is_file():
        raise ctx.error(
            row.lineno, f"{what}: BA/-zeta = {ba_tok!r}: tabulated damping is not supported yet"
        )
    ba = _number(ctx, row, 4, what, "BA/-zeta", "N-s", "any")

    ei_tok = t[5]
    if not (_is_number(ei_tok) or _NONFINITE_RE.match(ei_tok)) and _resolve_side_file(ctx, ei_tok).is_file():
        raise ctx.error(row.lineno, f"{what}: EI = {ei_tok!r}: tabulated bending stiffness is not supported yet")
    ei = _number(ctx, row, 5, what, "EI", "N-m^2", "nonneg")
    if ei > 0:
        ctx.warn(row.lineno, f"{what}: EI = {ei_tok} N-m^2: bending stiffness is not supported yet (ignored)")

    cd = _number(ctx, row, 6, what, "Cd", "[-]", "nonneg")
    ca = _number(ctx, row, 7, what, "Ca", "[-]", "nonneg")
    cd_ax = _number(ctx, row, 8, what, "CdAx", "[-]", "nonneg")
    ca_ax = _number(ctx, row, 9, what, "CaAx", "[-]", "nonneg")

    if len(t) > 10:
        cl = _number(ctx, row, 10, what, "Cl", "[-]", "nonneg")
        for i, field in ((11, "dF"), (12, "cF")):
            if len(t) > i:
                _number(ctx, row, i, what, field, "[-]", "nonneg")
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


# ----------------------------------------------------------------------------
# POINTS
# ----------------------------------------------------------------------------

_POINT_COLUMNS = ("ID", "Attachment", "X", "Y", "Z", "Mass", "Volume", "CdA", "Ca")


def _parse_point(ctx: _Context, row: _Row) -> DeckPoint:
    what = "POINTS row"
    _require_columns(ctx, row, what, _POINT_COLUMNS)
    t = row.tokens
    pid = _integer(ctx, row, 0, what, "ID")
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

    x = _number(ctx, row, 2, what, "X", "m")
    y = _number(ctx, row, 3, what, "Y", "m")
    z = _number(ctx, row, 4, what, "Z", "m")
    mass = _number(ctx, row, 5, what, "Mass", "kg", "nonneg")
    volume = _number(ctx, row, 6, what, "Volume", "m^3", "nonneg")

    if len(t) >= 12 and all(_is_number(s) or _NONFINITE_RE.match(s) for s in t[7:12]):
        # v1 layout with external force columns: ... FX FY FZ CdA Ca
        forces = [_number(ctx, row, i, what, f, "N") for i, f in ((7, "FX"), (8, "FY"), (9, "FZ"))]
        cda = _number(ctx, row, 10, what, "CdA", "m^2", "nonneg")
        ca = _number(ctx, row, 11, what, "Ca", "[-]", "nonneg")
        if any(f != 0 for f in forces):
            ctx.warn(row.lineno, f"{what}: external force (FX FY FZ) = {' '.join(t[7:10])} N is ignored")
        extra = t[12:]
    else:
        cda = _number(ctx, row, 7, what, "CdA", "m^2", "nonneg")
        ca = _number(ctx, row, 8, what, "Ca", "[-]", "nonneg")
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


# ----------------------------------------------------------------------------
# BODIES
# ----------------------------------------------------------------------------

_BODY_COLUMNS = ("ID", "Attachment", "X0", "Y0", "Z0", "r0", "p0", "y0", "Mass", "CG", "I", "Volume", "CdA", "Ca")

_BODY_KINDS: dict[str, str] = {
    **{w: "fixed" for w in ("FIXED", "FIX", "ANCHOR")},
    **{w: "coupled" for w in ("COUPLED", "CPLD", "VESSEL", "VES")},
    **{w: "coupled_pinned" for w in ("COUPLEDPINNED", "CPLDPIN", "VESSELPINNED", "VESPIN")},
    "FREE": "free",
}


def _pipe_numbers(
    ctx: _Context, row: _Row, index: int, what: str, field: str, unit: str, counts: tuple[int, ...],
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
        if _NONFINITE_RE.match(part) or (_FLOAT_RE.match(part) and not math.isfinite(float(part))):
            raise ctx.error(row.lineno, f"{what}: {field} = {token!r}: {part} {unit} must be a finite number")
        if not _FLOAT_RE.match(part):
            raise ctx.error(
                row.lineno,
                f"{what}: {field} = {token!r}: {part!r} is not a number; expected {expected} numbers "
                f"separated by '|' ({meaning}) in {unit}",
            )
        value = float(part)
        _check_constraint(ctx, row.lineno, what, field, token if len(parts) == 1 else f"{token!r}: {part}",
                          unit, value, constraint)
        values.append(value)
    return tuple(values)


def _parse_body(ctx: _Context, row: _Row) -> DeckBody:
    what = "BODIES row"
    _require_columns(ctx, row, what, _BODY_COLUMNS)
    t = row.tokens
    bid = _integer(ctx, row, 0, what, "ID")
    what = f"BODIES id {bid}"
    kind = _BODY_KINDS.get(t[1].upper())
    if kind is None:
        raise ctx.error(
            row.lineno,
            f"{what}: Attachment = {t[1]!r} is not a known body type; expected one of Fixed, "
            "Coupled (Vessel), Free, CoupledPinned (VesselPinned)",
        )
    position = tuple(_number(ctx, row, i, what, f, "m") for i, f in ((2, "X0"), (3, "Y0"), (4, "Z0")))
    orientation = tuple(_number(ctx, row, i, what, f, "deg") for i, f in ((5, "r0"), (6, "p0"), (7, "y0")))
    mass = _number(ctx, row, 8, what, "Mass", "kg", "nonneg")
    cg = _pipe_numbers(ctx, row, 9, what, "CG", "m", (1, 3), "any", "z, or x|y|z")
    if len(cg) == 1:
        cg = (0.0, 0.0, cg[0])
    inertia = _pipe_numbers(ctx, row, 10, what, "I", "kg-m^2", (1, 3), "nonneg", "Ixx=Iyy=Izz, or Ixx|Iyy|Izz")
    if len(inertia) == 1:
        inertia = inertia * 3
    volume = _number(ctx, row, 11, what, "Volume", "m^3", "nonneg")
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


# ----------------------------------------------------------------------------
# LINES
# ----------------------------------------------------------------------------

_LINE_COLUMNS = ("ID", "LineType", "AttachA", "AttachB", "UnstrLen", "NumSegs", "LineOutputs")


def _parse_attachment_ref(ctx: _Context, row: _Row, index: int, what: str, field: str) -> int:
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


def _parse_line(ctx: _Context, row: _Row) -> DeckLine:
    what = "LINES row"
    _require_columns(ctx, row, what, _LINE_COLUMNS)
    t = row.tokens
    lid = _integer(ctx, row, 0, what, "ID")
    what = f"LINES id {lid}"
    a = _parse_attachment_ref(ctx, row, 2, what, "AttachA")
    b = _parse_attachment_ref(ctx, row, 3, what, "AttachB")
    length = _number(ctx, row, 4, what, "UnstrLen", "m", "pos")
    nseg = _integer(ctx, row, 5, what, "NumSegs", "pos")
    if len(t) > 7:
        ctx.warn(row.lineno, f"{what}: {len(t) - 7} extra column(s) ignored: {' '.join(t[7:])}")
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


# ----------------------------------------------------------------------------
# OPTIONS
# ----------------------------------------------------------------------------


def _check_currents_mode(ctx: _Context, lineno: int, name: str, token: str, value: float) -> None:
    """``Currents``: 0 none, 1 steady and 2 dynamic depth profiles are read
    (:mod:`moorjax.io.currents`); 3 and 4 are not implemented in MoorDyn
    either; 5 (4-D grid) is not supported yet."""
    if value in (0, 1, 2):
        return
    if value in (3, 4):
        raise ctx.error(
            lineno,
            f"OPTIONS: {name} = {token}: current mode {int(value)} (steady/dynamic currents at nodes) is "
            "not implemented in MoorDyn v2 either; expected 0 (none), 1 (current_profile.txt) or "
            "2 (current_profile_dynamic.txt)",
        )
    if value == 5:
        raise ctx.error(
            lineno,
            f"OPTIONS: {name} = {token}: 4-D current grids (current_profile_4d.txt) are not supported "
            "yet; expected 0 (none), 1 (steady depth profile, current_profile.txt) or 2 (depth profile "
            "in time, current_profile_dynamic.txt)",
        )
    raise ctx.error(
        lineno,
        f"OPTIONS: {name} = {token} is not a MoorDyn current mode; expected 0, 1 or 2 "
        "(3, 4: not implemented in MoorDyn; 5: 4-D grid, not supported yet)",
    )


def _parse_options(ctx: _Context, section: _Section) -> tuple[dict[str, float | str], dict[str, int]]:
    options: dict[str, float | str] = {}
    where: dict[str, int] = {}
    for row in section.rows:
        if len(row.tokens) < 2:
            ctx.warn(row.lineno, f"OPTIONS: row {row.text.strip()!r} has a value but no option name; ignored")
            continue
        value_tok, name = row.tokens[0], row.tokens[1]
        canonical = _OPTION_ALIASES.get(name.lower())
        what = "OPTIONS"
        if canonical is None:
            if _NONFINITE_RE.match(value_tok):
                raise ctx.error(row.lineno, f"{what}: {name} = {value_tok} must be a finite number")
            value: float | str = float(value_tok) if _is_number(value_tok) else value_tok
            hint = " (a MoorDyn-F option, not used by MoorDyn-C)" if name.lower() in _MOORDYN_F_ONLY else ""
            ctx.warn(row.lineno, f"OPTIONS: unknown option {name!r}{hint}; kept as {value!r} but not used")
            key = name
        elif canonical == "tScheme":
            if not _TSCHEME_RE.match(value_tok):
                ctx.warn(
                    row.lineno,
                    f"OPTIONS: tScheme = {value_tok!r} is not a MoorDyn time scheme "
                    "(Euler, Heun, RK2, RK4, AB2-4, LAB2-4, BEulerN, MidpointN, ACAN, WilsonN)",
                )
            value = value_tok.lower()
            key = canonical
        elif canonical == "SeafloorFile":
            found = find_seafloor_file(value_tok, ctx.path)
            if found is None:
                raise ctx.error(
                    row.lineno,
                    f"{what}: SeafloorFile = {value_tok!r}: no such file next to the deck or in its "
                    "parent folders (MoorDyn resolves it from its working directory); give a path "
                    "relative to the deck",
                )
            value = str(found)
            key = canonical
        else:
            unit, constraint = _OPTION_RULES[canonical]
            if canonical == "WtrDpth" and not (_is_number(value_tok) or _NONFINITE_RE.match(value_tok)):
                raise ctx.error(
                    row.lineno,
                    f"{what}: WtrDpth = {value_tok!r}: a bathymetry file is not supported yet; "
                    "expected a water depth > 0 in m",
                )
            value = _number(ctx, row, 0, what, name, unit, constraint)
            if canonical == "WaveKin" and value != 0:
                raise ctx.error(
                    row.lineno,
                    f"{what}: {name} = {value_tok}: wave kinematics on lines are not supported yet "
                    "(MoorDyn's WaveKin 1 external, 2 FFT grid, 3 elevation grid, 7 component sum); "
                    "expected 0",
                )
            if canonical == "Currents":
                _check_currents_mode(ctx, row.lineno, name, value_tok, value)
            key = canonical
        if key in options:
            ctx.warn(
                row.lineno,
                f"OPTIONS: {key} given again (first at line {where[key]}); the later value {value!r} is used",
            )
        options[key] = value
        where[key] = row.lineno
    return options, where


# ----------------------------------------------------------------------------
# Whole deck
# ----------------------------------------------------------------------------


def _check_ids_sequential(ctx: _Context, kind: str, items: list[tuple[int, int]]) -> None:
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
    ctx = _Context(str(path))
    try:
        return _parse(text, ctx)
    finally:
        # also when raising: a warning often explains the error
        for msg in ctx.warnings:
            warnings.warn(msg, InputWarning, stacklevel=3)


def _parse(text: str, ctx: _Context) -> Deck:
    path = ctx.path
    title, sections = _split_sections(text, ctx)
    if not sections:
        raise ctx.error(
            None,
            "no sections found; expected section header lines such as "
            "'---------- LINE TYPES ----------' (is this a MoorDyn v2 input file?)",
        )

    # --- OPTIONS first: WtrDpth is needed to check the points
    options: dict[str, float | str] = {}
    option_lines: dict[str, int] = {}
    if "OPTIONS" in sections:
        options, option_lines = _parse_options(ctx, sections["OPTIONS"])

    # --- currents: the file MoorDyn-C reads from the deck's folder
    current = None
    mode = int(options.get("Currents", 0))
    if mode:
        origin = f"{ctx.path}:{option_lines['Currents']}: OPTIONS: Currents = {mode}"
        side = Path(ctx.path).parent / CURRENT_FILES[mode]
        reader = read_current_profile if mode == 1 else read_dynamic_current_profile
        current = reader(side, origin)

    seafloor = None
    if "SeafloorFile" in options:
        seafloor = read_seafloor(options["SeafloorFile"])

    # --- unsupported object sections
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

    # --- LINE TYPES
    sec = sections.get("LINE TYPES")
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

    # --- BODIES
    bodies: dict[int, DeckBody] = {}
    sec = sections.get("BODIES")
    if sec is not None:
        parsed_bodies = [_parse_body(ctx, row) for row in sec.rows]
        _check_ids_sequential(ctx, "BODIES", [(b.id, b.source_line) for b in parsed_bodies])
        bodies = {b.id: b for b in parsed_bodies}

    # --- POINTS
    points: dict[int, DeckPoint] = {}
    sec = sections.get("POINTS")
    point_items: list[tuple[int, int]] = []
    if sec is not None:
        parsed = [_parse_point(ctx, row) for row in sec.rows]
        point_items = [(p.id, p.source_line) for p in parsed]
        _check_ids_sequential(ctx, "POINTS", point_items)
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

    # --- LINES
    sec = sections.get("LINES")
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
    _check_ids_sequential(ctx, "LINES", [(ln.id, ln.source_line) for ln in lines])

    used = {ln.point_a for ln in lines} | {ln.point_b for ln in lines}
    for p in points.values():
        if p.id not in used:
            ctx.warn(p.source_line, f"POINTS id {p.id}: no line is attached to this point")
    unused_types = [n for n in line_types if n not in {ln.line_type for ln in lines}]
    for n in unused_types:
        ctx.warn(line_types[n].source_line, f"LINE TYPES {n!r}: not used by any line")

    return Deck(
        path=path,
        title=title,
        line_types=line_types,
        points=points,
        lines=tuple(lines),
        options=options,
        warnings=tuple(ctx.warnings),
        bodies=bodies,
        current=current,
        seafloor=seafloor,
    )


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
