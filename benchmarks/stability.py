"""Stress test: does every hard run either finish plausibly or fail loudly?

Cases (reference decks A = ``oc3_catenary``, B = ``taut_polyester``):

- slack–snap: B with its fairlead surging x = a·sin(2πt/8), a = 2 m (the
  reference) and harsher a = 4, 6 m;
- very stiff lines: A and B with EA = 1e9 and 1e10 N (the axial law changed by
  ``equinox.tree_at``; values only, so no recompilation);
- a fine mesh: A and B with 400 segments;
- large fixed steps with the implicit solvers (``dt`` = 10, 20, 50 ms,
  kvaerno5 and implicit_euler);
- a long run: A at N = 20 for 3 hours (10 800 s, output every 1 s; ``--quick``
  shortens it to 300 s; compiled on two cheap runs with the fairlead held still,
  then run once);
- explicit solvers (heun, tsit5) at fixed steps beyond their stability limit,
  next to a heun run at a stable step.

Each run must end with finite, plausible tensions or with moorjax's
``RuntimeError`` naming the time and cause (recorded as the outcome). A run that
returns non-finite values without raising is flagged ``SILENT NaN`` and makes
the script exit with status 1 (report it: it must never happen).

    python benchmarks/stability.py [--quick] [--json out.json] [--reference DIR]
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from benchmarks.common import (  # noqa: E402
    CASES,
    NOISE_NOTE,
    base_parser,
    case_scene,
    jsonable,
    print_table,
    rel_error,
    static_init,
    timed_run,
    with_ea,
    write_json,
)


def plan(quick: bool, solver: str = "kvaerno5"):
    """(group, case, N, solver, settings text, scene kwargs, simulate kwargs, duration).

    ``solver``: the implicit method of the slack–snap, stiff, fine-mesh, large-step
    and long runs (default kvaerno5; implicit Euler's large-step runs stay)."""
    per = {"A": 10.0, "B": 8.0}
    t_ab = {c: (per[c] if quick else 3 * per[c]) for c in per}
    runs = []
    # slack–snap
    for amp in ((2.0, 4.0) if quick else (2.0, 4.0, 6.0)):
        runs.append(("slack-snap", "B", 20, solver, f"amp {amp:g} m", dict(amplitude=amp), {},
                     t_ab["B"]))
    # very stiff lines
    for case in ("A", "B"):
        for ea in ((1e10,) if quick else (1e9, 1e10)):
            runs.append(("stiff EA", case, 20, solver, f"EA {ea:.0e} N", dict(ea=ea), {},
                         t_ab[case]))
    # fine mesh
    for case in (("B",) if quick else ("A", "B")):
        runs.append(("fine mesh", case, 400, solver, "400 segments", {}, {},
                     1.0 if quick else 10.0))
    # large fixed steps, implicit
    fixed = [("A", solver, 0.05), ("B", "implicit_euler", 0.05)] if quick else [
        (c, s, dt) for c in ("A", "B") for s in (solver, "implicit_euler")
        for dt in (0.01, 0.02, 0.05)]
    for case, method, dt in fixed:
        runs.append(("large dt", case, 20, method, f"dt {1e3 * dt:g} ms", {}, dict(dt=dt), t_ab[case]))
    # a long run
    t_long = 300.0 if quick else 10_800.0
    runs.append(("long run", "A", 20, solver, f"{t_long:g} s, out 1 s", {},
                 dict(dt_out=1.0, warm="still"), t_long))
    # explicit solvers beyond their stability limit (and one stable control run)
    expl = [("A", "heun", 0.02), ("A", "tsit5", 0.02), ("A", "heun", 0.004)]
    if not quick:
        expl += [("B", "heun", 0.005), ("B", "tsit5", 0.005), ("B", "heun", 5e-4)]
    for case, method, dt in expl:
        runs.append(("explicit", case, 20, method, f"dt {1e3 * dt:g} ms", {}, dict(dt=dt),
                     per[case] if quick else t_ab[case]))
    return runs


def main(argv=None):
    p = base_parser(__doc__)
    p.add_argument("--solver", default="kvaerno5",
                   help="implicit method of the stress runs (default kvaerno5; e.g. ros34pw2)")
    args = p.parse_args(argv)
    print("moorjax stability stress test" + (" (--quick: shorter runs, long run 300 s "
                                                "instead of 10 800 s)" if args.quick else ""))
    print(NOISE_NOTE)
    rows, inits = [], {}
    for group, case, n, solver, settings, sc_kw, sim_kw, duration in plan(args.quick, args.solver):
        scene = case_scene(case, n, amplitude=sc_kw.get("amplitude"))
        if "ea" in sc_kw:
            scene = with_ea(scene, sc_kw["ea"])
        key = (case, n, sc_kw.get("ea"))  # the t = 0 equilibrium does not depend on the amplitude
        statics_s = float("nan")
        if key not in inits:
            t_a = time.perf_counter()
            try:
                inits[key] = static_init(scene)
            except Exception as exc:  # noqa: BLE001 - reported as the outcome below
                inits[key] = exc
            statics_s = time.perf_counter() - t_a
        if isinstance(inits[key], Exception):
            r = timed_run(scene, duration, solver=solver, **sim_kw)  # records the statics error
        else:
            r = timed_run(scene, duration, solver=solver, init=inits[key], **sim_kw)
        r["statics_s"] = statics_s
        standard = (sc_kw.get("amplitude", CASES[case].amplitude) == CASES[case].amplitude
                    and "ea" not in sc_kw and n <= 160 and duration <= 60.0)
        row = dict(group=group, case=case, N=n, solver=solver, settings=settings,
                   duration_s=duration, **r)
        row["rel_err"] = rel_error(r, case) if standard else None
        if r["outcome"] == "ok" and group == "long run":
            row["drift"] = _drift(r["result"], period=10.0)
        rows.append(row)
        print(f"  {group:<10} {case} N={n:<3} {solver:<14} {settings:<18} {duration:>7g} s  "
              f"{r['outcome'][:60]:<60} statics {r['statics_s']:5.1f} s  compile {r['compile_s']:6.1f} s  "
              f"run {r['run_s']:7.2f} s",
              flush=True)

    print_table(rows, [
        ("group", "group", ""), ("case", "case", ""), ("N", "N", "d"), ("solver", "solver", ""),
        ("settings", "settings", ""), ("sim s", "duration_s", "g"),
        ("outcome", lambda r: r["outcome"][:64], ""),
        ("max T [kN]", lambda r: r["max_tension_N"] / 1e3, ".1f"),
        ("err/std", lambda r: None if r["rel_err"] is None else f"{100 * r['rel_err']:.2f}%", ""),
        ("steps", "steps", "d"), ("rej", "rejected", "d"),
        ("statics [s]", "statics_s", ".1f"), ("compile [s]", "compile_s", ".1f"),
        ("run [s]", "run_s", ".2f"),
    ], title="stability (err/std: RMS end-B tension error vs the MoorDyn N=160 reference / its std,"
             " only for the unmodified cases; statics: first static solve of a scene, shared by"
             " the runs below it)")
    for r in rows:
        if "drift" in r:
            d = r["drift"]
            print(f"\nlong run: peak tension over the first 10 periods {d['first_kN']:.1f} kN, "
                  f"over the last 10 {d['last_kN']:.1f} kN (relative change {100 * d['rel']:.3f} %)")
    silent = [r for r in rows if r["silent_nan"]]
    bad = [r for r in rows if r["outcome"] == "IMPLAUSIBLE"]
    print(f"\nchecks: {len(rows)} runs, {sum(r['outcome'] == 'ok' for r in rows)} ok, "
          f"{sum(r['outcome'].startswith('error') for r in rows)} stopped with a RuntimeError, "
          f"{len(silent)} SILENT NaN, {len(bad)} implausible")
    for r in silent + bad:
        print(f"  !! {r['outcome']}: {r['group']} case {r['case']} N={r['N']} {r['solver']} "
              f"{r['settings']} — report this to the lead")
    write_json(args.json, dict(runs=jsonable(rows), quick=args.quick))
    return 1 if (silent or bad) else 0


def _drift(res, period):
    """Peak end-B tension over the first and last 10 periods of a long run."""
    t = np.asarray(res.ts)
    tb = np.asarray(res.tension_b[:, 0])
    first = tb[(t > period) & (t <= 11 * period)].max()
    last = tb[t > t[-1] - 10 * period].max()
    return dict(first_kN=first / 1e3, last_kN=last / 1e3, rel=(last - first) / first)


if __name__ == "__main__":
    sys.exit(main())
