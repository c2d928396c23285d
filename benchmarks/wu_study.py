"""Wu et al.'s study end to end: polyester against steel wire and chain.

Regenerates, for the moored box of :mod:`moorjax.examples.wu_box` (every modelling
choice the paper leaves open is documented there):

1. static analysis: restoring force against surge offset per material
   (``static_offset.csv``) and the AD stiffness matrices (``stiffness.json``);
2. dynamic analysis: tension histories of the four lines and the six motions per
   material (``dynamic_<material>.csv``);
3. cable-length sweep 106–116 m (polyester, anchors fixed where 110 m lines have
   20 kN): mean and max dynamic force per line, grounded length (``length_sweep.csv``);
4. uniformity: ``--cases`` environmental cases (heading, Hs, Tz, wind, current and
   wave seed drawn at random around the base case), run as one vmapped ensemble per
   material; per case the standard deviation across the four lines of the peak and
   of the mean force, averaged over the cases (``uniformity.csv``);
5. ``table.md``: the paper's quantitative claims beside ours; ``summary.json``
   with every number and the run times; figures (``*.png``) with matplotlib.

Usage::

    PYTHONPATH=. python benchmarks/wu_study.py --out wu_results            # full
    PYTHONPATH=. python benchmarks/wu_study.py --out wu_quick --quick      # minutes

Run times are separated into compile (first call) and run.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import moorjax  # noqa: F401  (float64)
from moorjax.body import DOF_NAMES
from moorjax.dynamics import simulate
from moorjax.ensemble import simulate_ensemble
from moorjax.ensemble.run import status as ensemble_status
from moorjax.examples import wu_box as wu
from moorjax.statics import mooring_stiffness, offset_curve, solve_system_statics

MATERIALS = ("polyester", "steel", "chain")
PAPER = {
    "max tension polyester / chain": 67.72,
    "max tension polyester / steel": 91.58,
    "std of peak force polyester / chain": 48.89,
    "std of mean force polyester / chain": 23.12,
}


def _stack_states(states):
    return jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *states)


def static_analysis(radii, offsets, n_segments):
    rows, stiff = [], {}
    for mat in MATERIALS:
        sc = wu.scene(mat, radius=radii[mat], n_segments=n_segments, waves=False, wind=0.0,
                      current=0.0, radiation=False)
        f = np.asarray(offset_curve(sc, offsets, dof=0))
        rows.append(f)
        k = np.asarray(mooring_stiffness(sc))
        stiff[mat] = k.tolist()
    return np.column_stack([offsets] + rows), stiff


def run_dynamic(mat, radius, args, length=wu.LINE_LENGTH, **env):
    sc = wu.scene(mat, radius=radius, length=length, n_segments=args.segments, seed=args.seed,
                  n_components=args.components, **env)
    st = solve_system_statics(sc)
    init = st.state() + st.body_states(sc)
    kw = dict(dt_out=args.dt_out, solver=args.solver, rtol=args.rtol, atol=args.atol)
    t0 = time.perf_counter()
    res = simulate(sc, args.duration, init=init, **kw)
    jax.block_until_ready(res.tension_b)
    wall = time.perf_counter() - t0
    return sc, st, res, wall


def uniformity(mat, radius, args, rng):
    n = args.cases
    draws = dict(
        heading=wu.HEADING + np.radians(rng.uniform(-30, 30, n)),
        hs=rng.uniform(0.5 * wu.HS, wu.HS, n),
        tz=rng.uniform(5.0, 7.0, n),
        wind=rng.uniform(0.5 * wu.WIND, wu.WIND, n),
        current=rng.uniform(0.5 * wu.CURRENT, wu.CURRENT, n),
        seed=rng.integers(0, 2**31 - 1, n),
    )
    scenes, inits = [], []
    t0 = time.perf_counter()
    for i in range(n):
        sc = wu.scene(mat, radius=radius, n_segments=args.segments,
                      n_components=args.components,
                      **{k: (int(v[i]) if k == "seed" else float(v[i])) for k, v in draws.items()})
        st = solve_system_statics(sc, throw=False)  # a start near equilibrium is enough
        if not st.converged:
            print(f"  case {i}: statics left an imbalance of "
                  f"{float(np.max(np.abs(np.asarray(st.residual)))):.3g} N; starting there", flush=True)
        scenes.append(sc)
        inits.append(st.state() + st.body_states(sc))
    t_statics = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = simulate_ensemble(scenes, args.case_duration, init=_stack_states(inits),
                            dt_out=args.dt_out, solver=args.solver, rtol=args.rtol, atol=args.atol)
    jax.block_until_ready(res.tension_b)
    wall = time.perf_counter() - t0
    ok = np.array([s == "ok" for s in ensemble_status(res)])
    ten = np.asarray(res.tension_b)  # (cases, k, 4)
    skip = int(round(args.transient / args.dt_out))
    ten = ten[:, skip:]
    peak = ten.max(axis=1)
    mean = ten.mean(axis=1)
    return dict(
        cases=n, ok=int(ok.sum()),
        std_peak=float(np.mean(peak[ok].std(axis=1))),
        std_mean=float(np.mean(mean[ok].std(axis=1))),
        statics_s=t_statics, ensemble_s=wall, draws={k: np.asarray(v).tolist() for k, v in draws.items()},
    )


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--duration", type=float, default=300.0, help="dynamic runs [s]")
    p.add_argument("--transient", type=float, default=20.0, help="start-up discarded in statistics [s]")
    p.add_argument("--segments", type=int, default=8, help="elements per line")
    p.add_argument("--components", type=int, default=100, help="wave components")
    p.add_argument("--cases", type=int, default=100, help="uniformity cases")
    p.add_argument("--case-duration", type=float, default=120.0, help="uniformity runs [s]")
    p.add_argument("--lengths", type=float, nargs="+", default=[106, 108, 110, 112, 114, 116])
    p.add_argument("--sweep-duration", type=float, default=120.0, help="length-sweep runs [s]")
    p.add_argument("--solver", default="kvaerno3")
    p.add_argument("--rtol", type=float, default=1e-3)
    p.add_argument("--atol", type=float, default=1e-2, help="position tolerance [m]")
    p.add_argument("--dt-out", type=float, default=0.25)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--quick", action="store_true",
                   help="short runs: 60 s dynamics, 10 cases of 40 s, 3 lengths of 40 s")
    p.add_argument("--materials", nargs="+", default=list(MATERIALS), choices=MATERIALS,
                   help="materials of the uniformity study")
    p.add_argument("--skip", nargs="*", default=[], choices=["static", "dynamic", "sweep", "uniformity"])
    a = p.parse_args(argv)
    if a.quick:
        a.duration, a.cases, a.case_duration, a.sweep_duration = 60.0, 10, 40.0, 40.0
        a.lengths = [106.0, 110.0, 116.0]
        a.transient = 10.0
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    summary = dict(settings=vars(a).copy())

    t0 = time.perf_counter()
    radii = {m: wu.anchor_radius(m) for m in MATERIALS}
    summary["anchor_radius_m"] = radii
    print("anchor radii [m]:", {k: round(v, 3) for k, v in radii.items()}, flush=True)

    if "static" not in a.skip:
        offsets = np.linspace(0.0, 2.0, 11)
        curve, stiff = static_analysis(radii, offsets, a.segments)
        np.savetxt(out / "static_offset.csv", curve, delimiter=",", comments="",
                   header="surge_m," + ",".join(f"{m}_restoring_N" for m in MATERIALS))
        (out / "stiffness.json").write_text(json.dumps(stiff, indent=1))
        summary["static"] = {
            "offset_m": offsets.tolist(),
            **{m: curve[:, 1 + i].tolist() for i, m in enumerate(MATERIALS)},
            "surge_stiffness_N_per_m": {m: stiff[m][0][0] for m in MATERIALS},
        }
        print("static offset curve done", flush=True)

    dyn = {}
    if "dynamic" not in a.skip:
        for mat in MATERIALS:
            sc, st, res, wall = run_dynamic(mat, radii[mat], a)
            t = np.asarray(res.ts)
            pose = np.asarray(res.body_pose[:, 0])
            vel = np.asarray(res.body_velocity[:, 0])
            ten = np.asarray(res.tension_b)
            cols = np.column_stack([t, pose, vel, ten])
            header = ("t," + ",".join(DOF_NAMES) + "," + ",".join(f"{d}_velocity" for d in DOF_NAMES)
                      + "," + ",".join(f"L{k + 1}_tension_b" for k in range(4)))
            np.savetxt(out / f"dynamic_{mat}.csv", cols, delimiter=",", header=header, comments="")
            keep = t >= a.transient
            dyn[mat] = dict(
                wall_s=wall, steps=int(res.num_steps), rejected=int(res.num_rejected_steps),
                pretension_N=[float(s.tension_b) for s in st.lines],
                static_pose=np.asarray(st.poses[0]).tolist(),
                max_tension_N=ten[keep].max(axis=0).tolist(),
                mean_tension_N=ten[keep].mean(axis=0).tolist(),
                motion_mean=pose[keep].mean(axis=0).tolist(),
                motion_std=pose[keep].std(axis=0).tolist(),
            )
            print(f"dynamic {mat}: {wall:.1f} s (incl. compile), {int(res.num_steps)} steps, "
                  f"max tension {ten[keep].max() / 1e3:.1f} kN", flush=True)
        summary["dynamic"] = dyn

    if "sweep" not in a.skip:
        rows = []
        sweep_args = argparse.Namespace(**{**vars(a), "duration": a.sweep_duration})
        for length in a.lengths:
            sc, st, res, wall = run_dynamic("polyester", radii["polyester"], sweep_args, length=length)
            t = np.asarray(res.ts)
            ten = np.asarray(res.tension_b)[t >= a.transient]
            grounded = [float(s.grounded_length) for s in st.lines]
            rows.append([length, *ten.mean(axis=0), *ten.max(axis=0), *grounded, wall])
            print(f"length {length:g} m: mean force {ten.mean(axis=0).round(0)} N", flush=True)
        header = ("length_m," + ",".join(f"L{k}_mean_N" for k in range(1, 5)) + ","
                  + ",".join(f"L{k}_max_N" for k in range(1, 5)) + ","
                  + ",".join(f"L{k}_grounded_m" for k in range(1, 5)) + ",wall_s")
        np.savetxt(out / "length_sweep.csv", np.array(rows), delimiter=",", header=header, comments="")
        summary["length_sweep"] = [dict(zip(header.split(","), r)) for r in rows]

    if "uniformity" not in a.skip:
        uni = {}
        for mat in a.materials:
            uni[mat] = uniformity(mat, radii[mat], a, np.random.default_rng(a.seed + 1))
            print(f"uniformity {mat}: std peak {uni[mat]['std_peak'] / 1e3:.2f} kN, std mean "
                  f"{uni[mat]['std_mean'] / 1e3:.2f} kN ({uni[mat]['ok']}/{a.cases} ok, "
                  f"{uni[mat]['ensemble_s']:.0f} s)", flush=True)
        summary["uniformity"] = uni
        with open(out / "uniformity.csv", "w") as f:
            f.write("material,cases,ok,std_peak_N,std_mean_N,ensemble_s\n")
            for m, u in uni.items():
                f.write(f"{m},{u['cases']},{u['ok']},{u['std_peak']},{u['std_mean']},{u['ensemble_s']}\n")

    ours = {}
    if dyn:
        mx = {m: max(dyn[m]["max_tension_N"]) for m in dyn}
        ours["max tension polyester / chain"] = 100 * mx["polyester"] / mx["chain"]
        ours["max tension polyester / steel"] = 100 * mx["polyester"] / mx["steel"]
    if "uniformity" in summary and {"polyester", "chain"} <= set(summary["uniformity"]):
        u = summary["uniformity"]
        ours["std of peak force polyester / chain"] = 100 * u["polyester"]["std_peak"] / u["chain"]["std_peak"]
        ours["std of mean force polyester / chain"] = 100 * u["polyester"]["std_mean"] / u["chain"]["std_mean"]
    summary["claims"] = {k: dict(paper_percent=PAPER[k], moorjax_percent=ours.get(k)) for k in PAPER}
    summary["total_s"] = time.perf_counter() - t0
    lines = ["| claim (Wu et al.) | paper | moorjax |", "|---|---|---|"]
    for k in PAPER:
        v = ours.get(k)
        lines.append(f"| {k} | {PAPER[k]:.2f} % | {'—' if v is None else f'{v:.1f} %'} |")
    (out / "table.md").write_text("\n".join(lines) + "\n")
    (out / "summary.json").write_text(json.dumps(summary, indent=1, default=float))
    print("\n".join(lines))
    try:
        _figures(out, summary)
    except ImportError:
        print("matplotlib not installed: no figures")
    return summary


def _figures(out, summary):
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
    if "dynamic" in summary:
        data = {m: np.genfromtxt(out / f"dynamic_{m}.csv", delimiter=",", names=True) for m in summary["dynamic"]}
        fig, axes = plt.subplots(6, 1, figsize=(7, 11), sharex=True)
        for m, d in data.items():
            axes[0].plot(d["t"], d["L3_tension_b"] / 1e3, label=m, lw=0.7)
            for ax, dof in zip(axes[1:], ("surge", "sway", "heave", "roll", "pitch")):
                ax.plot(d["t"], d[dof], lw=0.7, label=m)
        axes[0].set_ylabel("line 3 tension [kN]")
        for ax, dof in zip(axes[1:], ("surge [m]", "sway [m]", "heave [m]", "roll [rad]", "pitch [rad]")):
            ax.set_ylabel(dof)
        axes[0].legend(fontsize=7)
        axes[-1].set_xlabel("t [s]")
        fig.tight_layout()
        fig.savefig(out / "dynamic.png", dpi=80)
        plt.close(fig)
        fig, axes = plt.subplots(1, 3, figsize=(11, 3.3))
        for ax, dof in zip(axes, ("surge", "sway", "heave")):
            for m, d in data.items():
                ax.plot(d[dof], d[f"{dof}_velocity"], lw=0.5, label=m)
            ax.set(xlabel=f"{dof} [m]", ylabel=f"{dof} velocity [m/s]", title=f"Phase diagram, {dof}")
        axes[0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(out / "phase.png", dpi=80)
        plt.close(fig)
    if "length_sweep" in summary:
        rows = summary["length_sweep"]
        fig, ax = plt.subplots(figsize=(5, 3.5))
        for k in range(1, 5):
            ax.plot([r["length_m"] for r in rows], [r[f"L{k}_mean_N"] / 1e3 for r in rows], "o-", label=f"cable {k}")
        ax.set(xlabel="cable length [m]", ylabel="mean dynamic force [kN]", title="Polyester (Fig. 4)")
        ax.legend()
        fig.tight_layout()
        fig.savefig(out / "length_sweep.png", dpi=90)
        plt.close(fig)


if __name__ == "__main__":
    main()
