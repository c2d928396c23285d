"""Ensemble cost: vmapped moorjax ensembles against one-by-one runs and MoorDyn.

For each case (A: OC3-style catenary, B: slack–snap polyester-like line) and
each ensemble size M, a member is the reference case with its normal drag
coefficient drawn uniformly from ±25 % of the deck value (member 0 keeps the
deck value). Each (case, M) runs in a fresh worker process so that its peak
memory (ru_maxrss) is its own; compile time (first call) and run time (a
second call with *new* member values, which must not recompile) are separate.

Columns: wall ms per simulated second per member for the vmapped ensemble, for
moorjax run one member at a time, and for MoorDyn in a loop (one run per
member, stepping loop only), plus the error of member 0 against the converged
reference (RMS / std of the fairlead tension) for both codes, so the costs are
compared at equal accuracy, and the worker's peak memory. ``first_call_ms_per_member``
is the first call's wall time (compile, statics and run, a fresh process with
an empty compilation cache, as a user's first run) per member and ``first_call_vs_single_run``
that over one single run's run time (compile excluded): issue 17's ensemble
figure. The workers split the CPU into one JAX device per core, as
``moorjax ensemble`` does (``--cpu-devices N`` to choose; 1 for one core).

    python benchmarks/ensemble.py [--cases A B] [--sizes 1 10 100 1000]
                                  [--duration 10] [--quick] [--json PATH]
                                  [--reference DIR] [--cpu-devices N]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

#: resolution per case: the segment count at which moorjax's default solver
#: (``auto``: ROS34PW2) is under 1 % error (see
#: vs_moordyn.py) and MoorDyn's cheapest run under 1 % (reference README)
SETTINGS = {
    "A": dict(n=40, solver="auto", moordyn=(40, "rk2", 3.125e-3)),
    "B": dict(n=10, solver="auto", moordyn=(10, "rk2", 1.667e-3)),
}


def _members(case, m, seed):
    from benchmarks.common import case_scene
    from moorjax.model.parameters import get_parameter, set_parameter

    base = case_scene(case, SETTINGS[case]["n"])
    cd = float(get_parameter(base, "Cd"))
    rng = np.random.default_rng(seed)
    values = cd * rng.uniform(0.75, 1.25, m)
    values[0] = cd
    return [set_parameter(base, "Cd", v) for v in values]


def _settings(case, solver=None, dt=None):
    """simulate's keyword arguments for a case: its default solver, or ``solver``
    (with a fixed step ``dt`` [s], e.g. an explicit method at MoorDyn's step)."""
    kw = dict(solver=solver or SETTINGS[case]["solver"], dt_out=0.05)
    if dt is not None:
        kw["dt"] = dt
    return kw


def worker(case, m, duration, solver=None, dt=None, cpu_devices=None):
    """One (case, M) measurement; prints a JSON line."""
    from moorjax.ensemble import use_cpu_cores

    devices = use_cpu_cores(cpu_devices)  # as `moorjax ensemble` does, before any JAX work
    import jax

    from benchmarks.common import reference_csv
    from benchmarks.moordyn_runner import rel_rms_error
    from moorjax.ensemble import simulate_ensemble, status
    from moorjax.ensemble.run import TRACES

    kw = _settings(case, solver, dt)
    t0 = time.perf_counter()
    res = simulate_ensemble(_members(case, m, 0), duration, **kw)
    jax.block_until_ready(res.tension_b)
    first = time.perf_counter() - t0
    traces = dict(TRACES)
    t0 = time.perf_counter()
    res = simulate_ensemble(_members(case, m, 1), duration, **kw)
    jax.block_until_ready(res.tension_b)
    run = time.perf_counter() - t0
    ref = reference_csv(case)
    err = (rel_rms_error(np.asarray(res.ts[0]), np.asarray(res.tension_b[0, :, 0]), ref)
           if ref else None)
    st = status(res)
    out = dict(
        case=case, members=m, cpu_devices=devices, compile_s=first - run, run_s=run, first_s=first,
        first_call_ms_per_member=first / m * 1e3,
        ms_per_sim_s_per_member=run / duration / m * 1e3,
        recompiled=TRACES != traces, failed=int(np.sum(st != "ok")),
        steps_mean=float(np.mean(res.num_steps)), steps_max=int(np.max(res.num_steps)),
        rel_err_member0=err, peak_rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    )
    print(json.dumps(out))


def single_moorjax(case, duration, repeats=3, solver=None, dt=None):
    import jax

    from moorjax.dynamics import simulate
    from moorjax.statics import solve_line_statics

    members = _members(case, repeats, 2)
    kw = _settings(case, solver, dt)
    init = [tuple(solve_line_statics(ln, s.env).state() for ln in s.lines) for s in members]
    jax.block_until_ready(simulate(members[0], duration, init=init[0], **kw).tension_b)
    t0 = time.perf_counter()
    for s, y in zip(members, init):
        jax.block_until_ready(simulate(s, duration, init=y, **kw).tension_b)
    return (time.perf_counter() - t0) / repeats / duration * 1e3


def moordyn_loop(case, duration, repeats=3):
    from benchmarks.common import CASES, reference_csv
    from benchmarks.moordyn_runner import rel_rms_error, run_moordyn
    from moorjax.examples import example_path

    n, scheme, dt = SETTINGS[case]["moordyn"]
    c = CASES[case]
    t0 = time.perf_counter()
    costs = []
    for _ in range(repeats):
        r = run_moordyn(example_path(c.deck), c.path(), duration, n_segments=n, dt=dt, scheme=scheme)
        costs.append(r["ms_per_sim_s"])
    wall = (time.perf_counter() - t0) / repeats / duration * 1e3
    ref = reference_csv(case)
    err = rel_rms_error(r["t"], r["tension"], ref) if ref and r["status"] == "ok" else None
    return dict(stepping_ms=float(np.mean(costs)), wall_ms=wall, rel_err=err, setting=f"N={n} {scheme} dt={dt:g}")


def main(argv=None):
    from benchmarks.common import _ReferenceDir

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", nargs="+", default=["A", "B"])
    ap.add_argument("--sizes", nargs="+", type=int, default=[1, 10, 100, 1000])
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--quick", action="store_true", help="sizes 1 10 100, 5 s")
    ap.add_argument("--json", help="write the figures here")
    ap.add_argument("--reference", metavar="DIR", action=_ReferenceDir,
                    help="folder of the reference data (default $MOORJAX_REFERENCE_DIR, else "
                         "../shared/reference beside the repository); workers inherit it")
    ap.add_argument("--solver", help="moorjax solver (default: the case's, see SETTINGS)")
    ap.add_argument("--dt", type=float, help="fixed step [s] (default: adaptive)")
    ap.add_argument("--cpu-devices", type=int, default=None, metavar="N",
                    help="CPU devices the ensemble shards over (default: one per core, as "
                         "`moorjax ensemble`; 1 for one core)")
    ap.add_argument("--worker", nargs=2, metavar=("CASE", "M"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        worker(a.worker[0], int(a.worker[1]), a.duration, a.solver, a.dt, a.cpu_devices)
        return 0
    if a.quick:
        a.sizes, a.duration = [1, 10, 100], 5.0
    rows = []
    for case in a.cases:
        single = single_moorjax(case, a.duration, solver=a.solver, dt=a.dt)
        md = moordyn_loop(case, a.duration)
        print(f"case {case}: moorjax one-by-one {single:.2f} ms/sim-s per member; MoorDyn "
              f"{md['setting']}: {md['stepping_ms']:.2f} ms/sim-s (stepping), error "
              f"{(md['rel_err'] or float('nan')) * 100:.2f} %", flush=True)
        for m in a.sizes:
            with tempfile.TemporaryDirectory() as cache:  # a user's first run: nothing cached
                p = subprocess.run([sys.executable, __file__, "--worker", case, str(m),
                                    "--duration", str(a.duration)]
                                   + (["--solver", a.solver] if a.solver else [])
                                   + (["--dt", str(a.dt)] if a.dt else [])
                                   + (["--cpu-devices", str(a.cpu_devices)] if a.cpu_devices else []),
                                   capture_output=True, text=True,
                                   env=dict(os.environ, MOORJAX_CACHE_DIR=cache))
            if p.returncode != 0:
                print(p.stderr[-2000:])
                rows.append(dict(case=case, members=m, error=p.stderr[-300:]))
                continue
            r = json.loads(p.stdout.strip().splitlines()[-1])
            r.update(solver=a.solver or SETTINGS[case]["solver"], dt=a.dt, single_ms=single, moordyn_ms=md["stepping_ms"], moordyn_err=md["rel_err"],
                     moordyn_setting=md["setting"],
                     vs_single=r["ms_per_sim_s_per_member"] / single,
                     first_call_vs_single_run=r["first_call_ms_per_member"] / (single * a.duration),
                     vs_moordyn=r["ms_per_sim_s_per_member"] / md["stepping_ms"])
            rows.append(r)
            print(f"  M={m:5d} on {r['cpu_devices']} CPU device(s): "
                  f"{r['ms_per_sim_s_per_member']:8.3f} ms/sim-s/member "
                  f"(x{r['vs_single']:.2f} of one-by-one, x{r['vs_moordyn']:.2f} of MoorDyn), "
                  f"compile {r['compile_s']:.1f} s, first call {r['first_call_ms_per_member']:.1f} ms "
                  f"per member (x{r['first_call_vs_single_run']:.2f} of one run), "
                  f"recompiled={r['recompiled']}, "
                  f"failed {r['failed']}, steps {r['steps_mean']:.0f}/{r['steps_max']}, "
                  f"err member0 {(r['rel_err_member0'] or float('nan')) * 100:.2f} %, "
                  f"peak RSS {r['peak_rss_mb']:.0f} MB", flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(dict(duration=a.duration, rows=rows), f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
