"""Newton variants of the implicit methods on reference cases A and B.

For each chord root finder (``VeryChord``: diffrax's test on the iterated stage
derivatives [v, a]; ``StageChord``: the test on the stage state [r, v], see
:mod:`moorjax.dynamics.newton`; ``StageRefresh``: the same with the iteration
matrix rebuilt when Newton contracts slower than 0.5), each solver and case: adaptive runs at the
default tolerances (steps, rejected steps, ms per simulated second, error
against the MoorDyn N = 160 reference over its std) and fixed-step runs (do
they complete, and how accurate are they?).

    python benchmarks/newton.py [--cases A B] [--duration 20] [--quick]
                                [--reference DIR] [--json out.json]
"""

from __future__ import annotations

import os
import sys

import equinox as eqx

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from benchmarks.common import (  # noqa: E402
    NOISE_NOTE,
    base_parser,
    case_scene,
    jsonable,
    print_table,
    rel_error,
    static_init,
    timed_run,
    write_json,
)
from moorjax.dynamics.newton import StageChord, VeryChord  # noqa: E402
from moorjax.dynamics.solvers import make_solver  # noqa: E402

class RefreshChord(StageChord):
    """StageChord rebuilding its matrix when Newton contracts slower than 0.5."""

    refresh_rate: float | None = eqx.field(static=True, default=0.5)


NEWTONS = {"VeryChord": VeryChord, "StageChord": StageChord, "StageRefresh": RefreshChord}
#: (case, N, solver, fixed dt [s] or None)
PLAN = [("A", 40, "kvaerno5", None), ("A", 40, "kvaerno3", None),
        ("A", 40, "kvaerno5", 1e-2), ("A", 40, "kvaerno5", 2e-2), ("A", 40, "kvaerno5", 5e-2),
        ("B", 10, "kvaerno5", None), ("B", 10, "kvaerno3", None), ("B", 20, "kvaerno5", None),
        ("B", 20, "kvaerno5", 1e-2), ("B", 20, "kvaerno5", 2e-2)]
QUICK = [r for r in PLAN if r[3] in (None, 1e-2) and r[2] == "kvaerno5"]


def solver_for(name, newton, fixed):
    """The named implicit solver with the given chord class. Adaptive: Newton
    takes the controller's tolerances; fixed: moorjax's defaults 1e-5 / 1e-4 m."""
    import jax.numpy as jnp

    from moorjax.dynamics.solvers import StateNorm

    if fixed:
        return make_solver(name, newton_rtol=jnp.asarray(1e-5), newton_atol=jnp.asarray(1e-4),
                           norm=StateNorm(jnp.asarray(0.01)), newton=newton)
    return make_solver(name, newton=newton)


def main(argv=None):
    p = base_parser(__doc__)
    p.add_argument("--cases", nargs="+", default=["A", "B"])
    p.add_argument("--duration", type=float, default=20.0, help="simulated seconds (default 20)")
    p.add_argument("--newtons", nargs="+", default=list(NEWTONS), choices=list(NEWTONS))
    args = p.parse_args(argv)
    print(f"Newton variants, {args.duration:g} s simulated" + (" (--quick)" if args.quick else ""))
    print(NOISE_NOTE)
    rows, inits = [], {}
    for case, n, name, dt in (QUICK if args.quick else PLAN):
        if case not in args.cases:
            continue
        scene = case_scene(case, n)
        if (case, n) not in inits:
            inits[(case, n)] = static_init(scene)
        for label in args.newtons:
            kw = dict(solver=solver_for(name, NEWTONS[label], dt is not None), init=inits[(case, n)])
            if dt is not None:
                kw["dt"] = dt
            r = timed_run(scene, args.duration, **kw)
            r["rel_err"] = rel_error(r, case)
            r.pop("result")
            setting = "adaptive" if dt is None else f"dt {1e3 * dt:g} ms"
            rows.append(dict(case=case, N=n, solver=name, newton=label, setting=setting, **r))
            err = "-" if r["rel_err"] is None else f"{100 * r['rel_err']:.3f} %"
            print(f"  {case} N={n:<3d} {name:9s} {label:10s} {setting:9s} {r['outcome'][:48]:30s} "
                  f"steps {r['steps']} rej {r['rejected']} {r['ms_per_sim_s']:8.1f} ms/sim-s "
                  f"err {err}", flush=True)
    print_table(rows, [
        ("case", "case", ""), ("N", "N", "d"), ("solver", "solver", ""), ("newton", "newton", ""),
        ("setting", "setting", ""), ("outcome", lambda r: r["outcome"][:40], ""),
        ("steps", "steps", "d"), ("rejected", "rejected", "d"),
        ("ms/sim-s", "ms_per_sim_s", ".1f"), ("compile [s]", "compile_s", ".1f"),
        ("err/std", lambda r: None if r["rel_err"] is None else f"{100 * r['rel_err']:.3f}%", ""),
    ], title="error: RMS end-B tension − reference |F|, over its std")
    write_json(args.json, dict(runs=jsonable(rows), duration_s=args.duration, quick=args.quick))
    return 0


if __name__ == "__main__":
    sys.exit(main())
