"""Work–precision: moorjax against MoorDyn on reference cases A and B.

Both codes run in this process on the same exact-sine fairlead motion, starting
from static equilibrium. For each run: wall time per simulated second (moorjax:
second call, compile time reported separately; MoorDyn: stepping loop only) and
the RMS fairlead-tension error relative to the converged MoorDyn N=160 reference,
divided by the reference's standard deviation.

    python benchmarks/vs_moordyn.py [--cases A B] [--duration 60] [--quick]
                                    [--json out.json] [--plot out.png]

The reference histories are looked for in $MOORJAX_REFERENCE_DIR (default
../shared/reference relative to the repository); without them the error column
is empty and no cheapest-at-error summary is printed.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import jax
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import moorjax as mj  # noqa: E402
from benchmarks.moordyn_runner import load_reference, rel_rms_error, run_moordyn  # noqa: E402
from moorjax.dynamics import timed_simulate  # noqa: E402
from moorjax.examples import example_path  # noqa: E402
from moorjax.io import build_scene, read_deck  # noqa: E402

CASES = {
    # deck, fairlead centre, amplitude (x), period
    "A": ("oc3_catenary", np.array([-5.2, 0.0, -70.0]), 5.0, 10.0),
    "B": ("taut_polyester", np.array([0.0, 0.0, -5.0]), 2.0, 8.0),
}
MOORDYN_RUNS = {
    "A": [(10, "rk2", 6.25e-3), (20, "rk2", 3.125e-3), (40, "rk2", 3.125e-3), (40, "rk4", 4.167e-3),
          (80, "rk2", 7.8e-4)],
    "B": [(10, "rk2", 1.667e-3), (20, "rk2", 4.0e-4), (40, "rk2", 1.0e-4)],
}
MOORJAX_RUNS = [(10, "kvaerno5", 1e-5), (20, "kvaerno5", 1e-6), (40, "kvaerno5", 1e-7),
                (20, "kvaerno3", 1e-6)]
QUICK = {"moordyn": {"A": [(40, "rk2", 3.125e-3)], "B": [(10, "rk2", 1.667e-3)]},
         "moorjax": [(20, "kvaerno5", 1e-6)]}


def reference_dir():
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    return os.environ.get("MOORJAX_REFERENCE_DIR", os.path.join(here, "..", "shared", "reference"))


def run_case(case, duration, quick):
    name, centre, amp, period = CASES[case]
    deck_path = example_path(name)
    ref_csv = os.path.join(reference_dir(), f"ref_{case}.csv")
    has_ref = os.path.exists(ref_csv)
    w = 2 * np.pi / period

    def path_fn(t):
        return centre + np.array([amp * np.sin(w * t), 0.0, 0.0])

    rows = []
    for n, scheme, dt in (QUICK["moordyn"][case] if quick else MOORDYN_RUNS[case]):
        r = run_moordyn(deck_path, path_fn, duration, n_segments=n, dt=dt, scheme=scheme)
        err = rel_rms_error(r["t"], r["tension"], ref_csv) if has_ref and r["status"] == "ok" else None
        rows.append(dict(case=case, code="MoorDyn", N=n, method=scheme, setting=f"dt={dt:g}",
                         ms_per_sim_s=r["ms_per_sim_s"], compile_s=0.0, rel_err=err,
                         status=r["status"]))
        print(_fmt(rows[-1]), flush=True)

    deck = read_deck(deck_path)
    for n, solver, tol in (QUICK["moorjax"] if quick else MOORJAX_RUNS):
        scene = build_scene(deck, segments=n)
        line = scene.lines[0]
        import equinox as eqx

        scene = eqx.tree_at(lambda s: s.lines[0].end_b, scene,
                            mj.SinePath(centre, [amp, 0.0, 0.0], period))
        del line
        try:
            res, c_s, r_s = timed_simulate(scene, duration, solver=solver, rtol=tol, atol=tol)
            res = jax.device_get(res)
            status = "ok"
            err = (rel_rms_error(np.asarray(res.ts), np.asarray(res.tension_b[:, 0]), ref_csv)
                   if has_ref else None)
            steps = int(res.num_steps)
        except RuntimeError as exc:  # a failed run is a result too
            c_s, r_s, err, status, steps = float("nan"), float("nan"), None, f"failed: {exc}", 0
        rows.append(dict(case=case, code="moorjax", N=n, method=solver, setting=f"tol={tol:g}",
                         ms_per_sim_s=1e3 * r_s / duration, compile_s=c_s, rel_err=err,
                         status=status, steps=steps))
        print(_fmt(rows[-1]), flush=True)
    return rows


def _fmt(r):
    err = "   n/a  " if r["rel_err"] is None else f"{100 * r['rel_err']:7.3f}%"
    return (f"{r['case']:>2} {r['code']:>8} N={r['N']:<4d} {r['method']:>9} {r['setting']:>13} "
            f"{r['ms_per_sim_s']:10.2f} ms/sim-s  compile {r['compile_s']:6.2f} s  err {err}  "
            f"{r['status']}")


def cheapest(rows, case, level):
    out = {}
    for code in ("MoorDyn", "moorjax"):
        ok = [r for r in rows if r["case"] == case and r["code"] == code
              and r["rel_err"] is not None and r["rel_err"] <= level]
        out[code] = min(ok, key=lambda r: r["ms_per_sim_s"]) if ok else None
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--cases", nargs="+", default=["A", "B"], choices=list(CASES))
    p.add_argument("--duration", type=float, default=60.0)
    p.add_argument("--quick", action="store_true", help="one run per code and case")
    p.add_argument("--json", help="write the figures to this path")
    p.add_argument("--plot", help="write a work-precision plot (PNG)")
    args = p.parse_args(argv)

    rows = []
    for case in args.cases:
        rows += run_case(case, args.duration, args.quick)

    summary = []
    print("\ncheapest run at a given error (ms per simulated second):")
    for case in args.cases:
        for level in (0.01, 0.001):
            c = cheapest(rows, case, level)
            md, mj_ = c["MoorDyn"], c["moorjax"]
            ratio = md["ms_per_sim_s"] / mj_["ms_per_sim_s"] if (md and mj_) else None
            summary.append(dict(case=case, level=level,
                                moordyn=md and md["ms_per_sim_s"], moorjax=mj_ and mj_["ms_per_sim_s"],
                                speedup=ratio))
            fmt = lambda r: "none" if r is None else f"{r['ms_per_sim_s']:.2f} (N={r['N']} {r['method']})"  # noqa: E731
            print(f"  {case} ≤{100 * level:g}%: MoorDyn {fmt(md)}  moorjax {fmt(mj_)}  "
                  f"speed-up {'n/a' if ratio is None else f'{ratio:.3g}x'}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(dict(runs=rows, summary=summary), f, indent=2)
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(1, len(args.cases), figsize=(5 * len(args.cases), 4), squeeze=False)
        for ax, case in zip(axes[0], args.cases):
            for code, mk in (("MoorDyn", "o"), ("moorjax", "s")):
                pts = [(r["rel_err"], r["ms_per_sim_s"]) for r in rows
                       if r["case"] == case and r["code"] == code and r["rel_err"] is not None]
                if pts:
                    e, t = zip(*pts)
                    ax.loglog(e, t, mk, label=code)
            ax.set(title=f"case {case}", xlabel="RMS error / reference std",
                   ylabel="wall ms per simulated s")
            ax.legend()
        fig.tight_layout()
        fig.savefig(args.plot, dpi=120)
    return 0


if __name__ == "__main__":
    sys.exit(main())
