"""The ``moorjax`` command line: statics and simulation of MoorDyn decks.

    moorjax statics DECK [--segments N] [--json]
    moorjax simulate DECK --duration T [--motion MOTION.csv] [--segments N]
        [--solver NAME] [--rtol R] [--atol A] [--atol-velocity AV] [--dt DT] [--dt-out 0.05]
        --out OUT.csv [--stats]
    moorjax ensemble DECK --duration T [--motion MOTION.csv] --vary NAME=v1,v2,...
        [--vary ...] --out DIR [--histories] [--chunk-size K] [simulate options]
    moorjax fit DECK --motion MOTION.csv --target TARGET.csv --params Cd_normal,Cd_axial[,...]
        [--line ID] [--steps K] --out FIT.json
    moorjax examples

DECK is a MoorDyn v2 input file or ``example:NAME`` for a bundled deck.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np


def _deck_path(arg: str) -> str:
    if arg.startswith("example:"):
        from .examples import example_path

        return example_path(arg.split(":", 1)[1])
    return arg


def _load(args, motion_path=None):
    from .io import build_scene, read_deck, read_deck_motion

    deck = read_deck(_deck_path(args.deck))
    motion = None
    if motion_path is not None:
        motion = read_deck_motion(motion_path, deck)
    return deck, build_scene(deck, segments=args.segments, motion=motion), motion


def cmd_statics(args) -> int:
    import jax

    from .statics import solve_line_statics

    _, scene, _ = _load(args)
    rows = []
    for line in scene.lines:
        st = solve_line_statics(line, scene.env, throw=False)
        st = jax.device_get(st)
        if not bool(st.converged):
            raise RuntimeError(
                f"line {line.label}: static solve did not converge "
                f"(max force imbalance {float(st.max_residual):.3g} N after "
                f"{int(st.iterations)} Newton iterations)"
            )
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


def _load_for_dynamics(args, with_motion=False):
    """Deck, scene and simulate() keyword arguments from the shared options
    (and the motion read, with ``with_motion``)."""
    if not (np.isfinite(args.duration) and args.duration > 0):
        raise ValueError(f"--duration = {args.duration} s must be > 0")
    deck, scene, motion = _load(args, args.motion)
    if motion is not None:
        _check_motion_covers(args.motion, motion.t, args.duration)
    kwargs = dict(
        solver=args.solver,
        rtol=args.rtol,
        atol=args.atol,
        atol_velocity=args.atol_velocity,
        dt=args.dt,
        dt_out=args.dt_out,
    )
    return (deck, scene, kwargs, motion) if with_motion else (deck, scene, kwargs)


def _check_motion_covers(path, t, duration):
    """The motion must cover the run, t = 0 to ``duration`` [s]: a ValueError
    naming the file and both time spans otherwise (no point is ever held still)."""
    tol = 1e-9 * max(1.0, duration)
    if t[0] > tol or t[-1] < duration - tol:
        raise ValueError(
            f"{path}: the motion covers t = {t[0]:.10g} to {t[-1]:.10g} s but the run needs "
            f"t = 0 to {duration:.10g} s (--duration); give the motion from t = 0 to at least "
            f"{duration:.10g} s (to hold a point still, add rows at its last position with "
            "zero velocity) or shorten --duration"
        )


def cmd_simulate(args) -> int:
    import jax

    from .dynamics import simulate
    from .io import coupled_body_ids, coupled_point_ids

    deck, scene, kwargs, motion = _load_for_dynamics(args, with_motion=True)
    t0 = time.perf_counter()
    res = simulate(scene, args.duration, **kwargs)
    jax.block_until_ready(res.tension_b)
    t1 = time.perf_counter()
    res = simulate(scene, args.duration, **kwargs) if args.stats else res
    jax.block_until_ready(res.tension_b)
    t2 = time.perf_counter()
    res = jax.device_get(res)

    ids = [ln.label for ln in scene.lines]
    point_ids = coupled_point_ids(deck)
    cols = ["t"]
    data = [np.asarray(res.ts)]
    for j, lid in enumerate(ids):
        cols += [f"L{lid}_tension_a", f"L{lid}_tension_b"]
        data += [res.tension_a[:, j], res.tension_b[:, j]]
    for pid in point_ids:
        total = np.zeros((len(res.ts), 3))
        for j, dl in enumerate(deck.lines):
            if dl.point_a == pid:
                total += res.force_a[:, j]
            if dl.point_b == pid:
                total += res.force_b[:, j]
        cols += [f"P{pid}_Fx", f"P{pid}_Fy", f"P{pid}_Fz"]
        data += [total[:, 0], total[:, 1], total[:, 2]]
    for bid in coupled_body_ids(deck):
        cols += [f"B{bid}_{c}" for c in ("Fx", "Fy", "Fz", "Mx", "My", "Mz")]
        data += list(_body_loads(deck, scene, motion, res, bid).T)
    np.savetxt(args.out, np.column_stack(data), delimiter=",", header=",".join(cols), comments="")
    if args.stats:
        stats = dict(
            compile_s=(t1 - t0) - (t2 - t1),
            run_s=t2 - t1,
            steps=int(res.num_steps),
            rejected_steps=int(res.num_rejected_steps),
            accepted_steps=int(res.num_accepted_steps),
            solver=args.solver,
        )
        print(json.dumps(stats), file=sys.stderr)
    return 0


def _body_loads(deck, scene, motion, res, body_id):
    """(k, 6) force [N] and moment about the body's reference point [N·m] (global
    axes) of the lines on a coupled body, at the output times."""
    import jax

    from .io import body_reference_end

    ts = np.asarray(res.ts)
    ref = np.asarray(jax.vmap(body_reference_end(deck, body_id, motion).position)(ts))
    out = np.zeros((len(ts), 6))
    for j, dl in enumerate(deck.lines):
        for name, pid, force in (("a", dl.point_a, res.force_a), ("b", dl.point_b, res.force_b)):
            if deck.points[pid].body != body_id:
                continue
            end = getattr(scene.lines[j], f"end_{name}")
            r = np.asarray(jax.vmap(end.position)(ts))
            f = np.asarray(force[:, j])
            out[:, :3] += f
            out[:, 3:] += np.cross(r - ref, f)
    return out


def cmd_ensemble(args) -> int:
    import os

    from .ensemble.store import SUMMARY_STATS, run_chunked
    from .ensemble.vary import parse_vary, sweep

    varies = [parse_vary(v) for v in args.vary]  # names checked before any work
    _, scene, kwargs = _load_for_dynamics(args)
    members, table = sweep(scene, varies)
    t0 = time.perf_counter()
    data = run_chunked(
        members, args.out, args.duration, chunk_size=args.chunk_size,
        histories=args.histories, **kwargs,
    )
    wall = time.perf_counter() - t0
    ids = [ln.label for ln in scene.lines]
    names = [n for n, _ in varies]
    cols = ["member"] + names + ["status", "steps"]
    for j, lid in enumerate(ids):
        for end in ("tension_a", "tension_b"):
            cols += [f"L{lid}_{end}_{st}" for st in SUMMARY_STATS]
    with open(os.path.join(args.out, "summary.csv"), "w") as f:
        f.write(",".join(cols) + "\n")
        for i, row in enumerate(table):
            vals = [str(i)] + [repr(row[n]) for n in names]
            vals += [str(data["status"][i]), str(int(data["num_steps"][i]))]
            for j in range(len(ids)):
                for end in ("tension_a", "tension_b"):
                    vals += [f"{data[f'stat_{end}_{st}'][i, j]:.9g}" for st in SUMMARY_STATS]
            f.write(",".join(vals) + "\n")
    if args.histories:
        hdir = os.path.join(args.out, "histories")
        os.makedirs(hdir, exist_ok=True)
        hcols = ["t"] + [f"L{lid}_{end}" for lid in ids for end in ("tension_a", "tension_b")]
        for i in range(len(table)):
            cols_i = [data["ts"]]
            for j in range(len(ids)):
                cols_i += [data["tension_a"][i, :, j], data["tension_b"][i, :, j]]
            np.savetxt(os.path.join(hdir, f"member_{i:05d}.csv"), np.column_stack(cols_i),
                       delimiter=",", header=",".join(hcols), comments="")
    n_bad = int(np.sum(data["status"] != "ok"))
    print(
        f"{len(table)} members in {wall:.1f} s; {n_bad} failed; summary: "
        f"{os.path.join(args.out, 'summary.csv')}",
        file=sys.stderr,
    )
    return 0


def cmd_examples(args) -> int:
    from .examples import EXAMPLES, example_path

    for name in EXAMPLES:
        print(f"example:{name}\t{example_path(name)}")
    return 0


def _positive_int(text):
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {v}")
    return v


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="moorjax", description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("statics", help="static equilibrium of every line of a deck")
    s.add_argument("deck", help="MoorDyn v2 deck, or example:NAME")
    s.add_argument("--segments", type=_positive_int, help="override every line's segment count")
    s.add_argument("--json", action="store_true", help="print JSON (one object per line)")
    s.set_defaults(func=cmd_statics)

    d = sub.add_parser("simulate", help="time-domain simulation of a deck")
    _dynamics_options(d)
    d.add_argument("--out", required=True, help="output CSV")
    d.add_argument("--stats", action="store_true", help="print one JSON line of statistics to stderr")
    d.set_defaults(func=cmd_simulate)

    en = sub.add_parser("ensemble", help="parameter sweep of a deck as one vmapped ensemble")
    _dynamics_options(en)
    en.add_argument(
        "--vary", action="append", required=True, metavar="NAME=v1,v2,...",
        help="parameter values (repeatable; members are all combinations). Names: "
        "EA, BA, Cd, CdAx, Ca, CaAx, d, mass, length (optionally L<id>.NAME for one line), "
        "depth, rho, kBot, cBot",
    )
    en.add_argument("--out", required=True, help="output directory (resumed if it exists)")
    en.add_argument("--histories", action="store_true", help="also write each member's tension history")
    en.add_argument("--chunk-size", type=_positive_int, default=100, help="members per compiled batch")
    en.set_defaults(func=cmd_ensemble)

    from .identify.cli import add_parser as add_fit_parser

    add_fit_parser(sub)

    e = sub.add_parser("examples", help="list the bundled example decks")
    e.set_defaults(func=cmd_examples)
    return p


def _dynamics_options(d):
    """Options shared by simulate and ensemble."""
    from .dynamics.solvers import SOLVERS

    d.add_argument("deck", help="MoorDyn v2 deck, or example:NAME")
    d.add_argument("--duration", type=float, required=True, help="simulated time [s]")
    d.add_argument("--motion", help="CSV of coupled-point and coupled-body motion "
                   "(t, P<id>_x, ..., B<id>_x, ..., B<id>_roll [rad], ...)")
    d.add_argument("--segments", type=_positive_int, help="override every line's segment count")
    d.add_argument("--solver", default="kvaerno5", choices=SOLVERS, help="time stepper")
    d.add_argument("--rtol", type=float, default=1e-5, help="relative tolerance (default 1e-5)")
    d.add_argument(
        "--atol", type=float, default=1e-4, help="absolute tolerance of positions [m] (default 1e-4)"
    )
    d.add_argument(
        "--atol-velocity",
        type=float,
        help="absolute tolerance of velocities [m/s] (default 100*atol per s)",
    )
    d.add_argument("--dt", type=float, help="fixed step [s] (default: adaptive)")
    d.add_argument("--dt-out", type=float, default=0.05, help="output interval [s]")


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (ValueError, RuntimeError, OSError) as exc:
        print(f"moorjax {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
