"""``moorjax fit``: identify line parameters from a measured tension history.

    moorjax fit DECK --motion MOTION.csv --target TARGET.csv --params Cd_normal,Cd_axial
        [--line ID] [--steps K] [--start NAME=VALUE ...] [--window T0,T1]
        [--segments N] [--dt DT] [--solver NAME] [--rtol R] [--atol A]
        [--optimizer lbfgs|adam] [--learning-rate LR] [--no-covariance] --out FIT.json

TARGET.csv has the columns ``moorjax simulate`` writes (``t``, ``L<id>_tension_a``,
``L<id>_tension_b``, ...); every tension column of the fitted line(s) enters the
misfit. FIT.json holds, per parameter, the initial and fitted values, unit and
standard deviation, plus the initial and final loss, iterations, gradient norm,
loss history and status.

Beside :mod:`moorjax.identify`, not in it: every command line builds this
parser, and importing the package loads the fitting machinery (optax), which
no other command needs (0.06 s of import time; ``moorjax statics`` on the built-in
example went from 1.38 to 1.345 s, medians of six).
"""

from __future__ import annotations

import json
import sys


def add_parser(subparsers):
    """Add the ``fit`` sub-command to an ``argparse`` sub-parser collection."""
    from ._cli_common import HelpFormatter, element_option
    from .dynamics.solvers import SOLVERS

    f = subparsers.add_parser(
        "fit", help="fit line parameters to a measured tension history",
        description="Fit line parameters to a measured tension history.",
        formatter_class=HelpFormatter,
        epilog="example:\n  moorjax fit example:oc3_catenary --target run.csv --params Cd_normal "
               "--segments 10 --steps 5 --out fit.json",
    )
    f.add_argument("deck", help="MoorDyn v2 deck, or example:NAME")
    f.add_argument("--motion", required=True,
                   help="CSV of coupled-point motion (t, P<id>_x, ...) over the target's time span")
    f.add_argument("--target", required=True,
                   help="CSV of measured tensions: t, L<id>_tension_a/_b (moorjax simulate columns)")
    f.add_argument("--params", required=True, metavar="NAME[,NAME...]",
                   help="free parameters, e.g. Cd_normal,Cd_axial (names of moorjax.model.parameters: "
                        "EA, BA, Cd_normal, Cd_axial, Ca_normal, Ca_axial, d, mass, length, ...)")
    f.add_argument("--line", help="fit this line's parameters (prefix L<id>.) to its tension columns")
    f.add_argument("--steps", type=int, default=50, help="maximum optimiser steps (default 50)")
    f.add_argument("--start", action="append", default=[], metavar="NAME=VALUE",
                   help="start value of a free parameter (default: the deck's value); repeatable")
    f.add_argument("--window", metavar="T0,T1", help="only samples with T0 <= t <= T1 [s] count")
    f.add_argument("--segments", type=int, help="override every line's segment count (default: the deck's)")
    element_option(f)
    f.add_argument("--dt", type=float, default=0.01, help="fixed time step [s] (default 0.01)")
    f.add_argument("--solver", default="kvaerno3", choices=SOLVERS, help="time stepper (default kvaerno3)")
    f.add_argument("--rtol", type=float, default=1e-6, help="Newton relative tolerance (default 1e-6)")
    f.add_argument("--atol", type=float, default=1e-6, help="Newton absolute tolerance [m] (default 1e-6)")
    f.add_argument("--optimizer", default="lbfgs", choices=("lbfgs", "adam"),
                   help="optax optimiser (default lbfgs)")
    f.add_argument("--learning-rate", type=float, default=0.05, help="adam learning rate (default 0.05)")
    f.add_argument("--no-covariance", action="store_true", help="skip the Gauss-Newton covariance")
    f.add_argument("--out", required=True, help="output JSON")
    f.add_argument("--quiet", "-q", action="store_true",
                   help="no progress on stderr (it is off anyway when stderr is not a terminal)")
    f.set_defaults(func=cmd_fit)
    return f


def _prefixed(name, line):
    """``Cd`` -> ``L<line>.Cd`` for a line parameter when --line is given."""
    from .model.parameters import PARAMETERS, split_name

    label, base = split_name(name)
    if line is None or label is not None or base not in PARAMETERS:
        return name
    return f"L{line}.{name}" if PARAMETERS[base].scope == "line" else name


def _parse_params(text, line):
    """(names as given, names used in the fit)."""
    from .model.parameters import check_name

    given = [n.strip() for n in text.split(",") if n.strip()]
    if not given:
        raise ValueError("--params: give at least one parameter name, e.g. Cd_normal")
    for n in given:
        check_name(n)
    return given, [_prefixed(n, line) for n in given]


def _parse_start(items, names, line):
    starts = {}
    for item in items:
        if "=" not in item:
            raise ValueError(f"--start {item!r}: expected NAME=VALUE")
        k, v = (x.strip() for x in item.split("=", 1))
        k = _prefixed(k, line)
        if k not in names:
            raise ValueError(f"--start {item!r}: {k} is not one of the free parameters {', '.join(names)}")
        try:
            starts[k] = float(v)
        except ValueError:
            raise ValueError(f"--start {item!r}: {v!r} is not a number") from None
    return starts


def _parse_window(text):
    if text is None:
        return None
    try:
        lo, hi = (float(x) for x in text.split(","))
    except ValueError:
        raise ValueError(f"--window {text!r}: expected T0,T1 in seconds") from None
    return lo, hi


def cmd_fit(args) -> int:
    import equinox as eqx
    import optax

    from ._cli_common import deck_path
    from ._cli_load import element_from, graded_as_asked
    from ._progress import Progress, enabled
    from .identify.experiment import load_experiment
    from .identify.fit import default_optimizer, fit
    from .identify.free import Free
    from .io.results import check_output

    if args.steps < 0:
        raise ValueError(f"--steps = {args.steps} must be >= 0")
    if args.segments is not None and args.segments < 1:
        raise ValueError(f"--segments = {args.segments} must be >= 1")
    check_output(args.out, (".json",))
    motion = args.motion
    given, names = _parse_params(args.params, args.line)
    starts = _parse_start(args.start, names, args.line)
    exp = load_experiment(
        deck_path(args.deck), motion, args.target, segments=args.segments,
        line=args.line, window=_parse_window(args.window), element=element_from(args),
    )
    exp = eqx.tree_at(lambda e: e.scene, exp, graded_as_asked(args, exp.scene))
    free = [Free(n, starts.get(n)) for n in names]
    if args.optimizer == "adam":
        opt = optax.adam(args.learning_rate)
    else:
        opt = default_optimizer()
    prog = Progress("fit", enabled(args.quiet))
    prog.say(f"{len(names)} parameter(s), up to {args.steps} steps; compiling the simulation and "
             "its gradient (a minute or more)…")

    def report(it, values, loss, grad_norm=None):
        vals = ", ".join(f"{k} {v:.6g}" for k, v in values.items())
        grad = "" if grad_norm is None else f", |gradient| {grad_norm:.3g}"
        prog.say(f"step {it}/{args.steps}: loss {loss:.6g}{grad}; {vals} ({prog.elapsed():.0f} s)")

    res = fit(
        exp, free, optimizer=opt, steps=args.steps, dt=args.dt, solver=args.solver,
        rtol=args.rtol, atol=args.atol, covariance=not args.no_covariance, callback=report,
    )
    out = res.to_json()
    out["params"] = {g: out["params"][n] for g, n in zip(given, names)}
    out["settings"]["optimizer"] = args.optimizer
    out.update(deck=args.deck, motion=motion, target=args.target,
               channels=list(exp.names), line=args.line)
    out["settings"].update(segments=args.segments, window=_parse_window(args.window))
    with open(args.out, "w") as fh:
        json.dump(out, fh, indent=2)
    summary = ", ".join(f"{g}: {res.initial[n]:.6g} -> {res.values[n]:.6g}" for g, n in zip(given, names))
    print(f"{summary}; loss {res.initial_loss:.4g} -> {res.final_loss:.4g} in "
          f"{res.iterations} steps ({res.status}); wrote {args.out}", file=sys.stderr)
    if res.status == "nonfinite":
        raise RuntimeError(f"{res.message} (last good values written to {args.out})")
    return 0
