"""Wu's box with the paper's element: cable-3 maximum tension, Hermite lines
against linear ones at N = 8 and 16 (issue 15's convergence check).

Each material at the study's base settings (``benchmarks/wu_study.py``'s
defaults: base environment with the 1.2 m/s current, start from rest, Kvaerno3,
rtol 1e-3, atol 1e-2 m, output every 0.5 s, 100 wave components, seed 0),
anchors where the 110 m lines have 20 kN horizontal pretension. The wall
times include compilation (one run per setting).

usage:
    PYTHONPATH=. python benchmarks/wu_hermite_check.py --duration 100 --json wu_hermite.json
"""

from __future__ import annotations

import argparse
import json
import time

import equinox as eqx
import jax
import numpy as np

from moorjax.dynamics import simulate
from moorjax.element import HermiteElement
from moorjax.examples import wu_box as wu

MATERIALS = ("polyester", "steel", "chain")
C3 = 2  # cable 3: line 3, the weather-side line (wu_box.CABLE_3)


def with_element(scene, element):
    """The scene with every line's element replaced."""
    return eqx.tree_at(lambda s: [ln.element for ln in s.lines], scene,
                       [element] * len(scene.lines))


def run(material, radius, segments, element, args):
    """(record dict) of one run."""
    sc = wu.scene(material, radius=radius, n_segments=segments, seed=0,
                  n_components=args.components, current=wu.CURRENT)
    if element is not None:
        sc = with_element(sc, element)
    t0 = time.perf_counter()
    st, init = wu.start_state(sc, "rest", throw=False)
    t1 = time.perf_counter()
    res = simulate(sc, args.duration, init=init, dt_out=0.5, solver="kvaerno3", rtol=1e-3,
                   atol=1e-2, throw=False)
    jax.block_until_ready(res.tension_b)
    t2 = time.perf_counter()
    ten = np.asarray(res.tension_b)
    return dict(material=material, element="hermite" if element is not None else "linear",
                segments=segments, statics_converged=bool(st.converged),
                succeeded=bool(res.succeeded()), t_end=float(np.asarray(res.ts)[-1]),
                cable3_max_N=float(np.nanmax(ten[:, C3])), max_N=np.nanmax(ten, axis=0).tolist(),
                steps=int(res.num_steps), rejected=int(res.num_rejected_steps),
                statics_wall_s=t1 - t0, run_wall_s=t2 - t1)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--duration", type=float, default=100.0, help="simulated time [s]")
    p.add_argument("--materials", nargs="+", default=list(MATERIALS))
    p.add_argument("--hermite-segments", type=int, nargs="+", default=[8])
    p.add_argument("--linear-segments", type=int, nargs="+", default=[8, 16])
    p.add_argument("--components", type=int, default=100, help="wave components")
    p.add_argument("--json", help="write the records here")
    args = p.parse_args(argv)
    rows = []
    for mat in args.materials:
        radius = wu.anchor_radius(mat)
        settings = ([(n, None) for n in args.linear_segments]
                    + [(n, HermiteElement()) for n in args.hermite_segments])
        for n, element in settings:
            r = run(mat, radius, n, element, args)
            rows.append(r)
            print(f"{mat:9s} {r['element']:7s} N={n:2d}: cable-3 max {r['cable3_max_N'] / 1e3:8.2f} kN, "
                  f"{r['steps']} steps ({r['rejected']} rejected), t_end {r['t_end']:.1f} s, "
                  f"statics {r['statics_wall_s']:.0f} s, run {r['run_wall_s']:.0f} s"
                  + ("" if r["succeeded"] and r["statics_converged"] else "  [FAILED]"), flush=True)
        if args.json:
            with open(args.json, "w") as f:
                json.dump(dict(duration_s=args.duration, rows=rows), f, indent=1)


if __name__ == "__main__":
    main()
