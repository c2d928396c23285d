"""Work–precision: moorjax against MoorDyn on reference cases A and B.

Both codes run in this process on the same exact-sine fairlead motion, starting
from static equilibrium. For each run: wall (and CPU) time per simulated second
(moorjax: second of two identical calls, compile time and the static solve
reported separately; MoorDyn: stepping loop only), the RMS end-B tension error
against the converged MoorDyn N=160 reference divided by the reference's
standard deviation, and the number of steps.

- MoorDyn: rk2, rk4 and midpoint5 (MoorDyn's k=0.5 implicit Euler, 5
  iterations) at N = 10 … 80 and the largest stable dtM and half of it, as
  listed in the reference cost table ``moordyn_cost_error.csv``;
- moorjax: kvaerno3, kvaerno5 and ros34pw2 (adaptive) at N = 10, 20, 40, 80 and
  tolerance pairs (rtol, atol [m]) = (1e-4, 1e-3), (1e-5, 1e-4), (1e-6, 1e-5)
  (ros34pw2 also at (3e-6, 3e-5) and (4e-4, 4e-3))
  (``atol_velocity`` = 100·atol m/s, moorjax's default); implicit_euler with
  fixed steps; heun with fixed steps at MoorDyn's RK2 stability limit for that N
  (and half of it);
- with ``--elements linear hermite``, also moorjax with Wu et al.'s Hermite-cubic
  element (``HERMITE_NS`` elements, kvaerno5/kvaerno3 at the middle tolerance pair),
  drawn in its own colour on the same work–precision plot.

- with ``--precise``, only the fine tier that reaches 0.3 %: N = 60, 80, 100,
  120 for both codes (MoorDyn rk2 and midpoint5 at their step limits and half
  of them; moorjax ros34pw2, kvaerno3, and heun at MoorDyn's rk2 limit).

Then the cheapest run of each code (and of each method) at ≤ 1 %, 0.5 %, 0.3 %
and 0.1 % error, with the time ratio. The references are good to about 0.3 %
(see the reference README), so differences below that mean little and 0.1 % is
out of reach.

    python benchmarks/vs_moordyn.py [--cases A B] [--duration 20] [--quick | --precise]
                                    [--json out.json] [--plot out.png]
                                    [--reference DIR] [--elements linear hermite]

The reference data is looked for in --reference DIR, else $MOORJAX_REFERENCE_DIR (default
../shared/reference relative to the repository); without it the error column
is empty and a built-in list of MoorDyn settings is used.
"""

from __future__ import annotations

import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from benchmarks.common import (  # noqa: E402
    CASES,
    NOISE_NOTE,
    base_parser,
    case_scene,
    jsonable,
    print_table,
    reference_csv,
    reference_dir,
    static_init,
    timed_run,
    write_json,
)
from benchmarks.moordyn_runner import rel_rms_error, run_moordyn  # noqa: E402
from moorjax.examples import example_path  # noqa: E402

TOLS = [(1e-4, 1e-3), (1e-5, 1e-4), (1e-6, 1e-5)]
#: a tighter pair for ros34pw2 (its cheapest runs are at the default and looser)
ROS_TIGHT = (3e-6, 3e-5)
#: and looser ones: with the segment chords measured (session 24) the error at a
#: tolerance no longer grows with N, and loose tolerances are usable on fine meshes
ROS_LOOSE = (4e-4, 4e-3)
ROS_LOOSEST = (1e-3, 1e-2)
#: error levels of the cheapest-run summary (0.5 %: only N = 80 runs get there; the
#: references are good to about 0.3 %, so 0.1 % is not reachable with them)
LEVELS = (0.01, 0.005, 0.003, 0.001)
NS = [10, 20, 40, 80]
#: the fine tier (``--precise``): where the ≤ 0.3 % runs are (A needs N ≈ 100, B N ≈ 80)
PRECISE_NS = [60, 80, 100, 120]
#: MoorDyn's cheapest schemes at N = 80 in the cost table
PRECISE_SCHEMES = ("rk2", "midpoint5")
#: Hermite elements per line (each carries slopes and a tension field: ~2.5× the
#: unknowns of a linear segment)
HERMITE_NS = [5, 10, 20]
#: used when the reference cost table is missing: (N, scheme, dtM [s])
MOORDYN_FALLBACK = {
    "A": [(10, "rk2", 6.25e-3), (20, "rk2", 3.125e-3), (40, "rk2", 3.125e-3), (40, "rk4", 4.167e-3),
          (40, "midpoint5", 1.25e-2), (80, "rk2", 7.9e-4)],
    "B": [(10, "rk2", 1.667e-3), (20, "rk2", 4.9e-4), (20, "midpoint5", 3.57e-3), (40, "rk2", 1.17e-4)],
}
QUICK = {
    "moordyn": {"A": [(40, "rk2", 3.125e-3), (20, "rk4", 8.333e-3), (40, "midpoint5", 1.25e-2)],
                "B": [(10, "rk2", 1.667e-3), (20, "midpoint5", 3.571e-3)]},
    # (N, solver, (rtol, atol) or None, fixed dt or None)
    "moorjax": {"A": [(40, "kvaerno5", (1e-5, 1e-4), None), (40, "kvaerno3", (1e-5, 1e-4), None),
                      (20, "kvaerno3", (1e-5, 1e-4), None),
                      (20, "heun", None, 6.25e-3), (40, "heun", None, 3.125e-3),
                      (40, "auto", (1e-5, 1e-4), None),
                      (40, "ros34pw2", (1e-5, 1e-4), None), (40, "ros34pw2", (1e-4, 1e-3), None),
                      (40, "ros34pw2", ROS_LOOSE, None), (20, "ros34pw2", ROS_TIGHT, None),
                      (20, "implicit_euler", None, 2e-3)],
                "B": [(10, "kvaerno5", (1e-5, 1e-4), None), (10, "kvaerno3", (1e-5, 1e-4), None),
                      (20, "kvaerno3", (1e-5, 1e-4), None), (20, "kvaerno5", (1e-6, 1e-5), None),
                      (10, "auto", (1e-5, 1e-4), None),
                      (10, "heun", None, 1.667e-3), (10, "ros34pw2", (1e-4, 1e-3), None),
                      (10, "ros34pw2", (1e-5, 1e-4), None), (20, "ros34pw2", (1e-4, 1e-3), None),
                      (10, "ros34pw2", ROS_LOOSE, None), (10, "ros34pw2", ROS_LOOSEST, None),
                      (20, "implicit_euler", None, 2e-3)]},
}


def moordyn_table():
    """{case: [(N, scheme, dtM)]} from moordyn_cost_error.csv, or None."""
    path = os.path.join(reference_dir(), "moordyn_cost_error.csv")
    if not os.path.exists(path):
        return None
    out = {}
    with open(path) as f:
        for row in csv.DictReader(f):
            out.setdefault(row["case"], []).append((int(row["N"]), row["scheme"], float(row["dtM"])))
    return out


def rk2_limit(table, case, n):
    """MoorDyn's largest stable RK2 dtM at N segments (from the cost table) [s]."""
    dts = [dt for (m, s, dt) in (table or {}).get(case, []) if m == n and s == "rk2"]
    return max(dts) if dts else None


def scaled_limit(table, case, n, scheme):
    """MoorDyn's largest stable dtM for ``scheme`` at N segments [s]: from the cost table
    at N, else its N = 80 limit scaled as 1/N² (the internal damping's limit, README)."""
    rows = [(m, dt) for (m, s, dt) in (table or {}).get(case, []) if s == scheme]
    at_n = [dt for m, dt in rows if m == n]
    if at_n:
        return max(at_n)
    base = max((m for m, _ in rows), default=None)
    if base is None:
        return None
    return max(dt for m, dt in rows if m == base) * (base / n) ** 2


def precise_moordyn(case, table):
    """[(N, scheme, dtM)] of the fine tier: each scheme at its limit and half of it."""
    runs = []
    for n in PRECISE_NS:
        for scheme in PRECISE_SCHEMES:
            lim = scaled_limit(table or MOORDYN_FALLBACK, case, n, scheme)
            if lim is not None:
                runs += [(n, scheme, lim), (n, scheme, lim / 2)]
    return runs


def precise_plan(case, table):
    """[(N, solver, (rtol, atol) or None, dt or None)] of the fine tier."""
    runs = []
    for n in PRECISE_NS:
        runs += [(n, "ros34pw2", tol, None) for tol in (ROS_LOOSE, TOLS[0], TOLS[1], ROS_TIGHT, TOLS[2])]
        runs += [(n, "kvaerno3", TOLS[0], None)]
        lim = scaled_limit(table or MOORDYN_FALLBACK, case, n, "rk2")
        if lim is not None:
            runs += [(n, "heun", None, lim)]
    return runs


def moorjax_plan(case, quick, table, elements=("linear",), precise=False):
    """[(N, solver, (rtol, atol) or None, dt or None, element)]."""
    runs = []
    if precise:
        return [r + ("linear",) for r in precise_plan(case, table)]
    if "linear" in elements:
        runs += [r + ("linear",) for r in _linear_plan(case, quick, table)]
    if "hermite" in elements:
        ns = [10] if quick else HERMITE_NS
        solvers = ["kvaerno5"] if quick else ["kvaerno3", "kvaerno5"]
        runs += [(n, s, TOLS[1], None, "hermite") for n in ns for s in solvers]
    return runs


def _linear_plan(case, quick, table):
    if quick:
        return QUICK["moorjax"][case]
    runs = [(n, s, tol, None) for n in NS for s in ("kvaerno3", "kvaerno5", "ros34pw2")
            for tol in TOLS]
    runs += [(n, "ros34pw2", tol, None) for n in NS for tol in (ROS_TIGHT, ROS_LOOSE, ROS_LOOSEST)]
    runs += [(n, "implicit_euler", None, dt) for n in (20, 40) for dt in (1e-3, 2e-3, 5e-3)]
    for n in NS:
        lim = rk2_limit(table, case, n)
        if lim is not None:
            runs += [(n, "heun", None, lim), (n, "heun", None, lim / 2)]
    return runs


def run_case(case, duration, quick, elements=("linear",), precise=False, repeats=3):
    c = CASES[case]
    ref_csv = reference_csv(case)
    table = moordyn_table()
    if precise:
        md_runs = precise_moordyn(case, table)
    else:
        md_runs = (QUICK["moordyn"][case] if quick else
                   [r for r in (table or MOORDYN_FALLBACK)[case] if r[0] <= 80])
    rows = []
    for n, scheme, dt in md_runs:
        r = run_moordyn(example_path(c.deck), c.path(), duration, n_segments=n, dt=dt, scheme=scheme,
                        repeats=repeats)
        ok = r["status"] == "ok"
        err = rel_rms_error(r["t"], r["tension"], ref_csv) if (ref_csv and ok) else None
        rows.append(dict(case=case, code="MoorDyn", N=n, method=scheme, element="lumped mass", setting=f"dtM {1e3 * dt:.4g} ms",
                         outcome="ok" if ok else "unstable", ms_per_sim_s=r["ms_per_sim_s"],
                         cpu_ms_per_sim_s=r["cpu_ms_per_sim_s"], compile_s=0.0,
                         statics_s=r["init_s"], rel_err=err, steps=int(round(duration / dt)),
                         max_tension_N=float(np.nanmax(r["tension"])) if ok else float("nan")))
        print(_line(rows[-1]), flush=True)

    inits = {}
    for n, solver, tol, dt, element in moorjax_plan(case, quick, table, elements, precise):
        scene = case_scene(case, n, element=element)
        if (n, element) not in inits:
            inits[n, element] = static_init(scene)
        kw = dict(solver=solver, init=inits[n, element])
        if tol is not None:
            kw.update(rtol=tol[0], atol=tol[1])
            setting = f"tol {tol[0]:.0e}/{tol[1]:.0e}"
        if dt is not None:
            kw["dt"] = dt
            setting = f"dt {1e3 * dt:.4g} ms"
        r = timed_run(scene, duration, repeats=repeats, **kw)
        res = r.pop("result")
        err = (rel_rms_error(np.asarray(res.ts), np.asarray(res.tension_b[:, 0]), ref_csv)
               if (ref_csv and r["outcome"] == "ok") else None)
        cpu = 1e3 * r["cpu_s"] / duration if r["outcome"] == "ok" else float("nan")
        if r["outcome"] != "ok":
            r["ms_per_sim_s"] = float("nan")
        rows.append(dict(case=case, code="moorjax", N=n, method=solver, setting=setting,
                         element=element, rel_err=err, cpu_ms_per_sim_s=cpu, **r))
        print(_line(rows[-1]), flush=True)
    return rows


def _label(r):
    """moorjax, moorjax hermite or MoorDyn."""
    return r["code"] + (" hermite" if r.get("element") == "hermite" else "")


def _line(r):
    err = "   n/a  " if r["rel_err"] is None else f"{100 * r['rel_err']:7.3f}%"
    return (f"  {r['case']} {_label(r):>16} N={r['N']:<3d} {r['method']:>14} {r['setting']:>18} "
            f"{r['ms_per_sim_s']:9.2f} ms/sim-s  compile {r['compile_s']:5.1f} s  err {err}  "
            f"{r['outcome'][:50]}")


def cheapest(rows, case, level, key="ms_per_sim_s", by="code"):
    """Cheapest ok run at error ≤ level, per code (or per ``by`` = "method")."""
    out = {}
    for r in rows:
        if (r["case"] == case and r["outcome"] == "ok" and r["rel_err"] is not None
                and r["rel_err"] <= level and np.isfinite(r[key])):
            k = r[by] if by == "code" else (_label(r), r["method"])
            if k not in out or r[key] < out[k][key]:
                out[k] = r
    if by == "code":
        return {code: out.get(code) for code in ("MoorDyn", "moorjax")}
    return out


def summarise(rows, cases):
    summary = []
    print("\ncheapest run at a given error (wall ms per simulated second; CPU ms in brackets):")
    for case in cases:
        for level in LEVELS:
            c = cheapest(rows, case, level)
            md, mj_ = c["MoorDyn"], c["moorjax"]
            ratio = md["ms_per_sim_s"] / mj_["ms_per_sim_s"] if (md and mj_) else None
            summary.append(dict(case=case, level=level,
                                moordyn=md and {k: md[k] for k in ("N", "method", "setting",
                                                                   "ms_per_sim_s", "rel_err")},
                                moorjax=mj_ and {k: mj_[k] for k in ("N", "method", "setting",
                                                                     "ms_per_sim_s", "rel_err")},
                                moordyn_over_moorjax=ratio))

            def f(r):
                if r is None:
                    return "none"
                return (f"{r['ms_per_sim_s']:.2f} [{r['cpu_ms_per_sim_s']:.2f}] (N={r['N']} {r['method']} "
                        f"{r['setting']}, {100 * r['rel_err']:.2f} %)")

            verdict = ("n/a" if ratio is None else
                       f"MoorDyn/moorjax time = {ratio:.3g} "
                       f"({'moorjax' if ratio > 1 else 'MoorDyn'} faster)")
            print(f"  {case} ≤ {100 * level:g} %: MoorDyn {f(md)}\n"
                  f"  {' ' * len(case)}           moorjax {f(mj_)}\n"
                  f"  {' ' * len(case)}           {verdict}")
            per = cheapest(rows, case, level, by="method")
            if per:
                print(f"  {' ' * len(case)}           per method: " + ", ".join(
                    f"{code} {m} {r['ms_per_sim_s']:.2f} (N={r['N']})"
                    for (code, m), r in sorted(per.items(), key=lambda kv: kv[1]["ms_per_sim_s"])))
    return summary


def plot(rows, cases, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(cases), figsize=(6 * len(cases), 4.5), squeeze=False)
    markers = {"rk2": "o", "rk4": "D", "midpoint5": "v", "kvaerno3": "s", "kvaerno5": "^",
               "implicit_euler": "P", "heun": "x"}
    for ax, case in zip(axes[0], cases):
        for code, colour in (("MoorDyn", "tab:blue"), ("moorjax", "tab:red"),
                             ("moorjax hermite", "tab:green")):
            methods = sorted({r["method"] for r in rows if r["case"] == case and _label(r) == code})
            for m in methods:
                pts = [(r["rel_err"], r["ms_per_sim_s"], r["N"]) for r in rows
                       if r["case"] == case and _label(r) == code and r["method"] == m
                       and r["rel_err"] is not None and np.isfinite(r["ms_per_sim_s"])]
                if not pts:
                    continue
                e, t, n = zip(*pts)
                ax.loglog(np.array(e) * 100, t, markers.get(m, "."), color=colour, alpha=0.8,
                          label=f"{code} {m}", mfc="none" if code == "MoorDyn" else colour)
                for ei, ti, ni in pts:
                    ax.annotate(str(ni), (ei * 100, ti), fontsize=6, xytext=(2, 2),
                                textcoords="offset points")
        for lvl in (1.0, 0.1):
            ax.axvline(lvl, color="grey", lw=0.5, ls="--")
        ax.set(title=f"case {case} (numbers: segments or elements)", xlabel="RMS tension error / reference std [%]",
               ylabel="wall ms per simulated s")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"wrote {path}")


def main(argv=None):
    p = base_parser(__doc__)
    p.add_argument("--cases", nargs="+", default=["A", "B"], choices=list(CASES))
    p.add_argument("--duration", type=float, default=20.0, help="simulated seconds (default 20)")
    p.add_argument("--plot", metavar="PATH", help="write a work-precision plot (PNG)")
    p.add_argument("--elements", nargs="+", default=["linear"], choices=["linear", "hermite"],
                   help="moorjax elements to run (default: linear)")
    p.add_argument("--precise", action="store_true",
                   help="only the fine tier for the ≤ 0.3 %% level: N = 60, 80, 100, 120, MoorDyn rk2 and "
                   "midpoint5 at their step limits (the table's, else its N = 80 limit scaled as 1/N²) and "
                   "half of them, moorjax ros34pw2, kvaerno3 and heun at MoorDyn's rk2 limit (about 20 "
                   "minutes); the references are good to about 0.3 %%, so this is the finest level they test")
    p.add_argument("--repeats", type=int, default=3,
                   help="timed runs per configuration and code; the least time is kept (default 3: "
                   "MoorDyn's whole run repeated, moorjax's call after its compiling first)")
    args = p.parse_args(argv)
    if args.repeats < 1:
        p.error("--repeats must be >= 1")
    if args.precise and (args.quick or args.elements != ["linear"]):
        p.error("--precise runs the linear element's fine tier; it does not combine with --quick "
                "or --elements")
    print(f"work–precision, {args.duration:g} s simulated" + (" (--quick)" if args.quick else "")
          + (" (--precise)" if args.precise else ""))
    print(NOISE_NOTE)
    rows = []
    for case in args.cases:
        rows += run_case(case, args.duration, args.quick, args.elements, args.precise, args.repeats)
    for case in args.cases:
        print_table([r for r in rows if r["case"] == case], [
            ("code", _label, ""), ("N", "N", "d"), ("method", "method", ""),
            ("setting", "setting", ""), ("outcome", lambda r: r["outcome"][:44], ""),
            ("ms/sim-s", "ms_per_sim_s", ".2f"), ("cpu ms/sim-s", "cpu_ms_per_sim_s", ".2f"),
            ("compile [s]", "compile_s", ".1f"),
            ("err/std", lambda r: None if r["rel_err"] is None else f"{100 * r['rel_err']:.3f}%", ""),
            ("steps", "steps", "d"),
        ], title=f"case {case} (error: RMS end-B tension − reference |F|, over its std)")
    summary = summarise(rows, args.cases)
    write_json(args.json, dict(runs=jsonable(rows), summary=summary, duration_s=args.duration,
                               quick=args.quick, precise=args.precise, repeats=args.repeats))
    if args.plot:
        plot(rows, args.cases, args.plot)
    return 0


if __name__ == "__main__":
    sys.exit(main())
