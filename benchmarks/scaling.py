"""Cost against the number of segments, and compile time.

(a) Per-step cost of one line (reference case A, adaptive kvaerno5, default
    tolerances) for N = 20 … 320 segments: run time / number of steps (accepted
    and rejected: each costs a Jacobian, a factorisation and the stage solves),
    per step and per step per node, with the fitted exponent of cost ∝ N^p
    (expected p ≈ 1: the Newton solve is block-tridiagonal, O(N)). The same runs
    with ``linear_solver="dense"`` (dense LU of the 6(N−1) system, O(N³)) show
    what the structured solve avoids.
(b) Compile time of one line (case A, N = 20) with kvaerno5 and kvaerno3, each
    measured in a fresh Python process: the first ``simulate`` call (statics and
    integrator, with XLA's backend-compile share) minus the run time of a second
    call. Target: under 5 s.

    python benchmarks/scaling.py [--quick] [--json out.json] [--reference DIR]
"""

from __future__ import annotations

import time

_T_START = time.perf_counter()  # before jax/moorjax are imported (compile probe)

import json  # noqa: E402
import os  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from benchmarks.common import (  # noqa: E402
    NOISE_NOTE,
    base_parser,
    case_scene,
    fmt,
    jsonable,
    print_table,
    static_init,
    timed_run,
    write_json,
)

COMPILE_TARGET_S = 5.0
DENSE_DURATION_S = 0.5  # [s] simulated by the dense runs (slow: O(N³) per step)


_INITS = {}  # (case, N) -> static equilibrium (moorjax recompiles the static solve per call)


def per_step(ns, linear_solver, duration, case="A"):
    rows = []
    for n in ns:
        scene = case_scene(case, n)
        if (case, n) not in _INITS:
            _INITS[case, n] = static_init(scene)
        r = timed_run(scene, duration, init=_INITS[case, n], linear_solver=linear_solver, solver="kvaerno5")
        us = 1e6 * r["run_s"] / r["steps"] if r["steps"] else float("nan")
        rows.append(dict(case=case, N=n, linear_solver=linear_solver, duration_s=duration,
                         us_per_step=us, us_per_step_node=us / (n - 1), **r))
        print(f"  N={n:<4d} {linear_solver:<8} {r['outcome'][:50]:<12} steps {r['steps']}  "
              f"{us:9.1f} µs/step  compile {r['compile_s']:5.1f} s", flush=True)
    return rows


def fit_exponent(rows, n_min=0):
    pts = [(r["N"], r["us_per_step"]) for r in rows
           if r["N"] >= n_min and r["outcome"] == "ok" and np.isfinite(r["us_per_step"])]
    if len(pts) < 2:
        return None
    n, c = np.log(np.array(pts)).T
    return float(np.polyfit(n, c, 1)[0])


def compile_probe(solver: str) -> dict:
    """Run in a fresh process: time the static solve and two simulate calls.

    The static solve is timed twice (moorjax currently recompiles it on every
    call); the integrator's compile time is the first ``simulate(init=...)``
    call minus the second. Wall and process CPU time are both recorded (CPU
    time is steadier on a loaded machine).
    """
    import jax
    import jax.monitoring

    from moorjax.dynamics import simulate

    t_import = time.perf_counter() - _T_START
    backend = []
    jax.monitoring.register_event_duration_secs_listener(
        lambda event, dur, **kw: backend.append(dur)
        if event == "/jax/core/compile/backend_compile_duration" else None)
    scene = case_scene("A", 20)
    duration = 1.0

    def timed(fn):
        del backend[:]
        t_a, c_a = time.perf_counter(), time.process_time()
        out = jax.block_until_ready(fn())
        return out, time.perf_counter() - t_a, time.process_time() - c_a, float(sum(backend))

    init, st1, st1_cpu, st1_xla = timed(lambda: static_init(scene))
    _, st2, _, st2_xla = timed(lambda: static_init(scene))
    res, s1, s1_cpu, s1_xla = timed(lambda: simulate(scene, duration, solver=solver, init=init))
    res, s2, s2_cpu, _ = timed(lambda: simulate(scene, duration, solver=solver, init=init))
    return dict(solver=solver, N=20, import_s=t_import,
                statics_first_s=st1, statics_first_cpu_s=st1_cpu, statics_first_xla_s=st1_xla,
                statics_again_s=st2, statics_again_xla_s=st2_xla,
                compile_s=s1 - s2, compile_cpu_s=s1_cpu - s2_cpu, compile_xla_s=s1_xla,
                run_s=s2, first_call_total_s=st1 + s1, steps=int(res.num_steps),
                outcome="ok" if bool(res.succeeded()) else "error")


def compile_times(solvers):
    rows = []
    for solver in solvers:
        cmd = [sys.executable, os.path.abspath(__file__), "--probe", solver]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            rows.append(dict(solver=solver, outcome="error: " + proc.stderr.strip()[-200:]))
        else:
            rows.append(json.loads(proc.stdout.strip().splitlines()[-1]))
        r = rows[-1]
        print(f"  {solver}: {r['outcome']}  compile {r.get('compile_s', float('nan')):.2f} s", flush=True)
    return rows


def main(argv=None):
    p = base_parser(__doc__)
    p.add_argument("--probe", help=argparse_hidden())
    args = p.parse_args(argv)
    if args.probe:
        print(json.dumps(compile_probe(args.probe)))
        return 0
    print("moorjax scaling: case A, adaptive kvaerno5, rtol 1e-5, atol 1e-4 m")
    print(NOISE_NOTE)
    duration = 1.0 if args.quick else 4.0
    ns = [20, 40, 80, 160, 320]
    ns_dense = [20, 30, 40] if args.quick else [20, 30, 40, 80, 160]
    print("\n(a) per-step cost")
    rows = per_step(ns, "reduced", duration)
    rows += per_step(ns_dense, "dense", DENSE_DURATION_S)
    if not args.quick:
        rows += per_step(ns, "block", duration)
    fits = {}
    for ls in ("reduced", "block", "dense"):
        sel = [r for r in rows if r["linear_solver"] == ls]
        if sel:
            fits[ls] = dict(all=fit_exponent(sel), from_n40=fit_exponent(sel, 40))
    print_table(rows, [
        ("linear solve", "linear_solver", ""), ("N", "N", "d"), ("outcome", "outcome", ""),
        ("steps", "steps", "d"), ("rej", "rejected", "d"), ("µs/step", "us_per_step", ".1f"),
        ("µs/step/node", "us_per_step_node", ".2f"), ("ms/sim-s", "ms_per_sim_s", ".1f"),
        ("compile [s]", "compile_s", ".1f"),
    ], title=f"(a) per-step cost, case A, {duration:g} s simulated "
             f"(dense: {DENSE_DURATION_S:g} s)")
    for ls, f in fits.items():
        print(f"  fitted exponent p (µs/step ∝ N^p), {ls}: all N {fmt(f['all'], '.2f')}, "
              f"N ≥ 40 {fmt(f['from_n40'], '.2f')}")
    print("\n(b) compile time, case A, N = 20, 1 s simulated (fresh process each)")
    comp = compile_times(["kvaerno5", "kvaerno3"])
    print_table(comp, [
        ("solver", "solver", ""), ("outcome", "outcome", ""),
        ("integrator compile [s]", "compile_s", ".2f"), ("(CPU [s])", "compile_cpu_s", ".2f"),
        ("(XLA backend [s])", "compile_xla_s", ".2f"),
        ("statics 1st [s]", "statics_first_s", ".2f"), ("statics again [s]", "statics_again_s", ".2f"),
        ("1st simulate total [s]", "first_call_total_s", ".2f"), ("run 1 s sim [s]", "run_s", ".3f"),
        ("target", lambda r: "-" if "compile_s" not in r else
         ("met" if r["compile_s"] < COMPILE_TARGET_S else f"MISSED (> {COMPILE_TARGET_S:g} s)"), ""),
    ], title="(b) compile time (target: integrator compile < 5 s; '1st simulate total' = what a "
             "user waits on the first call = statics 1st + integrator compile + run)")
    write_json(args.json, dict(per_step=jsonable(rows), exponents=fits, compile=comp,
                               quick=args.quick, duration_s=duration))
    return 0


def argparse_hidden():
    import argparse

    return argparse.SUPPRESS


if __name__ == "__main__":
    sys.exit(main())
