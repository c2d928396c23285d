"""Cost of one integration step of a line, per solver, beside its error.

For reference cases A and B: each solver at the given tolerances is run for
``--duration`` simulated seconds from the static equilibrium (solved once,
outside the timing), the call repeated ``--repeats`` times; the best wall time
is kept (the first call compiles, so the best is a run without compile). Reported
per row: steps tried (diffrax's ``num_steps``, rejected ones included), µs per
step, ms per simulated second and the error against the MoorDyn N = 160
reference (RMS of the fairlead |F| − reference, over the reference's std), so
a cheaper step is never read without its accuracy.

The XLA flags in force (``XLA_FLAGS`` after ``import moorjax``) are printed and
stored: an A/B of XLA options is two runs of this script, e.g. with and without
``MOORJAX_XLA_TUNING=0``.

    python benchmarks/per_step.py [--cases A B] [--duration 20] [--repeats 5]
                                  [--solvers auto ros34pw2 kvaerno3] [--quick]
                                  [--reference DIR] [--json out.json]
"""

from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from benchmarks.common import (  # noqa: E402
    NOISE_NOTE,
    _call,
    base_parser,
    case_scene,
    jsonable,
    print_table,
    rel_error,
    short_error,
    static_init,
    write_json,
)

#: segments per case (each case's cheapest N at about 1 % error)
SEGMENTS = {"A": 40, "B": 10}
#: solver -> (rtol, atol) the rows use; ``auto`` at moorjax's defaults
SOLVERS = {"auto": (1e-5, 1e-4), "ros34pw2": (1e-4, 1e-3), "kvaerno3": (1e-5, 1e-4),
           "kvaerno5": (1e-5, 1e-4)}


def best_run(scene, duration, repeats, **kwargs):
    """(best wall time of ``repeats`` calls [s], first call's time [s], last
    result or None, error message): each call is :func:`common._call`, so a run
    that stops with moorjax's RuntimeError is reported, not raised."""
    times, res, err = [], None, ""
    for _ in range(repeats):
        res, err, wall, _ = _call(scene, duration, kwargs)
        if res is None:
            return None, None, None, err
        times.append(wall)
    return min(times[1:]), times[0], res, err


def main(argv=None):
    p = base_parser(__doc__)
    p.add_argument("--cases", nargs="+", default=["A", "B"], choices=sorted(SEGMENTS))
    p.add_argument("--duration", type=float, default=20.0, help="simulated seconds (default 20)")
    p.add_argument("--repeats", type=int, default=5,
                   help="calls per row, the best is kept (default 5; at least 2)")
    p.add_argument("--solvers", nargs="+", default=["auto", "ros34pw2", "kvaerno3"],
                   choices=list(SOLVERS))
    args = p.parse_args(argv)
    if args.repeats < 2:
        p.error("--repeats must be at least 2 (the first call compiles)")
    if args.quick:
        args.duration, args.repeats = min(args.duration, 10.0), min(args.repeats, 3)
    flags = os.environ.get("XLA_FLAGS", "")
    print(f"Cost per step, {args.duration:g} s simulated, best of {args.repeats} calls")
    print(f"XLA_FLAGS: {flags or '(none)'}")
    print(NOISE_NOTE)
    rows = []
    for case in args.cases:
        n = SEGMENTS[case]
        scene = case_scene(case, n)
        init = static_init(scene)
        for solver in args.solvers:
            rtol, atol = SOLVERS[solver]
            run_s, first_s, res, message = best_run(scene, args.duration, args.repeats,
                                                    init=init, solver=solver, rtol=rtol, atol=atol)
            row = dict(case=case, N=n, solver=solver, rtol=rtol, atol=atol,
                       outcome="ok" if res is not None else "error: " + short_error(message),
                       message=message, steps=None, rejected=None, run_s=run_s,
                       compile_s=None, us_per_step=None, ms_per_sim_s=None, rel_err=None)
            if res is None:
                rows.append(row)
                print(f"  {case} N={n:<3d} {solver:9s} {rtol:g}/{atol:g}: {row['outcome']}",
                      flush=True)
                continue
            steps, rejected = int(res.num_steps), int(res.num_rejected_steps)
            err = rel_error(dict(result=res, outcome="ok"), case)
            row.update(steps=steps, rejected=rejected, compile_s=max(first_s - run_s, 0.0),
                       us_per_step=1e6 * run_s / max(steps, 1),
                       ms_per_sim_s=1e3 * run_s / args.duration, rel_err=err)
            rows.append(row)
            shown = "-" if err is None else f"{100 * err:.3f} %"
            print(f"  {case} N={n:<3d} {solver:9s} {rtol:g}/{atol:g}: steps {steps} "
                  f"({rejected} rejected) {row['us_per_step']:7.1f} µs/step "
                  f"{row['ms_per_sim_s']:7.2f} ms/sim-s err {shown}", flush=True)
    print_table(rows, [
        ("case", "case", ""), ("N", "N", "d"), ("solver", "solver", ""),
        ("rtol/atol", lambda r: f"{r['rtol']:g}/{r['atol']:g}", ""),
        ("outcome", lambda r: r["outcome"][:40], ""),
        ("steps", "steps", "d"), ("rejected", "rejected", "d"),
        ("µs/step", "us_per_step", ".1f"), ("ms/sim-s", "ms_per_sim_s", ".2f"),
        ("compile [s]", "compile_s", ".1f"),
        ("err/std", lambda r: None if r["rel_err"] is None else f"{100 * r['rel_err']:.3f}%", ""),
    ], title="steps: all steps tried, rejected included; µs/step: best run time over "
             "them; error: RMS end-B tension − reference |F|, over its std")
    write_json(args.json, dict(runs=jsonable(rows), duration_s=args.duration,
                               repeats=args.repeats, xla_flags=flags, quick=args.quick))
    return 0


if __name__ == "__main__":
    sys.exit(main())
