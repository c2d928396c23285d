"""What every ``moorjax`` sub-command module shares: help layout, message
clipping, the ``example:NAME`` deck argument, and the argument types and
options (dynamics settings) of several sub-commands.

Kept apart from :mod:`moorjax.cli` so that sub-command modules
(:mod:`moorjax._cli_fit`, ...) need not import the command line that
imports them.
"""

from __future__ import annotations

import argparse
import re


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Keeps the epilog's layout and appends defaults that mean something."""

    def _get_help_string(self, action):
        text = action.help or ""
        if "%(default)" in text or "default" in text:
            return text
        if action.option_strings and not any(action.default is v for v in (None, False, True)) \
                and action.default != argparse.SUPPRESS:
            text += " (default: %(default)s)"
        return text


def clip(text: str, longest: int = 80) -> str:
    """``text`` with every token longer than ``longest`` characters shortened; the
    end of a token (a path's file name and line number) is kept."""
    def short(m):
        tok = m.group(0)
        return f"{tok[:20]}…[{len(tok) - 60} more characters]…{tok[-40:]}"
    text = re.sub(rf"\S{{{longest + 1},}}", short, str(text))
    return text if len(text) <= 2000 else text[:2000] + f"… [{len(text) - 2000} more characters]"


def deck_path(arg: str) -> str:
    """The file of a DECK argument: ``example:NAME`` is a bundled deck, anything else a path."""
    if arg.startswith("example:"):
        from .examples import example_path

        return example_path(arg.split(":", 1)[1])
    return arg


def positive_int(text):
    """argparse type: an integer >= 1."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {clip(repr(text))}")
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {v}")
    return v


def add_subcommand(sub, name, help, example, **kw):
    """A sub-command parser with its one-line help, defaults and one example."""
    return sub.add_parser(name, help=help, description=help[0].upper() + help[1:] + ".",
                          epilog=f"example:\n  {example}", formatter_class=HelpFormatter, **kw)


def element_option(d, mesh="uniform"):
    """``--element linear|hermite`` and ``--hermite-mesh`` (statics, simulate,
    ensemble, fit; ``mesh``: the command's default grading)."""
    d.add_argument("--element", choices=("linear", "hermite"), default="linear",
                   help="line discretisation: Aamo & Fossen's linear element (default), or Wu "
                        "et al.'s Hermite-cubic element with a tension field (lines between "
                        "fixed or moving points, free points and bodies; no 3-D seabed)")
    d.add_argument("--hermite-mesh", choices=("touchdown", "uniform"), default=mesh,
                   help="with --element hermite: 'touchdown' grades the elements of a line with "
                        "one end on the seabed about its static touchdown (an element boundary "
                        "there, elements growing away from it; moorjax.statics.hermite."
                        "touchdown_mesh: grounded end tensions ~1e-4 of MoorPy's at 10 elements "
                        "against ~5e-3), 'uniform' keeps equal elements (default: %(default)s; "
                        "in dynamics the touchdown moves off the graded node)")
    d.add_argument("--hermite-tension", choices=("projected", "element", "strain", "mixed"),
                   default="projected",
                   help="with --element hermite, how the dynamics' tension follows from the "
                        "slopes: 'projected' (default) Wu's continuous quadratic field, the law "
                        "on the strain projected onto it; 'element' the same field per element; "
                        "'strain' the law at every quadrature point; 'mixed' Wu's field solved "
                        "from his Eq. 27 at every evaluation (dense solves, a line that stays "
                        "taut); statics always solve Wu's field")


def dynamics_options(d):
    """Options shared by simulate and ensemble."""
    from .dynamics.solvers import SOLVERS

    d.add_argument("deck", help="MoorDyn v2 deck, or example:NAME")
    d.add_argument("--duration", type=float, required=True, help="simulated time [s]")
    d.add_argument("--t0", type=float, default=0.0, help="start time [s] (static equilibrium there)")
    d.add_argument("--motion", help="CSV of coupled-point and coupled-body motion "
                   "(t, P<id>_x, ..., B<id>_x, ..., B<id>_roll [rad], ...); 'none' holds "
                   "them still (default: an example's own motion, else none)")
    d.add_argument("--segments", type=positive_int,
                   help="override every line's segment count (default: the deck's)")
    d.add_argument("--wave-kinematics", metavar="FILE.py:NAME",
                   help="external wave kinematics of a WaveKin = 1 deck (MoorDyn's API waves): a "
                        "pure JAX function NAME(r, t) -> (velocity, acceleration) in FILE.py, r (..., 3) "
                        "[m], both results (..., 3) [m/s, m/s^2]; without it such a deck's water is "
                        "still")
    d.add_argument("--solver", default="auto", choices=("auto",) + SOLVERS,
                   help="time stepper; auto: ros34pw2 (Rosenbrock-W, no Newton iteration) for "
                        "decks of lines with the linear element, kvaerno5 with bodies, Hermite "
                        "lines or bending stiffness")
    element_option(d)
    d.add_argument("--rtol", type=float, default=1e-5, help="relative tolerance")
    d.add_argument("--atol", type=float, default=1e-4,
                   help="absolute tolerance of positions [m]; adaptive steps also hold each "
                        "segment chord of a line to its share of the position tolerance "
                        "(atol + rtol*|r|)/segments, so that tension errors do not grow with "
                        "the number of segments")
    d.add_argument(
        "--atol-velocity",
        type=float,
        help="absolute tolerance of velocities [m/s] (default 100*atol per s)",
    )
    d.add_argument("--dt", type=float, help="fixed step [s] (default: adaptive)")
    d.add_argument("--dt-out", type=float, default=0.05, help="output interval [s]")
    d.add_argument("--quiet", "-q", action="store_true",
                   help="no progress on stderr (it is off anyway when stderr is not a terminal)")
