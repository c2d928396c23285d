"""``moorjax ensemble``: a parameter sweep of a deck as chunked, vmapped batches
(``DIR/summary.csv``, ``DIR/ensemble.nc``, optional histories; resumable)."""

from __future__ import annotations

import sys
import time

import numpy as np

from .._cli_common import add_subcommand, dynamics_options, positive_int
from .._cli_load import command_line, load_for_dynamics, motion_path, resolved_settings


def add_parser(subparsers):
    """Add the ``ensemble`` sub-command to an ``argparse`` sub-parser collection."""
    en = add_subcommand(subparsers, "ensemble", "parameter sweep of a deck as one vmapped ensemble",
              "moorjax ensemble example:taut_polyester --duration 20 --segments 20 "
              "--vary Cd=1.2,1.6,2.0 --out sweep")
    dynamics_options(en)
    en.add_argument(
        "--vary", action="append", required=True, metavar="NAME=v1,v2,...",
        help="parameter values (repeatable; members are all combinations). Names: "
        "EA, BA, Cd, CdAx, Ca, CaAx, d, mass, length (optionally L<id>.NAME for one line), "
        "depth, rho, kBot, cBot",
    )
    en.add_argument("--out", required=True,
                    help="output directory (resumed if it exists): summary.csv, ensemble.nc")
    en.add_argument("--histories", action="store_true", help="also write each member's tension history")
    en.add_argument("--chunk-size", type=positive_int, default=100, help="members per compiled batch")
    en.add_argument("--cpu-devices", type=positive_int, default=None, metavar="N",
                    help="on CPU, split the host into N JAX devices and shard each chunk's members over "
                    "them (default: one per available core; 1 runs on one core; a count set in "
                    "XLA_FLAGS is kept)")
    en.set_defaults(func=cmd_ensemble)
    return en


def _may_call_lapack(args) -> bool:
    """Whether the deck's ensemble may call batched LAPACK kernels (see
    :func:`moorjax.ensemble.use_cpu_cores`), from the deck's text alone (JAX must
    not start before the devices are set): all but linear-element lines between
    fixed and coupled points, without bodies or bending, under ``auto``,
    ``ros34pw2`` or an explicit solver. Unreadable decks count as True (their
    error comes later, from the loader)."""
    from .._cli_common import deck_path
    from ..dynamics.solvers import EXPLICIT, LINEARLY_IMPLICIT
    from ..io import read_deck

    if (args.element or "linear") != "linear":
        return True
    # by name, the solvers of dynamics.settings.factorises_nothing_dense (and
    # auto, which picks ROS34PW2 for such decks)
    if (args.solver or "auto").lower() not in ("auto", *LINEARLY_IMPLICIT, *EXPLICIT):
        return True
    try:
        deck = read_deck(deck_path(args.deck))
    except Exception:  # noqa: BLE001 - reported by the loader
        return True
    return bool(deck.bodies
                or any(p.attachment not in ("fixed", "coupled") for p in deck.points.values())
                or any(float(lt.ei or 0.0) > 0.0 for lt in deck.line_types.values()))


def cmd_ensemble(args) -> int:
    import os

    from .._progress import Progress, enabled
    from .devices import use_cpu_cores
    from .store import SUMMARY_STATS, run_chunked
    from .vary import parse_vary, sweep

    use_cpu_cores(args.cpu_devices, lapack=_may_call_lapack(args))  # before JAX computes anything

    varies = [parse_vary(v) for v in args.vary]  # names checked before any work
    if os.path.exists(args.out) and not os.path.isdir(args.out):
        raise ValueError(f"--out {args.out}: exists and is not a directory")
    parent = os.path.dirname(os.path.abspath(args.out))
    if not os.path.isdir(parent):
        raise ValueError(f"--out {args.out}: folder {parent} does not exist")
    _, scene, kwargs = load_for_dynamics(args)
    kwargs = resolved_settings(kwargs, scene)
    members, table = sweep(scene, varies)
    prog = Progress("ensemble", enabled(args.quiet))
    n_chunks = -(-len(members) // min(args.chunk_size, len(members)))
    import jax

    where = f"{len(jax.local_devices())} {jax.default_backend().upper()} device(s)"
    prog.say(f"{len(members)} members in {n_chunks} chunk(s) of up to {args.chunk_size}, on "
             f"{where}; compiling…")

    def on_chunk(k, n):
        prog.bar((k + 1) / n, f"chunk {k + 1}/{n} done, {prog.elapsed():.0f} s")

    t0 = time.perf_counter()
    data = run_chunked(
        members, args.out, args.duration, chunk_size=args.chunk_size,
        histories=args.histories, on_chunk=on_chunk, **kwargs,
    )
    prog.close()
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
                       delimiter=",", header=",".join(hcols), comments="", fmt="%.15g")
    from ..io.ensemble import ensemble_dataset

    ds = ensemble_dataset(data, table, names, ids, attrs=dict(
        deck=args.deck, motion=motion_path(args) or "none",
        settings=dict(kwargs, duration=args.duration, segments=args.segments),
        history=command_line(args)))
    from ..io.results import write_netcdf

    write_netcdf(ds, os.path.join(args.out, "ensemble.nc"))
    n_bad = int(np.sum(data["status"] != "ok"))
    print(
        f"{len(table)} members in {wall:.1f} s on {where}; {n_bad} failed; summary: "
        f"{os.path.join(args.out, 'summary.csv')}, {os.path.join(args.out, 'ensemble.nc')}",
        file=sys.stderr,
    )
    return 0
