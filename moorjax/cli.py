"""The ``moorjax`` command line: statics, simulation, ensembles, fits and plots of
MoorDyn decks. ``main(argv)`` returns the exit code; ``run()`` is the console
entry point (exit codes, one-line warnings, Ctrl-C).

Exit codes: 0 success, 2 bad input or usage, 3 the numerics failed (a static
solve or time integration did not converge, a fit's loss became non-finite),
4 out of memory or another resource (disk full), 130 interrupted (Ctrl-C), 141
the reader of the output went away (``moorjax statics deck | head``: no message,
as a shell reports a process its pipe ended).
"""

from __future__ import annotations

import argparse
import errno
import json
import sys
import time
import warnings

import numpy as np

from . import __version__
from ._cli_common import (HelpFormatter, add_subcommand, clip, dynamics_options, element_option,
                          positive_int)
from ._cli_load import (command_line, deck_text, load, load_for_dynamics, motion_path,
                        resolved_settings)

EXIT_OK, EXIT_INPUT, EXIT_NUMERICS, EXIT_RESOURCES, EXIT_INTERRUPTED = 0, 2, 3, 4, 130
EXIT_PIPE = 141  # 128 + SIGPIPE

DESCRIPTION = ("moorjax: statics and time-domain simulation of mooring lines from MoorDyn v2 "
               "decks (differentiable, on JAX).")
EPILOG = """\
DECK is a MoorDyn v2 input file or example:NAME for a bundled deck (moorjax examples).

quick start:
  moorjax statics example:oc3_catenary --json
  moorjax simulate example:oc3_catenary --duration 60 --out run.nc
  moorjax plot run.nc --out run.png

exit codes: 0 ok, 2 bad input or usage, 3 the numerics failed, 4 out of memory or
another resource, 130 interrupted. 'moorjax COMMAND --help' shows each command's options."""


class ArgumentParser(argparse.ArgumentParser):
    def error(self, message):
        self.print_usage(sys.stderr)
        self.exit(EXIT_INPUT, f"{self.prog}: error: {clip(message)}\n")


# ------------------------------------------------------------------ loading


def cmd_statics(args) -> int:
    import jax

    _, scene, _ = load(args)
    if scene.bodies:
        # free points and bodies move to their equilibrium with the lines
        from .statics.system import imbalance_report, solve_system_statics

        if args.method == "catenary":
            from .io.errors import InputError

            raise InputError("--method catenary: decks with free points or bodies are solved as a "
                             "system (catenary lines where they apply); use --method auto or fem")
        system = solve_system_statics(scene, throw=False, method=args.method)
        if not system.converged:
            raise RuntimeError(
                "system statics (free points and bodies with their lines) did not converge: "
                f"force imbalance {float(np.max(np.abs(np.asarray(system.residual)))):.3g} N "
                f"after {system.iterations} Newton iterations ("
                + imbalance_report(scene, system.poses, system.residual, system.mooring)
                + "); a run can still start as MoorDyn's "
                "does with TmaxIC = 0, from each line's own static shape with the points and bodies "
                "where the deck puts them: moorjax simulate DECK --initial catenary")
        statics = system.lines
        methods = list(system.methods)
    else:
        statics, methods = zip(*(_line_statics(line, scene.env, args.method)
                                 for line in scene.lines))
    rows = []
    for line, st, method in zip(scene.lines, statics, methods):
        st = jax.device_get(st)
        if not bool(st.converged):
            raise RuntimeError(
                f"line {line.label}: static solve did not converge "
                f"(max force imbalance {float(st.max_residual):.3g} N after "
                f"{int(st.iterations)} Newton iterations)"
            )
        z_top = float(np.max(np.asarray(st.positions)[:, 2]))
        if z_top > 0.0 and not line.element.wets_partially:
            warnings.warn(
                f"line {line.label}: nodes above the free surface at equilibrium (highest "
                f"z = {z_top:.4g} m); the {type(line.element).__name__} has no free-surface "
                "model, so buoyancy acts there as if submerged")
        rows.append(
            dict(
                id=int(line.label) if line.label.isdigit() else line.label,
                tension_a=float(st.tension_a),
                tension_b=float(st.tension_b),
                force_a=[float(x) for x in st.force_a],
                force_b=[float(x) for x in st.force_b],
                grounded_length=float(st.grounded_length),
                n_segments=line.n_segments,
                newton_iterations=int(st.iterations),
                max_residual=float(st.max_residual),
                method=method,
            )
        )
    if args.json:
        print(json.dumps(rows, indent=2))
    else:
        print(f"{'line':>5} {'segs':>5} {'T_A [N]':>14} {'T_B [N]':>14} {'grounded [m]':>13}")
        for r in rows:
            print(
                f"{r['id']:>5} {r['n_segments']:>5} {r['tension_a']:>14.6g} "
                f"{r['tension_b']:>14.6g} {r['grounded_length']:>13.4f}"
            )
    return 0


def _line_statics(line, env, method: str):
    """A line's statics and the method it got: ``auto`` is the exact catenary where
    it describes the line and has a solution (its ``converged`` flag), else the FEM."""
    from .statics import solve_line_statics
    from .statics.exact import catenary_eligible

    if method == "auto":
        if catenary_eligible(line, env):
            st = solve_line_statics(line, env, throw=False, method="catenary")
            if bool(st.converged):
                return st, "catenary"
        method = "fem"
    return solve_line_statics(line, env, throw=False, method=method), method


class _CompileTimer:
    """Seconds JAX spends tracing, lowering and compiling while active, from its
    monitoring events, so --stats needs no second run. Nested jits report
    nested spans; their union is counted once."""

    EVENTS = ("/jax/core/compile/jaxpr_trace_duration",
              "/jax/core/compile/jaxpr_to_mlir_module_duration",
              "/jax/core/compile/backend_compile_duration")

    def __init__(self):
        self.spans = []

    def _listen(self, event, duration, **_):
        if event in self.EVENTS:
            end = time.perf_counter()
            self.spans.append((end - duration, end))

    @property
    def seconds(self) -> float:
        total, reach = 0.0, -np.inf
        for lo, hi in sorted(self.spans):
            if hi > reach:
                total += hi - max(lo, reach)
                reach = hi
        return total

    def __enter__(self):
        import jax.monitoring

        jax.monitoring.register_event_duration_secs_listener(self._listen)
        return self

    def __exit__(self, *exc):
        import jax.monitoring

        jax.monitoring.unregister_event_duration_listener(self._listen)


def cmd_simulate(args) -> int:
    import jax

    from ._progress import Progress, enabled
    from .dynamics import simulate
    from .io.dataset import to_dataset
    from .io.plausibility import check_run
    from .io.results import check_output, write_results

    check_output(args.out)
    deck, scene, kwargs, motion = load_for_dynamics(args, with_motion=True)
    kwargs = resolved_settings(kwargs, scene)
    prog = Progress("simulate", enabled(args.quiet))
    prog.say(f"{len(scene.lines)} line(s), {sum(ln.n_segments for ln in scene.lines)} segments, "
             f"{args.duration:g} s; compiling (tens of seconds the first time)…")
    t_start = time.perf_counter()
    with _CompileTimer() as timer, prog.meter(args.t0, args.duration):
        res = simulate(scene, args.duration, save_nodes=not args.no_nodes, init=args.initial,
                       progress=prog.on, **kwargs)
        jax.block_until_ready(res.tension_b)
    wall = time.perf_counter() - t_start
    res = jax.device_get(res)
    prog.say(f"{args.duration:g} s simulated in {wall:.1f} s: {int(res.num_steps)} steps "
             f"({int(res.num_rejected_steps)} rejected)")
    settings = dict(kwargs, duration=args.duration, segments=args.segments,
                    save_nodes=not args.no_nodes, initial=args.initial)
    ds = to_dataset(res, scene, deck=deck, motion=motion, attrs=dict(
        deck=args.deck, deck_text=deck_text(args.deck), motion=motion_path(args) or "none",
        settings=settings, history=command_line(args),
    ))
    for msg in check_run(ds, dry_ok=[ln.element.wets_partially for ln in scene.lines]):
        warnings.warn(msg)
    write_results(ds, args.out, nodes=not args.no_nodes)
    prog.say(f"wrote {args.out}")
    if args.stats:
        stats = dict(
            compile_s=timer.seconds,
            run_s=wall - timer.seconds,
            steps=int(res.num_steps),
            rejected_steps=int(res.num_rejected_steps),
            accepted_steps=int(res.num_accepted_steps),
            solver=kwargs["solver"],
            solver_requested=args.solver,
            rtol=kwargs["rtol"],
            atol=kwargs["atol"],
        )
        print(json.dumps(stats), file=sys.stderr)
    return 0


def cmd_examples(args) -> int:
    from .examples import EXAMPLES, example

    for name in EXAMPLES:
        ex = example(name)
        print(f"example:{name}\t{ex.shows}\n    deck:   {ex.deck}\n    motion: {ex.motion}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = ArgumentParser(prog="moorjax", description=DESCRIPTION, epilog=EPILOG,
                       formatter_class=HelpFormatter)
    p.add_argument("--version", action="version", version=f"moorjax {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND",
                           parser_class=ArgumentParser)

    s = add_subcommand(sub, "statics", "static equilibrium of every line of a deck",
             "moorjax statics example:oc3_catenary --json")
    s.add_argument("deck", help="MoorDyn v2 deck, or example:NAME")
    s.add_argument("--segments", type=positive_int,
                   help="override every line's segment count (default: the deck's)")
    element_option(s, mesh="touchdown")
    s.add_argument("--method", choices=("auto", "fem", "catenary"), default="auto",
                   help="auto: the exact elastic catenary where it describes the line (linear "
                        "element, Hooke's law, negligible EI, no current, flat seabed, a "
                        "solution exists), else the finite-element equilibrium; fem: always the "
                        "discrete model's equilibrium (the state a simulation starts from); "
                        "catenary: the catenary or an error")
    s.add_argument("--json", action="store_true", help="print JSON (one object per line)")
    s.set_defaults(func=cmd_statics)

    d = add_subcommand(sub, "simulate", "time-domain simulation of a deck",
             "moorjax simulate example:oc3_catenary --duration 60 --segments 40 --out run.nc")
    dynamics_options(d)
    d.add_argument("--out", required=True,
                   help="output file: .nc (netCDF: tensions, forces, node positions, segment "
                        "tensions, units) or .csv (tensions and forces)")
    d.add_argument("--no-nodes", action="store_true",
                   help="leave node positions and segment tensions out (huge runs)")
    from .dynamics.simulate import INITIAL

    d.add_argument("--initial", choices=INITIAL, default="statics",
                   help="start: statics, the static equilibrium of lines, points and bodies at "
                        "--t0; catenary, MoorDyn's start with TmaxIC = 0: each line's own static "
                        "shape with the points and bodies where the deck puts them, at rest and "
                        "not balanced (a line whose solve fails starts straight)")
    d.add_argument("--stats", action="store_true",
                   help="print one JSON line of statistics to stderr (compile and run time "
                        "measured in the same run)")
    d.set_defaults(func=cmd_simulate)

    from .ensemble.cli import add_parser as add_ensemble_parser

    add_ensemble_parser(sub)

    from ._cli_fit import add_parser as add_fit_parser

    add_fit_parser(sub)

    from .plot.cli import add_parsers as add_plot_parsers

    add_plot_parsers(sub)

    e = add_subcommand(sub, "examples", "list the bundled examples (deck, motion, what each shows)",
             "moorjax examples")
    e.set_defaults(func=cmd_examples)
    return p


# ------------------------------------------------------------------ running


def _exit_code(exc: BaseException) -> int:
    if isinstance(exc, MemoryError):
        return EXIT_RESOURCES
    if isinstance(exc, ImportError):  # an optional dependency is missing
        return EXIT_INPUT
    if isinstance(exc, OSError):
        if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.ENOMEM, errno.EMFILE, errno.ENFILE):
            return EXIT_RESOURCES
        return EXIT_INPUT
    text = str(exc)
    if "RESOURCE_EXHAUSTED" in text or "Out of memory" in text or "out of memory" in text:
        return EXIT_RESOURCES
    if isinstance(exc, ValueError):
        return EXIT_INPUT
    return EXIT_NUMERICS


def _message(exc: BaseException) -> str:
    if _exit_code(exc) == EXIT_RESOURCES and not isinstance(exc, OSError):
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        return (f"out of memory ({clip(first, 200)}); use fewer segments, a shorter run, "
                "--no-nodes or a smaller --chunk-size")
    if isinstance(exc, OSError) and exc.filename is not None:
        return clip(f"{exc.filename}: {exc.strerror or exc}")
    return clip(str(exc))


def _format_warning(command):
    def fmt(message, category, filename, lineno, line=None):
        name = "warning" if category in (UserWarning, RuntimeWarning) else category.__name__
        return f"moorjax {command}: {name}: {clip(str(message))}\n"
    return fmt


def main(argv=None) -> int:
    """Run the command line on ``argv`` and return the exit code (see the module notes)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    args = build_parser().parse_args(argv)
    args.argv = argv
    saved = warnings.formatwarning
    warnings.formatwarning = _format_warning(args.command)
    try:
        return args.func(args)
    except KeyboardInterrupt:
        print(f"\nmoorjax {args.command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # whoever read the output stopped reading: nothing to say
        _silence_stdout()
        return EXIT_PIPE
    except (ValueError, RuntimeError, OSError, MemoryError, ImportError) as exc:
        print(f"moorjax {args.command}: error: {_message(exc)}", file=sys.stderr)
        return _exit_code(exc)
    finally:
        warnings.formatwarning = saved


def _silence_stdout() -> None:
    """Point the standard output at the null device, so that flushing what is
    still buffered for a closed pipe (at exit) neither fails nor complains."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # no real file behind sys.stdout
        pass


def run() -> None:  # pragma: no cover - the console entry point
    """``moorjax`` and ``python -m moorjax``: :func:`main`, exiting with its code."""
    _fewer_collections()
    try:
        code = main()
    except KeyboardInterrupt:  # while parsing or importing
        print("\nmoorjax: interrupted", file=sys.stderr)
        code = EXIT_INTERRUPTED
    leave(code)


#: objects allocated between two young-generation collections in a command
#: (Python's default is 700)
GC_YOUNG = 50_000


def _fewer_collections() -> None:
    """Python's garbage collector, tuned for one command's process.

    Tracing and loading JAX programs allocates millions of short-lived objects;
    at Python's default threshold every 700 allocations start a collection, and
    the older generations' collections walk everything imported (JAX, NumPy,
    moorjax). Measured with perf on a new process loading a stored simulation:
    7 % of its samples in ``gc_collect_main``. So the objects alive now (the
    imported modules) are moved out of the collector's sight (``gc.freeze``) and
    the young generation is collected every :data:`GC_YOUNG` allocations. Peak
    memory was unchanged (0.68 GB, 200-member ``moorjax ensemble``). The
    command line only: ``import moorjax`` leaves a user's process alone;
    ``MOORJAX_GC_TUNING=0`` (also ``false``/``off``/``no``) turns it off.
    """
    import gc

    from ._cache import _switched_on

    if not _switched_on("MOORJAX_GC_TUNING"):
        return
    gc.freeze()
    young, *older = gc.get_threshold()
    gc.set_threshold(max(young, GC_YOUNG), *older)


def leave(code: int) -> None:  # pragma: no cover - ends the process
    """End the process with ``code`` without Python's finalisation.

    A process that ran a simulation holds its compiled programs, and the
    interpreter's finalisation (its last garbage collections, then destroying
    XLA's executables and MLIR contexts) took 0.5 s after a 200-member
    ``moorjax ensemble`` (perf: ``gc_collect_main``, ``~CpuExecutable``,
    ``~HloModule``), on every call. Nothing is left to write by then: outputs
    are written and closed, stored programs and JAX's cache entries are written
    when compiled. So the streams are flushed and the process ends at once
    (``os._exit``), unless a compile started ahead is still running (its cache
    entry is worth the wait; Python then waits for it as before) or
    ``MOORJAX_FAST_EXIT=0`` (also ``false``/``off``/``no``).
    """
    import logging
    import os

    from ._cache import _switched_on, compiling

    if not _switched_on("MOORJAX_FAST_EXIT") or compiling():
        sys.exit(code)
    logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:  # e.g. a closed pipe: nothing more can be said
            pass
    os._exit(int(code or 0))


if __name__ == "__main__":  # pragma: no cover
    run()
