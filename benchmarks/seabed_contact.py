"""Seabed contact law: MoorDyn's damping step against moorjax's ramped damping.

Case A (chain catenary, a node near the anchor lifts off and lands) at N
segments, with the seabed damping switched on at full size on contact
(``damping_depth=0``, MoorDyn's law) and ramped in over the rest penetration
(moorjax's default, see :class:`moorjax.Seabed`). For each law: adaptive
kvaerno5 at the default tolerances (error against the MoorDyn N = 160
reference, steps, rejections, ms per simulated second) and kvaerno5 at fixed
steps (does the run complete?).

    python benchmarks/seabed_contact.py [--n 40] [--duration 20] [--quick]
                                        [--reference DIR] [--json out.json]
"""

from __future__ import annotations

import os
import sys

import equinox as eqx
import jax.numpy as jnp

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

LAWS = {"step (MoorDyn)": 0.0, "ramp (default)": None}
FIXED_DT = (5e-3, 1e-2, 2e-2, 5e-2)


def with_law(scene, depth):
    """The scene with its seabed's damping ramp depth set (None: default ramp)."""
    value = None if depth is None else jnp.asarray(depth, dtype=float)
    return eqx.tree_at(lambda s: s.env.seabed.damping_depth, scene, value,
                       is_leaf=lambda x: x is None)


def main(argv=None):
    p = base_parser(__doc__)
    p.add_argument("--n", type=int, default=40, help="segments (default 40)")
    p.add_argument("--duration", type=float, default=20.0, help="simulated seconds (default 20)")
    args = p.parse_args(argv)
    fixed = FIXED_DT[1:3] if args.quick else FIXED_DT
    print(f"seabed contact, case A, N = {args.n}, {args.duration:g} s simulated")
    print(NOISE_NOTE)
    base = case_scene("A", args.n)
    init = static_init(base)
    rows = []
    for law, depth in LAWS.items():
        scene = with_law(base, depth)
        plans = [("adaptive", {})] + [(f"dt {1e3 * dt:g} ms", {"dt": dt}) for dt in fixed]
        for setting, kw in plans:
            r = timed_run(scene, args.duration, solver="kvaerno5", init=init, **kw)
            r["rel_err"] = rel_error(r, "A")
            r.pop("result")
            rows.append(dict(law=law, setting=setting, **r))
            err = "-" if r["rel_err"] is None else f"{100 * r['rel_err']:.3f} %"
            print(f"  {law:15s} {setting:9s} {r['outcome'][:60]:30s} "
                  f"{r['ms_per_sim_s']:8.1f} ms/sim-s  err {err}", flush=True)
    print_table(rows, [
        ("law", "law", ""), ("kvaerno5", "setting", ""),
        ("outcome", lambda r: r["outcome"][:44], ""), ("steps", "steps", "d"),
        ("rejected", "rejected", "d"), ("ms/sim-s", "ms_per_sim_s", ".1f"),
        ("err/std", lambda r: None if r["rel_err"] is None else f"{100 * r['rel_err']:.3f}%", ""),
    ], title=f"case A, N = {args.n} (error: RMS end-B tension − reference |F|, over its std)")
    write_json(args.json, dict(runs=jsonable(rows), n=args.n, duration_s=args.duration))
    return 0


if __name__ == "__main__":
    sys.exit(main())
