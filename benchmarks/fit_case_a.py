"""Real-data check of the identification: fit case A's Cd_normal to MoorDyn's history.

Case A of the reference set (OC3-like chain, 135 m on the seabed, fairlead
x = −5.2 + 5·sin(2πt/10) m) was run with MoorDyn 2.7.2 at N = 160 segments
(rk4, converged in time). This script fits the normal drag coefficient of a
moorjax model of the same deck to that history, starting from half the deck's
value (0.8 instead of 1.6), and reports how close the fit lands to the deck's
value (target: within 10 %; the two codes' discretisations differ, and the
reference is itself good to ~0.3 % of the tension std).

It goes through ``moorjax fit`` (the CLI's own code path: deck, motion and target
files, ``load_experiment``, ``fit`` with optax L-BFGS and the safeguarded line
search, the Gauss–Newton standard deviation, FIT.json). The target file has one
column, ``L1_tension_b`` = |F| of the reference (``Fx_N, Fy_N, Fz_N``: MoorDyn's
force of the line on the fairlead, the end node's net force — what moorjax's
end tension is; ``T_fair_N`` is the tension at the top segment's midpoint, not
comparable). Motion and target are cut to the first ``--duration`` seconds (the
files must span the same time); ``--window`` restricts the samples that count
(e.g. ``5,60`` to leave out the start-up transient).

    PYTHONPATH=. python benchmarks/fit_case_a.py [--segments 20] [--duration 60] [--dt 0.01]
        [--window T0,T1] [--steps 30] [--reference-dir DIR] [--json out.json]

Reference files (``case_A.dat``, ``motion_A.csv``, ``ref_A.csv``) are read from
``--reference-dir`` (default ``$MOORJAX_REFERENCE_DIR``, else ``../shared/reference``
next to the repository). Timings are wall times of the whole fit (compilation
included) on whatever machine runs it; say how loaded it was.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from moorjax.cli import main as moorjax_main  # noqa: E402
from moorjax.io import build_scene, read_deck  # noqa: E402
from moorjax.model.parameters import get_parameter  # noqa: E402

FILES = dict(deck="case_A.dat", motion="motion_A.csv", reference="ref_A.csv")


def reference_dir():
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    return os.environ.get("MOORJAX_REFERENCE_DIR", os.path.join(here, "..", "shared", "reference"))


def write_inputs(ref_dir, out_dir, duration):
    """Motion and target CSVs cut to t ≤ ``duration`` [s]; returns their paths."""
    motion_path = os.path.join(ref_dir, FILES["motion"])
    with open(motion_path) as f:
        header = f.readline().strip()
    motion = np.loadtxt(motion_path, delimiter=",", skiprows=1)
    motion = motion[motion[:, 0] <= duration + 1e-9]
    ref = np.loadtxt(os.path.join(ref_dir, FILES["reference"]), delimiter=",", skiprows=1)
    ref = ref[ref[:, 0] <= duration + 1e-9]
    if motion[-1, 0] < duration - 1e-9 or ref[-1, 0] < duration - 1e-9:
        raise ValueError(f"--duration {duration} s is longer than the reference files "
                         f"({motion[-1, 0]:g} s of motion, {ref[-1, 0]:g} s of history)")
    paths = dict(motion=os.path.join(out_dir, "motion_A.csv"), target=os.path.join(out_dir, "target_A.csv"))
    np.savetxt(paths["motion"], motion, delimiter=",", header=header, comments="", fmt="%.10f")
    # |F|: the force of the line on the fairlead (columns Fx_N, Fy_N, Fz_N)
    np.savetxt(paths["target"], np.column_stack([ref[:, 0], np.linalg.norm(ref[:, 3:6], axis=1)]),
               delimiter=",", header="t,L1_tension_b", comments="", fmt="%.6f")
    return paths


def fit_case_a(segments=20, duration=60.0, dt=0.01, window=None, steps=30, start_factor=0.5,
               ref_dir=None, solver="kvaerno3"):
    """Run ``moorjax fit`` on case A; returns FIT.json's content plus the deck value and wall time."""
    ref_dir = ref_dir or reference_dir()
    deck = os.path.join(ref_dir, FILES["deck"])
    missing = [f for f in FILES.values() if not os.path.exists(os.path.join(ref_dir, f))]
    if missing:
        raise FileNotFoundError(f"{ref_dir}: missing {', '.join(missing)} (set --reference-dir)")
    deck_cd = float(get_parameter(build_scene(read_deck(deck)), "Cd_normal"))
    with tempfile.TemporaryDirectory() as tmp:
        paths = write_inputs(ref_dir, tmp, duration)
        out = os.path.join(tmp, "fit_A.json")
        argv = ["fit", deck, "--motion", paths["motion"], "--target", paths["target"],
                "--params", "Cd_normal", "--start", f"Cd_normal={start_factor * deck_cd}",
                "--segments", str(segments), "--dt", str(dt), "--solver", solver,
                "--steps", str(steps), "--out", out]
        if window is not None:
            argv += ["--window", f"{window[0]},{window[1]}"]
        t0 = time.perf_counter()
        rc = moorjax_main(argv)
        wall = time.perf_counter() - t0
        if rc != 0:
            raise RuntimeError(f"moorjax fit failed (exit {rc}): see the message above")
        with open(out) as f:
            res = json.load(f)
    res.update(deck_value=deck_cd, wall_s=wall, argv=argv[1:])
    return res


def report(res):
    p = res["params"]["Cd_normal"]
    s = res["settings"]
    rel = p["fitted"] / res["deck_value"] - 1
    std = "n/a" if p["std"] is None else f"{p['std']:.2g}"
    print(f"case A, N = {s['segments']}, dt = {s['dt']} s ({s['solver']}), 0-{res['duration_s']:g} s, "
          f"window {s['window'] or 'all'}")
    print(f"  Cd_normal: initial {p['initial']:.4g}, fitted {p['fitted']:.5f} (GN std {std}), "
          f"deck {res['deck_value']:.4g}: {100 * rel:+.2f} %  ({'within' if abs(rel) <= 0.1 else 'NOT within'} 10 %)")
    print(f"  loss {res['initial_loss']:.4g} -> {res['final_loss']:.4g}; {res['iterations']} steps, "
          f"{res['evaluations']} loss+gradient evaluations; {res['status']}: {res['message']}")
    print("  loss history: " + ", ".join(f"{x:.4g}" for x in res["loss_history"]))
    print(f"  run time (wall, compilation included): {res['wall_s']:.0f} s")
    return rel


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--segments", type=int, default=20, help="segments of the moorjax line (default 20)")
    p.add_argument("--duration", type=float, default=60.0, help="simulated time [s] (default 60, the whole reference)")
    p.add_argument("--dt", type=float, default=0.01, help="fixed step [s] (default 0.01)")
    p.add_argument("--solver", default="kvaerno3", help="time stepper (default kvaerno3)")
    p.add_argument("--window", metavar="T0,T1", help="only samples with T0 <= t <= T1 [s] count")
    p.add_argument("--steps", type=int, default=30, help="maximum optimiser steps (default 30)")
    p.add_argument("--start-factor", type=float, default=0.5, help="start at this fraction of the deck's Cd (default 0.5)")
    p.add_argument("--reference-dir", help="folder of case_A.dat, motion_A.csv, ref_A.csv")
    p.add_argument("--json", metavar="PATH", help="write FIT.json plus the deck value and time here")
    a = p.parse_args(argv)
    window = None if a.window is None else tuple(float(x) for x in a.window.split(","))
    res = fit_case_a(a.segments, a.duration, a.dt, window, a.steps, a.start_factor, a.reference_dir, a.solver)
    res["duration_s"] = a.duration
    rel = report(res)
    res["rel_to_deck"] = rel
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=2)
        print(f"wrote {a.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
