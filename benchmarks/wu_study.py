"""Wu et al.'s study end to end: polyester against steel wire and chain.

Regenerates, for the moored box of :mod:`moorjax.examples.wu_box` (every input and
its source is in ``wu_box.ASSUMPTIONS``; "Lnnn" below is a line of the paper's text):

1. ``assumptions.md``: the input table (value, source);
2. static analysis (Fig. 13, L291–300): restoring force against surge offset per
   material, the polyester−steel difference at 0.2 and 1.0 m and the crossover
   (``static_offset.csv``), the AD surge stiffness at rest;
3. dynamic analysis (Figs. 5–12, L260–289): tension of the four lines and the six
   motions per material, at the base current (1.2 m/s) and at 0.4 m/s, each from
   rest (loads switched on at t = 0) and from the loaded equilibrium
   (``dynamic_<material>_<current>_<start>.csv``); the claims of L262 are taken on
   cable 3 (line 3, the weather-side line); sensitivity runs (polyester with
   Table 1's linearised AE = 1.5e8 N, chain drag 2.4 on the volume-equivalent
   diameter) and, with ``--stress``, Table 1's 4 m/s current;
4. cable-length sweep (Fig. 4, L252–254): polyester, anchors fixed where the 110 m
   lines have 20 kN, mean and max force per line and grounded length;
5. uniformity (Fig. 14, L302–313): ``--cases`` environmental cases drawn within
   Table 1's maxima (heading, Hs, Tz, wind, current, wave seed) run per material
   from the loaded equilibrium, in vmapped chunks of ``--chunk`` cases (each chunk
   kept in ``OUT/uniformity_cases`` so that a rerun resumes); records of ``--case-duration``
   after a ``--case-transient``; per case the standard deviation across the four
   lines of the peak and of the mean force, averaged over the cases. Full mode
   makes each record three undamped surge periods of that material, the longer of
   those at the base current and at half of it (the lowest drawn), from the AD
   stiffness at the loaded equilibrium;
6. convergence of the headline ratios: segments per line and tolerances, with
   linear elements (the paper's Hermite element is checked on the same runs by
   ``benchmarks/wu_hermite_check.py``);
7. ``table.md`` and ``summary.json`` (every number and run time), ``--json PATH``
   (the claims in percent and every figure the table shows) and figures.

Usage::

    PYTHONPATH=. python benchmarks/wu_study.py --out wu_quick --quick --json wu_quick/claims.json
    PYTHONPATH=. python benchmarks/wu_study.py --out wu_results --json wu_results/claims.json  # hours

Run times include compilation (each distinct structure compiles once).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import jax
import numpy as np

import moorjax  # noqa: F401  (float64)
from moorjax.body import DOF_NAMES
from moorjax.dynamics import simulate
from moorjax.ensemble import equilibrium as ensemble_equilibrium
from moorjax.ensemble import simulate_ensemble
from moorjax.ensemble import status as ensemble_status
from moorjax.examples import wu_box as wu
from moorjax.statics import mooring_stiffness, offset_curve, solve_system_statics

MATERIALS = ("polyester", "steel", "chain")
#: --skip name: key in summary.json
SECTIONS = {"dynamic": "dynamic", "uniformity": "uniformity", "sensitivity": "sensitivity",
            "sweep": "length_sweep", "static": "static", "convergence": "convergence"}
C3 = wu.CABLE_3
PAPER = {
    "max_tension_polyester_over_chain": 67.72,  # L262
    "max_tension_polyester_over_steel": 91.58,  # L262
    "std_peak_polyester_over_chain": 48.89,  # L308
    "std_mean_polyester_over_chain": 23.12,  # L308
}
PAPER_FIGURES = {
    "static_poly_minus_steel_at_0.2m_N": -13000.0,  # L295
    "static_poly_minus_steel_at_1.0m_N": 54000.0,  # L295 ("larger than")
    "static_crossover_offset_m": 0.7,  # L295
    "polyester_mean_surge_m": 3.0,  # L280, Fig. 10 focal point ("around 3 m")
}


def _timed(fn, *a, **kw):
    """(fn(...), wall [s]) with JAX's asynchronous work finished inside the timing
    (the first run of a structure includes its compilation)."""
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*a, **kw))
    return out, time.perf_counter() - t0


# --------------------------------------------------------------------------- static


def static_analysis(radii, offsets, n_segments):
    calm = dict(waves=False, wind=0.0, current=0.0, radiation=False)
    out = {"offset_m": offsets.tolist()}
    for mat in MATERIALS:
        sc = wu.scene(mat, radius=radii[mat], n_segments=n_segments, **calm)
        out[mat] = np.asarray(offset_curve(sc, offsets, dof=0)).tolist()
        out.setdefault("surge_stiffness_N_per_m", {})[mat] = float(mooring_stiffness(sc)[0, 0])
    diff = np.asarray(out["polyester"]) - np.asarray(out["steel"])
    at = {x: float(np.interp(x, offsets, diff)) for x in (0.2, 1.0)}
    sign = np.flatnonzero(np.diff(np.sign(diff[1:])) != 0)
    cross = None
    if sign.size:
        i = sign[0] + 1
        cross = float(np.interp(0.0, [diff[i], diff[i + 1]], [offsets[i], offsets[i + 1]]))
    out["poly_minus_steel_at_0.2m_N"] = at[0.2]
    out["poly_minus_steel_at_1.0m_N"] = at[1.0]
    out["crossover_offset_m"] = cross
    return out


# --------------------------------------------------------------------------- dynamic


def run_case(mat, radius, args, *, current, start, duration, length=wu.LINE_LENGTH,
             segments=None, rtol=None, atol=None, seed=None):
    """One dynamic run; returns (scene, statics, result, wall [s], statics_ok)."""
    sc = wu.scene(mat, radius=radius, length=length, n_segments=segments or args.segments,
                  seed=args.seed if seed is None else seed, n_components=args.components,
                  current=current)
    st, init = wu.start_state(sc, start, throw=False)
    res, wall = _timed(simulate, sc, duration, init=init, dt_out=args.dt_out, solver=args.solver,
                       rtol=rtol or args.rtol, atol=atol or args.atol, throw=False)
    return sc, st, res, wall, bool(st.converged)


def _dyn_record(res, st, wall, ok_statics, transient):
    t = np.asarray(res.ts)
    ten = np.asarray(res.tension_b)
    pose = np.asarray(res.body_pose[:, 0])
    keep = t >= transient
    status = "ok" if bool(res.succeeded()) and np.all(np.isfinite(ten)) else "failed"
    return dict(
        status=status, statics_converged=ok_statics, wall_s=wall, steps=int(res.num_steps),
        rejected=int(res.num_rejected_steps), t_end=float(t[-1]),
        start_pose=np.asarray(st.poses[0]).tolist(),
        max_tension_N=np.nanmax(ten, axis=0).tolist(),  # whole record (a start from rest peaks early)
        max_tension_after_transient_N=np.nanmax(ten[keep], axis=0).tolist(),
        mean_tension_N=np.nanmean(ten[keep], axis=0).tolist(),
        motion_mean=np.nanmean(pose[keep], axis=0).tolist(),
        motion_std=np.nanstd(pose[keep], axis=0).tolist(),
    )


def _save_history(path, res):
    t = np.asarray(res.ts)
    cols = np.column_stack([t, np.asarray(res.body_pose[:, 0]), np.asarray(res.body_velocity[:, 0]),
                            np.asarray(res.tension_b)])
    header = ("t," + ",".join(DOF_NAMES) + "," + ",".join(f"{d}_velocity" for d in DOF_NAMES)
              + "," + ",".join(f"L{k + 1}_tension_b" for k in range(4)))
    np.savetxt(path, cols, delimiter=",", header=header, comments="", fmt="%.6g")


def _ratios(rec, key="max_tension_N"):
    """Cable-3 maxima of polyester over chain and steel [%] from {material: record}."""
    mx = {m: rec[m][key][C3] for m in rec}
    out = {}
    if "polyester" in mx and "chain" in mx:
        out["max_tension_polyester_over_chain"] = 100 * mx["polyester"] / mx["chain"]
    if "polyester" in mx and "steel" in mx:
        out["max_tension_polyester_over_steel"] = 100 * mx["polyester"] / mx["steel"]
    return out


def dynamic_analysis(radii, args, out):
    runs, table = {}, []
    for current in args.currents:
        for start in args.starts:
            key = f"{current:g}ms_{start}"
            runs[key] = {}
            for mat in MATERIALS:
                sc, st, res, wall, ok = run_case(mat, radii[mat], args, current=current, start=start,
                                                 duration=args.duration)
                _save_history(out / f"dynamic_{mat}_{key}.csv", res)
                runs[key][mat] = r = _dyn_record(res, st, wall, ok, args.transient)
                print(f"dynamic {mat:9s} {key}: {wall:6.1f} s, {r['steps']} steps, {r['status']}, "
                      f"cable-3 max {r['max_tension_N'][C3] / 1e3:.1f} kN, mean surge "
                      f"{r['motion_mean'][0]:.2f} m", flush=True)
            table.append(dict(case=key, **_ratios(runs[key])))
    return runs, table


def sensitivity(radii, args, out):
    """Base environment from rest: one input changed at a time."""
    cur, start = args.currents[0], args.starts[0]
    rows = {}
    for variant, replaces in (("polyester_ae150", "polyester"), ("chain_cd_on_dve", "chain")):
        radius = wu.anchor_radius(variant)
        sc, st, res, wall, ok = run_case(variant, radius, args, current=cur, start=start,
                                         duration=args.duration)
        _save_history(out / f"dynamic_{variant}_{cur:g}ms_{start}.csv", res)
        rows[variant] = dict(replaces=replaces, **_dyn_record(res, st, wall, ok, args.transient))
        print(f"sensitivity {variant}: cable-3 max {rows[variant]['max_tension_N'][C3] / 1e3:.1f} kN, "
              f"{wall:.1f} s", flush=True)
    return rows


def stress(radii, args):
    rows = {}
    for mat in MATERIALS:
        try:
            sc, st, res, wall, ok = run_case(mat, radii[mat], args, current=wu.CURRENT_MAX,
                                             start="equilibrium", duration=args.stress_duration)
            rows[mat] = _dyn_record(res, st, wall, ok, 0.0)
        except Exception as exc:  # a stress case may not reach equilibrium at all
            rows[mat] = dict(status=f"failed: {exc}")
        print(f"stress {mat} at {wu.CURRENT_MAX} m/s: {rows[mat].get('status')}", flush=True)
    return rows


def surge_periods(radii, args, current=None):
    """Undamped surge period 2π√((M + A∞₁₁)/K₁₁) at the loaded equilibrium [s]
    (default: the base current)."""
    out = {}
    for mat in MATERIALS:
        sc = wu.scene(mat, radius=radii[mat], n_segments=args.segments,
                      current=args.currents[0] if current is None else current)
        st = solve_system_statics(sc, throw=False)
        k = float(mooring_stiffness(sc, st.poses)[0, 0])
        m = wu.MASS + float(sc.bodies[0].added_mass[0, 0])
        out[mat] = dict(stiffness_N_per_m=k, period_s=float(2 * np.pi * np.sqrt(m / k)))
    return out


# --------------------------------------------------------------------------- sweep


def length_sweep(radius, args):
    rows = []
    for length in args.lengths:
        try:
            sc, st, res, wall, ok = run_case("polyester", radius, args, current=args.currents[0],
                                             start="equilibrium", duration=args.sweep_duration,
                                             length=length)
        except Exception as exc:
            rows.append(dict(length_m=length, status=f"failed: {exc}"))
            print(f"length {length:g} m: failed ({exc})", flush=True)
            continue
        t = np.asarray(res.ts)
        ten = np.asarray(res.tension_b)[t >= args.transient]
        rows.append(dict(
            length_m=length, status="ok" if bool(res.succeeded()) else "failed",
            statics_converged=ok, wall_s=wall, mean_N=ten.mean(axis=0).tolist(),
            max_N=ten.max(axis=0).tolist(),
            grounded_m=[float(s.grounded_length) for s in st.lines],
        ))
        print(f"length {length:g} m: mean force {np.round(ten.mean(axis=0) / 1e3, 1)} kN, "
              f"statics {'ok' if ok else 'not converged'}, {wall:.0f} s", flush=True)
    return rows


# --------------------------------------------------------------------------- uniformity


def draw_cases(n, rng):
    """Environmental cases within Table 1's maxima (L239–243) around the base case."""
    return dict(
        heading=wu.HEADING + np.radians(rng.uniform(-30, 30, n)),
        hs=rng.uniform(0.5 * wu.HS, wu.HS, n),
        tz=rng.uniform(4.0, 10.0, n),  # ≤ Table 1's 60 s
        wind=rng.uniform(0.5 * wu.WIND, wu.WIND, n),
        current=rng.uniform(0.5 * wu.CURRENT, wu.CURRENT, n),
        seed=rng.integers(0, 2**31 - 1, n),
    )


def uniformity(mat, radius, args, draws, record, transient, store=None):
    """The drawn cases of one material, run in vmapped chunks of ``args.chunk`` members.

    Each chunk's peaks and means are written to ``store/{mat}_{first case}.npz`` as it
    finishes, and read back instead of rerun (so an interrupted study resumes where it
    stopped). On a CPU a chunk of 1 is the cheapest per member: a vmapped batch takes
    as many steps as its slowest member and every Newton iteration of the slowest one.
    """
    n = len(draws["seed"])
    k = max(1, int(args.chunk))
    peak, mean = np.full((n, 4), np.nan), np.full((n, 4), np.nan)
    ok, steps = np.zeros(n, bool), np.zeros(n, int)
    not_conv, t_statics, wall = [], 0.0, 0.0
    for first in range(0, n, k):
        idx = np.arange(first, min(first + k, n))
        path = None if store is None else Path(store) / f"{mat}_{first:04d}.npz"
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
        # what the chunk's numbers depend on: its drawn cases, the record, the
        # resolution and the solver; a stored chunk is reused only when all agree
        key = np.concatenate([[record, transient, args.segments, args.rtol, args.atol,
                               args.components, args.dt_out],
                              np.ravel([np.asarray(draws[name], float)[idx] for name in sorted(draws)])])
        if path is not None and path.exists():
            z = np.load(path)
            if (z["key"].shape == key.shape and np.allclose(z["key"], key, rtol=1e-12, atol=0.0)
                    and "solver" in z.files and str(z["solver"]) == args.solver):
                peak[idx], mean[idx], ok[idx], steps[idx] = z["peak"], z["mean"], z["ok"], z["steps"]
                t_statics, wall = t_statics + float(z["statics_s"]), wall + float(z["ensemble_s"])
                not_conv += [int(i) for i in z["not_conv"]]
                continue
        scenes = []
        for i in idx:
            kw = {kk: (int(v[i]) if kk == "seed" else float(v[i])) for kk, v in draws.items()}
            scenes.append(wu.scene(mat, radius=radius, n_segments=args.segments,
                                   n_components=args.components, **kw))
        t0 = time.perf_counter()
        # the loaded equilibria, vmapped; where one did not converge it starts where
        # the iteration stopped (near equilibrium is enough)
        inits, converged = ensemble_equilibrium(scenes)
        jax.block_until_ready(inits)
        nc = idx[~np.all(np.asarray(converged), axis=1)]
        ts = time.perf_counter() - t0
        res, w = _timed(simulate_ensemble, scenes, transient + record, init=inits,
                        dt_out=args.dt_out, solver=args.solver, rtol=args.rtol, atol=args.atol)
        jax.block_until_ready(res.tension_b)
        ten = np.asarray(res.tension_b)[:, np.asarray(res.ts[0]) >= transient]  # (k, samples, 4)
        peak[idx], mean[idx] = ten.max(axis=1), ten.mean(axis=1)
        ok[idx] = [s == "ok" for s in ensemble_status(res)]
        steps[idx] = np.asarray(res.num_steps)
        t_statics, wall = t_statics + ts, wall + w
        not_conv += nc.tolist()
        if path is not None:
            np.savez(path, key=key, solver=args.solver, peak=peak[idx], mean=mean[idx], ok=ok[idx], steps=steps[idx],
                     statics_s=ts, ensemble_s=w, not_conv=nc)
        print(f"  {mat} cases {idx[0]}–{idx[-1]}: {int(ok[idx].sum())}/{len(idx)} ok, "
              f"{w:.0f} s", flush=True)
    return dict(
        cases=n, ok=int(ok.sum()), statics_not_converged=not_conv, record_s=record,
        transient_s=transient, chunk=k, steps_max=int(steps.max()), steps_mean=float(steps.mean()),
        # Wu's uniformity (L306): the standard deviation over the four cables of each
        # case's peak (mean) force, averaged over the cases
        std_peak_N=float(np.mean(peak[ok].std(axis=1))),
        std_mean_N=float(np.mean(mean[ok].std(axis=1))),
        peak_N=peak.tolist(), mean_N=mean.tolist(), statics_s=t_statics, ensemble_s=wall,
    )


# --------------------------------------------------------------------------- convergence


def convergence(radii, args, base=None):
    """Headline cable-3 ratios (base environment, from rest) against resolution.

    ``base``: the dynamic records of the base case, reused for the first row when
    they have the same record length.
    """
    settings = [dict(segments=args.segments, rtol=args.rtol, atol=args.atol),
                dict(segments=2 * args.segments, rtol=args.rtol, atol=args.atol),
                dict(segments=args.segments, rtol=args.rtol / 10, atol=args.atol / 10)]
    rows = []
    for i, s in enumerate(settings):
        if i == 0 and base is not None and args.conv_duration == args.duration:
            rec = base
        else:
            rec = {}
            for mat in MATERIALS:
                sc, st, res, wall, ok = run_case(mat, radii[mat], args, current=args.currents[0],
                                                 start=args.starts[0], duration=args.conv_duration,
                                                 **s)
                rec[mat] = _dyn_record(res, st, wall, ok, 0.0)
        rows.append(dict(**s, element="linear (Hermite: benchmarks/wu_hermite_check.py)",
                         cable3_max_N={m: rec[m]["max_tension_N"][C3] for m in MATERIALS},
                         wall_s={m: rec[m]["wall_s"] for m in MATERIALS},
                         steps={m: rec[m]["steps"] for m in MATERIALS},
                         # a run that failed part-way has its maximum over a partial record
                         status={m: rec[m]["status"] for m in MATERIALS}, **_ratios(rec)))
        print(f"convergence {s}: {({k: round(v, 2) for k, v in _ratios(rec).items()})}", flush=True)
    return rows


# --------------------------------------------------------------------------- main


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--json", help="write the claims and the table's figures here")
    p.add_argument("--quick", action="store_true",
                   help="200 s records, 8 uniformity cases of 300 s (about 45 min on 2 loaded cores, mostly compilation)")
    p.add_argument("--duration", type=float, default=600.0, help="dynamic runs [s]")
    p.add_argument("--transient", type=float, default=100.0, help="start-up left out of means [s]")
    p.add_argument("--currents", type=float, nargs="+", default=[wu.CURRENT, wu.CURRENT_GUESS],
                   help="current speeds of the dynamic runs (the first is the base) [m/s]")
    p.add_argument("--starts", nargs="+", default=["rest", "equilibrium"],
                   choices=["rest", "equilibrium"], help="the first is the base")
    p.add_argument("--segments", type=int, default=8, help="elements per line")
    p.add_argument("--components", type=int, default=100, help="wave components")
    p.add_argument("--cases", type=int, default=100, help="uniformity cases")
    p.add_argument("--case-duration", type=float, default=None,
                   help="uniformity record after the transient [s] (default: 3 surge periods)")
    p.add_argument("--case-transient", type=float, default=200.0, help="[s]")
    p.add_argument("--case-materials", nargs="+", choices=MATERIALS, default=list(MATERIALS),
                   help="materials of the uniformity cases (default: all three). A run with one "
                        "material fills OUT/uniformity_cases, which a later run of all three reuses: "
                        "two such runs can share one case store on two cores")
    p.add_argument("--chunk", type=int, default=1,
                   help="uniformity cases per vmapped batch (on a CPU 1 is cheapest per case: "
                        "a batch steps as often as its slowest member); each finished chunk is "
                        "kept in OUT/uniformity_cases and reused by a rerun")
    p.add_argument("--lengths", type=float, nargs="+", default=[106, 108, 110, 112, 114, 116])
    p.add_argument("--sweep-duration", type=float, default=600.0, help="length-sweep runs [s]")
    p.add_argument("--conv-duration", type=float, default=300.0, help="convergence runs [s]")
    p.add_argument("--stress", action="store_true", help="also run Table 1's 4 m/s current")
    p.add_argument("--stress-duration", type=float, default=300.0)
    p.add_argument("--solver", default="kvaerno3")
    p.add_argument("--rtol", type=float, default=1e-3)
    p.add_argument("--atol", type=float, default=1e-2, help="position tolerance [m]")
    p.add_argument("--dt-out", type=float, default=0.5)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--resume", action="store_true",
                   help="keep the sections already in OUT/summary.json and run the others")
    p.add_argument("--skip", nargs="*", default=[],
                   choices=["static", "dynamic", "sensitivity", "sweep", "uniformity", "convergence"])
    a = p.parse_args(argv)
    if a.quick:
        a.duration, a.transient = 200.0, 50.0
        a.cases, a.case_duration, a.case_transient = 8, 300.0, 50.0
        # one record length for every single run: a new end time recompiles
        a.sweep_duration, a.lengths = 200.0, [106.0, 110.0, 112.0, 116.0]
        a.conv_duration = 200.0
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    summary = dict(settings=vars(a).copy(), run_times_s={})
    if a.resume and (out / "summary.json").exists():  # keep the sections already done
        done = json.loads((out / "summary.json").read_text())
        summary.update({k: v for k, v in done.items() if k != "settings"})
        a.skip = list(a.skip) + [k for k, key in SECTIONS.items() if key in done]
        print("resuming; done:", [k for k, key in SECTIONS.items() if key in done], flush=True)
    rt = summary["run_times_s"]
    t_all = time.perf_counter()

    (out / "assumptions.md").write_text(
        "| input | value | source |\n|---|---|---|\n"
        + "".join(f"| {i} | {v} | {s} |\n" for i, v, s in wu.ASSUMPTIONS))
    summary["assumptions"] = [dict(input=i, value=v, source=s) for i, v, s in wu.ASSUMPTIONS]

    def save():  # after every section, so that a long run interrupted keeps what it did
        (out / "summary.json").write_text(json.dumps(summary, indent=1, default=float))

    radii, rt["anchor_radii"] = _timed(lambda: {m: wu.anchor_radius(m) for m in MATERIALS})
    summary["anchor_radius_m"] = radii
    print("anchor radii [m]:", {k: round(v, 3) for k, v in radii.items()}, flush=True)

    if "surge_periods" not in summary:
        summary["surge_periods"], rt["surge_periods"] = _timed(surge_periods, radii, a)
        save()
    print("undamped surge periods [s]:",
          {m: round(v["period_s"], 1) for m, v in summary["surge_periods"].items()}, flush=True)

    if "dynamic" not in a.skip:
        (runs, table), rt["dynamic"] = _timed(dynamic_analysis, radii, a, out)
        summary["dynamic"], summary["dynamic_ratios"] = runs, table
        save()
    if "surge_periods_low_current" not in summary:
        # the uniformity cases reach down to half the base current, where the catenaries
        # are slacker and slower: their records must cover three of those periods too
        summary["surge_periods_low_current"], rt["surge_periods_low_current"] = _timed(
            surge_periods, radii, a, 0.5 * wu.CURRENT)
        save()
        print("undamped surge periods at half the current [s]:",
              {m: round(v["period_s"], 1) for m, v in summary["surge_periods_low_current"].items()},
              flush=True)

    def three_periods(mat):
        return 3 * max(summary[k][mat]["period_s"] for k in ("surge_periods", "surge_periods_low_current"))

    if "uniformity" not in a.skip:
        draws = draw_cases(a.cases, np.random.default_rng(a.seed + 1))
        uni = {"draws": {k: np.asarray(v).tolist() for k, v in draws.items()}}
        for mat in a.case_materials:
            record = a.case_duration or three_periods(mat)
            uni[mat] = uniformity(mat, radii[mat], a, draws, record, a.case_transient,
                                  store=out / "uniformity_cases")
            u = uni[mat]
            print(f"uniformity {mat}: std peak {u['std_peak_N'] / 1e3:.2f} kN, std mean "
                  f"{u['std_mean_N'] / 1e3:.2f} kN ({u['ok']}/{u['cases']} ok, {record:.0f} s records, "
                  f"{u['ensemble_s']:.0f} s)", flush=True)
            rt[f"uniformity_{mat}"] = u["statics_s"] + u["ensemble_s"]
        # a part of the materials is kept apart, so that a resumed full run still runs them all
        summary["uniformity" if set(a.case_materials) == set(MATERIALS) else "uniformity_partial"] = uni
        save()
    if "sensitivity" not in a.skip:
        summary["sensitivity"], rt["sensitivity"] = _timed(sensitivity, radii, a, out)
        save()
    if a.stress:
        summary["stress"], rt["stress"] = _timed(stress, radii, a)
    if "sweep" not in a.skip:
        summary["length_sweep"], rt["sweep"] = _timed(length_sweep, radii["polyester"], a)
        save()
    if "static" not in a.skip:
        offsets = np.array([0.0, 0.1, 0.2, 0.4, 0.6, 0.7, 0.8, 1.0, 1.5, 2.0])
        summary["static"], rt["static"] = _timed(static_analysis, radii, offsets, a.segments)
        s = summary["static"]
        np.savetxt(out / "static_offset.csv",
                   np.column_stack([offsets] + [s[m] for m in MATERIALS]), delimiter=",",
                   comments="", header="surge_m," + ",".join(f"{m}_restoring_N" for m in MATERIALS))
        print(f"static: poly−steel {s['poly_minus_steel_at_0.2m_N'] / 1e3:.1f} kN at 0.2 m, "
              f"{s['poly_minus_steel_at_1.0m_N'] / 1e3:.1f} kN at 1.0 m, crossover "
              f"{s['crossover_offset_m']}", flush=True)
        save()

    if "convergence" not in a.skip:
        base = summary.get("dynamic", {}).get(f"{a.currents[0]:g}ms_{a.starts[0]}")
        summary["convergence"], rt["convergence"] = _timed(convergence, radii, a, base)
        save()
    rt["total_this_process"] = time.perf_counter() - t_all
    for mat in MATERIALS:
        u = summary.get("uniformity", {}).get(mat)
        if u is not None:
            # cost of the full study (100 cases, records of 3 surge periods after 200 s)
            # from this run, linear in cases × simulated time (a vmapped batch steps
            # together); includes this run's compilation, so it errs high
            full = three_periods(mat) + 200.0
            u["estimated_full_s"] = (u["ensemble_s"] * (100 / u["cases"]) * full
                                     / (u["record_s"] + u["transient_s"]))
            u["full_record_s"] = three_periods(mat)

    claims = _claims(summary, a)
    summary["claims"] = claims
    summary["figures"] = _figures_table(summary)
    (out / "table.md").write_text(_table_md(summary))
    (out / "summary.json").write_text(json.dumps(summary, indent=1, default=float))
    if a.json:
        Path(a.json).parent.mkdir(parents=True, exist_ok=True)
        Path(a.json).write_text(json.dumps(
            {"claims": claims, "figures": summary["figures"], "settings": summary["settings"],
             "run_times_s": rt}, indent=1, default=float))
    print(_table_md(summary))
    try:
        _plots(out, summary)
    except ImportError:
        print("matplotlib not installed: no figures")
    return summary


def _claims(summary, a):
    base = f"{a.currents[0]:g}ms_{a.starts[0]}"
    ours = {}
    if "dynamic" in summary:
        ours.update(_ratios(summary["dynamic"][base]))
    u = summary.get("uniformity", {})
    if "polyester" in u and "chain" in u:
        ours["std_peak_polyester_over_chain"] = 100 * u["polyester"]["std_peak_N"] / u["chain"]["std_peak_N"]
        ours["std_mean_polyester_over_chain"] = 100 * u["polyester"]["std_mean_N"] / u["chain"]["std_mean_N"]
    where = {k: f"cable 3 (line 3), {base}" for k in PAPER if k.startswith("max")}
    where.update({k: f"{a.cases} cases, from equilibrium" for k in PAPER if k.startswith("std")})
    return {k: dict(paper=PAPER[k], moorjax=ours.get(k), unit="%", case=where[k]) for k in PAPER}


def _figures_table(summary):
    """Every number the table shows, with the paper's value where it gives one."""
    f = {}
    if "static" in summary:
        s = summary["static"]
        for key, name in (("static_poly_minus_steel_at_0.2m_N", "poly_minus_steel_at_0.2m_N"),
                          ("static_poly_minus_steel_at_1.0m_N", "poly_minus_steel_at_1.0m_N"),
                          ("static_crossover_offset_m", "crossover_offset_m")):
            f[key] = dict(paper=PAPER_FIGURES[key], moorjax=s[name])
        f["static_surge_stiffness_at_rest_N_per_m"] = dict(paper=None, moorjax=s["surge_stiffness_N_per_m"])
    if "dynamic" in summary:
        for key, runs in summary["dynamic"].items():
            if "polyester" in runs:
                f[f"polyester_mean_surge_m_{key}"] = dict(paper=PAPER_FIGURES["polyester_mean_surge_m"],
                                                          moorjax=runs["polyester"]["motion_mean"][0])
            f[f"cable3_max_tension_N_{key}"] = dict(
                paper=None, moorjax={m: r["max_tension_N"][C3] for m, r in runs.items()})
        for row in summary["dynamic_ratios"]:
            for k, v in row.items():
                if k != "case":
                    f[f"{k}_{row['case']}"] = dict(paper=PAPER[k], moorjax=v)
    if "sensitivity" in summary:
        base = summary["dynamic"][next(iter(summary["dynamic"]))] if "dynamic" in summary else {}
        for var, r in summary["sensitivity"].items():
            rec = {m: base[m] for m in base}
            rec[r["replaces"]] = r
            for k, v in _ratios(rec).items():
                f[f"{k}_sensitivity_{var}"] = dict(paper=PAPER[k], moorjax=v)
    if "surge_periods" in summary:
        f["undamped_surge_period_s"] = dict(paper=None, moorjax={m: v["period_s"] for m, v in summary["surge_periods"].items()})
    if "length_sweep" in summary:
        f["length_sweep_mean_force_N"] = dict(
            paper="decreases 106→116 m, abrupt drop 110→112 m (L252–254)",
            moorjax={r["length_m"]: r.get("mean_N") for r in summary["length_sweep"]})
    if "uniformity" in summary:
        u = summary["uniformity"]
        for m in MATERIALS:
            if m in u:
                f[f"uniformity_std_peak_N_{m}"] = dict(paper=None, moorjax=u[m]["std_peak_N"])
                f[f"uniformity_std_mean_N_{m}"] = dict(paper=None, moorjax=u[m]["std_mean_N"])
        if "polyester" in u and "steel" in u:
            f["std_peak_polyester_over_steel"] = dict(paper=None, moorjax=100 * u["polyester"]["std_peak_N"] / u["steel"]["std_peak_N"])
            f["std_mean_polyester_over_steel"] = dict(paper=None, moorjax=100 * u["polyester"]["std_mean_N"] / u["steel"]["std_mean_N"])
    if "convergence" in summary:
        for r in summary["convergence"]:
            tag = f"N{r['segments']}_rtol{r['rtol']:g}"
            for k in ("max_tension_polyester_over_chain", "max_tension_polyester_over_steel"):
                if k in r:
                    f[f"{k}_convergence_{tag}"] = dict(paper=PAPER[k], moorjax=r[k])
    return f


def _fmt(v):
    if v is None:
        return "—"
    if isinstance(v, dict):
        return ", ".join(f"{k}: {_fmt(x)}" for k, x in v.items())
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    if isinstance(v, str):
        return v
    return f"{v:.4g}"


def _table_md(summary):
    lines = ["| claim (Wu et al.) | paper | moorjax | case |", "|---|---|---|---|"]
    for k, c in summary["claims"].items():
        v = c["moorjax"]
        lines.append(f"| {k} | {c['paper']:.2f} % | {'—' if v is None else f'{v:.1f} %'} | {c['case']} |")
    lines += ["", "| figure | paper | moorjax |", "|---|---|---|"]
    for k, c in summary["figures"].items():
        lines.append(f"| {k} | {_fmt(c['paper'])} | {_fmt(c['moorjax'])} |")
    return "\n".join(lines) + "\n"


def _plots(out, summary):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if "static" in summary:
        s = summary["static"]
        fig, ax = plt.subplots(figsize=(5, 3.5))
        for m in MATERIALS:
            ax.plot(s["offset_m"], np.asarray(s[m]) / 1e3, label=m)
        ax.set(xlabel="surge offset [m]", ylabel="restoring force [kN]", title="Static offset (Fig. 13)")
        ax.legend()
        fig.tight_layout()
        fig.savefig(out / "static_offset.png", dpi=90)
        plt.close(fig)
    for key in summary.get("dynamic", {}):
        data = {m: np.genfromtxt(out / f"dynamic_{m}_{key}.csv", delimiter=",", names=True)
                for m in summary["dynamic"][key]}
        fig, axes = plt.subplots(6, 1, figsize=(7, 11), sharex=True)
        for m, d in data.items():
            axes[0].plot(d["t"], d["L3_tension_b"] / 1e3, label=m, lw=0.7)
            for ax, dof in zip(axes[1:], ("surge", "sway", "heave", "roll", "pitch")):
                ax.plot(d["t"], d[dof], lw=0.7, label=m)
        axes[0].set_ylabel("cable 3 tension [kN]")
        axes[0].set_title(f"Figs. 5–9, current {key.replace('ms_', ' m/s, from ')}")
        for ax, dof in zip(axes[1:], ("surge [m]", "sway [m]", "heave [m]", "roll [rad]", "pitch [rad]")):
            ax.set_ylabel(dof)
        axes[0].legend(fontsize=7)
        axes[-1].set_xlabel("t [s]")
        fig.tight_layout()
        fig.savefig(out / f"dynamic_{key}.png", dpi=80)
        plt.close(fig)
        fig, axes = plt.subplots(1, 3, figsize=(11, 3.3))
        for ax, dof in zip(axes, ("surge", "sway", "heave")):
            for m, d in data.items():
                ax.plot(d[dof], d[f"{dof}_velocity"], lw=0.5, label=m)
            ax.set(xlabel=f"{dof} [m]", ylabel=f"{dof} velocity [m/s]", title=f"{dof} ({key})")
        axes[0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(out / f"phase_{key}.png", dpi=80)
        plt.close(fig)
    rows = [r for r in summary.get("length_sweep", []) if "mean_N" in r]
    if rows:
        fig, ax = plt.subplots(figsize=(5, 3.5))
        for k in range(4):
            ax.plot([r["length_m"] for r in rows], [r["mean_N"][k] / 1e3 for r in rows], "o-",
                    label=f"cable {k + 1}")
        ax.set(xlabel="cable length [m]", ylabel="mean dynamic force [kN]", title="Polyester (Fig. 4)")
        ax.legend()
        fig.tight_layout()
        fig.savefig(out / "length_sweep.png", dpi=90)
        plt.close(fig)
    u = summary.get("uniformity", {})
    mats = [m for m in MATERIALS if m in u]
    if mats:
        fig, ax = plt.subplots(figsize=(5, 3.5))
        x = np.arange(len(mats))
        ax.bar(x - 0.2, [u[m]["std_peak_N"] / 1e3 for m in mats], 0.4, label="std of peak")
        ax.bar(x + 0.2, [u[m]["std_mean_N"] / 1e3 for m in mats], 0.4, label="std of mean")
        ax.set_xticks(x, mats)
        ax.set(ylabel="std across the four lines [kN]", title=f"Uniformity (Fig. 14), {u[mats[0]]['cases']} cases")
        ax.legend()
        fig.tight_layout()
        fig.savefig(out / "uniformity.png", dpi=90)
        plt.close(fig)


if __name__ == "__main__":
    main()
