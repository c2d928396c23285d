"""The ``OPTIONS`` section: MoorDyn's option names, aliases, units, limits and defaults.

:func:`parse_options` reads the rows (``value  name  [description]``) into a
dict keyed by MoorDyn's canonical names; :func:`options_with_defaults` fills in
MoorDyn-C v2's defaults for a whole deck.
"""

from __future__ import annotations

import re

from ..seafloor import find_seafloor_file
from ._lexer import NONFINITE_RE, Context, Section, is_number, number
from ._records import Deck


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


def _check_currents_mode(ctx: Context, lineno: int, name: str, token: str, value: float) -> None:
    """``Currents``: 0 none, 1 steady and 2 dynamic depth profiles and 5 the 4-D
    grid are read (:mod:`moorjax.io.currents`); 3 and 4 are not implemented in
    MoorDyn either."""
    if value in (0, 1, 2, 5):
        return
    if value in (3, 4):
        raise ctx.error(
            lineno,
            f"OPTIONS: {name} = {token}: current mode {int(value)} (steady/dynamic currents at nodes) is "
            "not implemented in MoorDyn v2 either; expected 0 (none), 1 (current_profile.txt), "
            "2 (current_profile_dynamic.txt) or 5 (current_profile_4d.txt)",
        )
    raise ctx.error(
        lineno,
        f"OPTIONS: {name} = {token} is not a MoorDyn current mode; expected 0, 1, 2 or 5 "
        "(3, 4: not implemented in MoorDyn)",
    )


def _check_wave_mode(ctx: Context, lineno: int, name: str, token: str, value: float) -> None:
    """``WaveKin``: 0 none, 2 (FFT grid), 3 (elevation grid) and 7 (component sum)
    are read (:mod:`moorjax.io.waves`); 1 (external kinematics, MoorDyn's API) is
    supplied at run time (:class:`moorjax.model.ExternalWaves`, ``--wave-kinematics``);
    4, 5 and 6 are not implemented in MoorDyn either."""
    if value in (0, 1, 2, 3, 7):
        return
    expected = ("expected 0 (none), 1 (external, supplied at run time), 2 (wave_frequencies.txt on a "
                "grid), 3 (wave_elevation.txt on a grid) or 7 (wave_frequencies.txt summed at the nodes)")
    if value in (4, 5, 6):
        raise ctx.error(lineno, f"OPTIONS: {name} = {token}: wave mode {int(value)} is not implemented "
                        f"in MoorDyn v2 either; {expected}")
    raise ctx.error(lineno, f"OPTIONS: {name} = {token} is not a MoorDyn wave mode; {expected}")


def parse_options(ctx: Context, section: Section) -> tuple[dict[str, float | str], dict[str, int]]:
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
            if NONFINITE_RE.match(value_tok):
                raise ctx.error(row.lineno, f"{what}: {name} = {value_tok} must be a finite number")
            value: float | str = float(value_tok) if is_number(value_tok) else value_tok
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
            if canonical == "WtrDpth" and not (is_number(value_tok) or NONFINITE_RE.match(value_tok)):
                raise ctx.error(
                    row.lineno,
                    f"{what}: WtrDpth = {value_tok!r}: a bathymetry file is not supported yet; "
                    "expected a water depth > 0 in m",
                )
            value = number(ctx, row, 0, what, name, unit, constraint)
            if canonical == "WaveKin":
                _check_wave_mode(ctx, row.lineno, name, value_tok, value)
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
