"""Skip what a scene doesn't need: the cost of each optional force term.

One line, case A's chain at N = 40 with its anchor raised to z = −200 m so that
it hangs free of the seabed (lowest node ≈ −267 m, 53 m above it) — every
variant then moves the same way and "no seabed" does not let the line fall
through the bottom. Variants remove the seabed, a 0.5 m/s uniform current,
added mass and drag (one at a time, then all). For each:

- HLO ops: lines of ``eqx.filter_jit(vector_field).lower(t, y, scene).as_text()``
  (StableHLO): an absent term is never traced, so the count must drop;
- µs per vector-field evaluation, in a jitted ``fori_loop`` of evaluations;
- µs per simulate step and ms per simulated second (adaptive kvaerno5,
  default tolerances; statics solved once, outside the timing), with the
  peak fairlead tension as the outcome.

All variants start from the same static equilibrium (solved without seabed and
current: the seabed is not touched, and the current's drag only adds a
transient at t = 0).

    python benchmarks/terms.py [--quick] [--json out.json]
"""

from __future__ import annotations

import os
import sys
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import moorjax as mj  # noqa: E402
from benchmarks.common import (  # noqa: E402
    NOISE_NOTE,
    base_parser,
    case_scene,
    jsonable,
    print_table,
    static_init,
    timed_run,
    write_json,
)
from moorjax.dynamics.vector_field import pack, vector_field  # noqa: E402

ANCHOR_Z = -200.0  # [m], raised from −320 m so the line hangs free
CURRENT = (0.5, 0.0, 0.0)  # [m/s]
VF_EVALS = 2000


def variants(n_segments: int):
    """(name, scene) pairs, the full scene first."""
    base = case_scene("A", n_segments)
    base = eqx.tree_at(lambda s: s.lines[0].end_a, base, mj.FixedEnd([-853.87, 0.0, ANCHOR_Z]))
    assert base.env.seabed is not None and base.lines[0].line_type.drag is not None
    assert base.lines[0].line_type.added_mass is not None
    is_none = lambda x: x is None  # noqa: E731
    full = eqx.tree_at(lambda s: s.env.current, base, mj.UniformCurrent(CURRENT), is_leaf=is_none)

    def drop(scene, *what):
        for w in what:
            where = {
                "seabed": lambda s: s.env.seabed,
                "current": lambda s: s.env.current,
                "added mass": lambda s: s.lines[0].line_type.added_mass,
                "drag": lambda s: s.lines[0].line_type.drag,
            }[w]
            scene = eqx.tree_at(where, scene, None)
        return scene

    return [
        ("full (seabed, current, added mass, drag)", full),
        ("no seabed", drop(full, "seabed")),
        ("no current", drop(full, "current")),
        ("no added mass", drop(full, "added mass")),
        ("no drag (current kept)", drop(full, "drag")),
        ("no drag, no current", drop(full, "drag", "current")),
        ("bare (elastic, damping, weight)", drop(full, "seabed", "current", "added mass", "drag")),
    ]


def hlo_lines(scene, y) -> int:
    text = eqx.filter_jit(vector_field).lower(0.0, y, scene).as_text()
    return sum(1 for ln in text.splitlines() if ln.strip())


@eqx.filter_jit
def _vf_loop(scene, y, n_evals: int):
    def body(i, carry):
        y, acc = carry
        f = vector_field(0.01 * i, y, scene)
        y = jax.tree_util.tree_map(lambda a, b: a + 1e-12 * b, y, f)
        return y, acc + sum(jnp.sum(x) for x in f)

    return jax.lax.fori_loop(0, n_evals, body, (y, jnp.asarray(0.0)))


def us_per_vf(scene, y, n_evals: int = VF_EVALS) -> tuple[float, bool]:
    jax.block_until_ready(_vf_loop(scene, y, n_evals))  # compile
    best = float("inf")
    for _ in range(3):
        t_a = time.perf_counter()
        out = jax.block_until_ready(_vf_loop(scene, y, n_evals))
        best = min(best, time.perf_counter() - t_a)
    finite = bool(np.isfinite(np.asarray(out[1])))
    return 1e6 * best / n_evals, finite


def main(argv=None):
    p = base_parser(__doc__)
    p.add_argument("--segments", type=int, default=40)
    args = p.parse_args(argv)
    duration = 5.0 if args.quick else 20.0
    print(f"moorjax force terms: case A chain, N={args.segments}, anchor at z={ANCHOR_Z:g} m, "
          f"{duration:g} s simulated")
    print(NOISE_NOTE)
    vs = variants(args.segments)
    bare = vs[-1][1]  # no seabed, no current: the static solve converges fast
    init = static_init(bare)
    z_min = float(jnp.min(init[0].r[:, 2]))
    depth = float(bare.env.depth)
    print(f"static lowest node z = {z_min:.1f} m (seabed at {-depth:g} m)")
    y = pack(init)
    rows = []
    for name, scene in vs:
        ops = hlo_lines(scene, y)
        us, finite = us_per_vf(scene, y)
        r = timed_run(scene, duration, init=init, solver="kvaerno5")
        res = r["result"]
        lowest = (float(jnp.min(res.final_state[0].r[:, 2])) if res is not None else float("nan"))
        if res is not None and lowest < -depth:
            r["outcome"] = f"line below seabed (z={lowest:.0f} m)"
        if not finite:
            r["outcome"] = "vf NaN in loop"
        rows.append(dict(variant=name, hlo_lines=ops, us_per_vf=us,
                         us_per_step=1e6 * r["run_s"] / r["steps"] if r["steps"] else None,
                         lowest_z_end=lowest, **r))
        print(f"  {name:<42} HLO {ops:6d}  {us:8.2f} µs/vf  {r['outcome'][:40]:<12} "
              f"{r['ms_per_sim_s']:8.1f} ms/sim-s", flush=True)
    full = rows[0]
    for r in rows:
        r["ops_vs_full"] = r["hlo_lines"] / full["hlo_lines"]
        r["vf_vs_full"] = r["us_per_vf"] / full["us_per_vf"]
    print_table(rows, [
        ("variant", "variant", ""), ("HLO lines", "hlo_lines", "d"),
        ("ops/full", "ops_vs_full", ".2f"), ("µs/vf eval", "us_per_vf", ".2f"),
        ("vf/full", "vf_vs_full", ".2f"), ("outcome", lambda r: r["outcome"][:40], ""),
        ("max T [kN]", lambda r: r["max_tension_N"] / 1e3, ".1f"), ("steps", "steps", "d"),
        ("µs/step", "us_per_step", ".0f"), ("ms/sim-s", "ms_per_sim_s", ".1f"),
        ("compile [s]", "compile_s", ".1f"),
    ], title="force terms (ms/sim-s also reflects how many steps each variant's dynamics need)")
    bad = [r["variant"] for r in rows[1:] if r["hlo_lines"] >= full["hlo_lines"]]
    slower = [r["variant"] for r in rows[1:] if r["us_per_vf"] > 1.1 * full["us_per_vf"]]
    print(f"\nchecks: variants not smaller in HLO than the full scene: {bad or 'none'}; "
          f"more than 10 % slower per vf eval than the full scene: {slower or 'none'}")
    write_json(args.json, dict(runs=jsonable(rows), quick=args.quick, duration_s=duration,
                               segments=args.segments, anchor_z=ANCHOR_Z, current=CURRENT,
                               vf_evals=VF_EVALS))
    return 0


if __name__ == "__main__":
    sys.exit(main())
