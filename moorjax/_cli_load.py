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

    from .element.hermite_motion import MixedTension, ProjectedTension, StrainTension

    name = getattr(args, "element", "linear")
    if name == "linear":
        return LinearElement()
    tension = {"projected": ProjectedTension, "element": lambda: ProjectedTension(continuous=False),
               "strain": StrainTension, "mixed": MixedTension}[getattr(args, "hermite_tension", "projected")]
    return HermiteElement(tension=tension())


def wave_kinematics_from(spec: str | None):
    """The external wave kinematics named by ``--wave-kinematics FILE.py:NAME``:
    ``NAME`` in the Python file is either a function ``f(r, t) -> (u, a)``
    (wrapped in :class:`moorjax.model.ExternalWaves`) or an
    :class:`moorjax.model.AbstractWaveKinematics`. None without the option."""
    if spec is None:
        return None
    import importlib.util
    from pathlib import Path

    from .model import AbstractWaveKinematics, ExternalWaves

    path, sep, name = spec.rpartition(":")
    if not sep or not path or not name:
        raise ValueError(f"--wave-kinematics {spec!r}: expected FILE.py:NAME, the Python file and the "
                         "function f(r, t) -> (velocity, acceleration) in it")
    file = Path(path)
    if not file.is_file():
        raise ValueError(f"--wave-kinematics {spec!r}: no such file {path!r}")
    module_spec = importlib.util.spec_from_file_location(f"_moorjax_wave_kinematics_{file.stem}", file)
    module = importlib.util.module_from_spec(module_spec)
    try:
        module_spec.loader.exec_module(module)
    except Exception as exc:  # the user's file: say which and why
        raise ValueError(f"--wave-kinematics {spec!r}: importing {path!r} failed: "
                         f"{type(exc).__name__}: {exc}") from exc
    obj = getattr(module, name, None)
    if obj is None:
        raise ValueError(f"--wave-kinematics {spec!r}: {path!r} defines no {name!r}")
    if isinstance(obj, AbstractWaveKinematics):
        return obj
    if not callable(obj):
        raise ValueError(f"--wave-kinematics {spec!r}: {name!r} is a {type(obj).__name__}, not a function "
                         "f(r, t) -> (velocity, acceleration) or a moorjax.model.AbstractWaveKinematics")
    return ExternalWaves(obj)


def load(args, motion=None):
    """Deck, scene and motion of a sub-command: ``motion`` is the motion file
    to read (None: coupled points and bodies held where the deck puts them)."""
    from .io import build_scene, read_deck, read_deck_motion

    deck = read_deck(deck_path(args.deck))
    table = None if motion is None else read_deck_motion(motion, deck)
    waves = wave_kinematics_from(getattr(args, "wave_kinematics", None))
    scene = build_scene(deck, segments=args.segments, motion=table, element=element_from(args),
                        waves=waves)
    return deck, graded_as_asked(args, scene), table


def graded_as_asked(args, scene):
    """The scene as ``--element hermite --hermite-mesh touchdown`` asks: each
    Hermite line's elements graded about its static touchdown
    (:func:`moorjax.statics.hermite.touchdown_mesh`; lines off the bed
    unchanged); otherwise the scene itself."""
    if getattr(args, "element", "linear") != "hermite" or getattr(args, "hermite_mesh", "uniform") != "touchdown":
        return scene
    import equinox as eqx

    from .statics.hermite import touchdown_mesh

    lines = tuple(touchdown_mesh(line, scene.env) for line in scene.lines)
    return eqx.tree_at(lambda s: s.lines, scene, lines)


def dynamics_settings(args) -> dict:
    """simulate() keyword arguments of the shared dynamics options."""
    return dict(solver=args.solver, rtol=args.rtol, atol=args.atol,
                atol_velocity=args.atol_velocity, dt=args.dt, dt_out=args.dt_out)


def resolved_settings(kwargs, scene) -> dict:
    """simulate() keyword arguments with ``solver="auto"`` replaced by the method
    the run uses for ``scene`` and the tolerances it runs at (recorded in output
    files and ``--stats``: passed again, they reproduce the run)."""
    from .dynamics.settings import resolve_tolerances

    solver, rtol, atol, atol_velocity = resolve_tolerances(
        kwargs["solver"], kwargs["rtol"], kwargs["atol"], kwargs["atol_velocity"], scene)
    return dict(kwargs, solver=solver, rtol=rtol, atol=atol, atol_velocity=atol_velocity)


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
