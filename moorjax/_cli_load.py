"""How every ``moorjax`` sub-command reads its deck and motion: the deck
argument, the motion file (or a bundled example's own), the scene, and the
dynamics settings of ``simulate``/``ensemble`` checked before anything compiles.
"""

from __future__ import annotations

import numpy as np

from ._cli_common import deck_path


def motion_path(args) -> str | None:
    """--motion, or a bundled example's own motion; ``none`` holds the coupled points."""
    motion = getattr(args, "motion", None)
    if motion is not None:
        return None if motion.lower() == "none" else motion
    if args.deck.startswith("example:"):
        from .examples import example_motion_path

        return example_motion_path(args.deck.split(":", 1)[1])
    return None


def element_from(args):
    """The line discretisation named by ``--element`` (None: the default, linear)."""
    from .element import HermiteElement, LinearElement

    name = getattr(args, "element", "linear")
    return {"linear": LinearElement(), "hermite": HermiteElement()}[name]


def load(args, motion=None):
    """Deck, scene and motion of a sub-command: ``motion`` is the motion file
    to read (None: coupled points and bodies held where the deck puts them)."""
    from .io import build_scene, read_deck, read_deck_motion

    deck = read_deck(deck_path(args.deck))
    table = None if motion is None else read_deck_motion(motion, deck)
    scene = build_scene(deck, segments=args.segments, motion=table, element=element_from(args))
    return deck, scene, table


def dynamics_settings(args) -> dict:
    """simulate() keyword arguments of the shared dynamics options."""
    return dict(solver=args.solver, rtol=args.rtol, atol=args.atol,
                atol_velocity=args.atol_velocity, dt=args.dt, dt_out=args.dt_out)


def resolved_settings(kwargs, scene) -> dict:
    """simulate() keyword arguments with ``solver="auto"`` replaced by the method
    the run uses for ``scene`` (recorded in output files and ``--stats``)."""
    from .dynamics.settings import resolve_solver

    return dict(kwargs, solver=resolve_solver(kwargs["solver"], scene))


def load_for_dynamics(args, with_motion=False):
    """Deck, scene and simulate() keyword arguments from the shared options
    (and the motion read, with ``with_motion``). Every option is checked here,
    before anything is compiled."""
    from .dynamics.simulate import plan

    if not (np.isfinite(args.duration) and args.duration > 0):
        raise ValueError(f"--duration = {args.duration} s must be > 0")
    if not np.isfinite(args.t0):
        raise ValueError(f"--t0 = {args.t0} s must be finite")
    kwargs = dynamics_settings(args)
    path = motion_path(args)
    deck, scene, motion = load(args, path)
    if motion is not None:
        check_motion_covers(path, motion.t, args.t0, args.t0 + args.duration)
    plan(args.duration, t0=args.t0, **kwargs)  # raises ValueError naming a bad setting
    kwargs["t0"] = args.t0
    return (deck, scene, kwargs, motion) if with_motion else (deck, scene, kwargs)


def check_motion_covers(path, t, t0, t_end):
    """The motion must cover the run, t0 to t_end [s]: a ValueError naming the
    file and both time spans otherwise (no point is ever held still)."""
    tol = 1e-9 * max(1.0, abs(t_end))
    if t[0] > t0 + tol or t[-1] < t_end - tol:
        raise ValueError(
            f"{path}: the motion covers t = {t[0]:.10g} to {t[-1]:.10g} s but the run needs "
            f"t = {t0:.10g} to {t_end:.10g} s (--t0, --duration); give the motion over at least "
            "that span (to hold a point still, add rows at its last position with zero "
            "velocity) or shorten --duration"
        )


def deck_text(deck_arg) -> str:
    """The deck's text (kept in the outputs' metadata)."""
    with open(deck_path(deck_arg), encoding="utf-8", errors="replace") as f:
        return f.read()


def command_line(args) -> str:
    """The command line as the user typed it."""
    return "moorjax " + " ".join(getattr(args, "argv", []) or [args.command])
