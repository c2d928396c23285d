"""Order of convergence in N of a reference case's fairlead tension, by motion amplitude.

Self-convergence: the case's line at N, 2N, 4N, … segments (or Hermite
elements) on its sine path of a given amplitude, adaptive with the solver
``auto`` picks (ROS34PW2 for linear lines, Kvaerno5 for Hermite ones) at tight
tolerances (default 1e-6 / 1e-5 m, so the time error is far below the space
error), the fairlead |F| sampled every 0.05 s. For each pair (N, 2N): the RMS
difference over t ≥ 0.5 s divided by the finer run's standard deviation, and
the observed order log2(d(N/2, N) / d(N, 2N)). Beside them, for each amplitude,
the least segment tension of the finest run (damping included: below zero a
segment is slack and being compressed) and the least fairlead tension, and at
the case's own amplitude the error against the MoorDyn N = 160 reference.

It separates what limits the order: case A's chain is second order while it
stays taut and first order once its grounded part goes slack and snaps taut
again (see benchmarks/README.md, session 42).

    python benchmarks/order_in_n.py [--case A] [--amplitudes 1 2.5 5]
                                    [--ns 10 20 40 80 160] [--element linear|hermite]
                                    [--duration 20] [--quick] [--json out.json]
"""

from __future__ import annotations

import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from benchmarks.common import (  # noqa: E402
    CASES,
    base_parser,
    case_scene,
    print_table,
    reference_csv,
    static_init,
    write_json,
)
from benchmarks.moordyn_runner import rel_rms_error  # noqa: E402

SETTLE_S = 0.5  # the start-up transient left out of the differences [s]


def difference(t, coarse, fine):
    """RMS(coarse − fine) over t ≥ SETTLE_S, over std(fine) there."""
    keep = t >= SETTLE_S
    return float(np.sqrt(np.mean((coarse[keep] - fine[keep]) ** 2)) / np.std(fine[keep]))


def run(case, n, amplitude, element, duration, rtol, atol):
    """Fairlead tension history, least segment tension and wall time of one run."""
    from moorjax.dynamics import simulate

    scene = case_scene(case, n, amplitude=amplitude, element=element)
    t_a = time.perf_counter()
    res = simulate(scene, duration, init=static_init(scene), rtol=rtol, atol=atol, dt_out=0.05,
                   save_nodes=True)
    tension = np.asarray(res.tension_b[:, 0])
    ts = np.asarray(res.ts)
    seg = np.asarray(res.segment_tensions[0])[ts >= SETTLE_S]
    return dict(t=ts, tension=tension, least_segment_N=float(seg.min()),
                least_fairlead_N=float(tension[ts >= SETTLE_S].min()), steps=int(res.num_steps),
                wall_s=time.perf_counter() - t_a)


def main(argv=None):
    p = base_parser(__doc__)
    p.add_argument("--case", choices=sorted(CASES), default="A")
    p.add_argument("--amplitudes", type=float, nargs="+", metavar="M",
                   help="fairlead sine amplitudes [m] (default: the case's own over 5, over 2, and itself: 1, 2.5, 5 for A; 0.4, 1, 2 for B)")
    p.add_argument("--ns", type=int, nargs="+", metavar="N", help="segment counts (default 10 20 40 80 160)")
    p.add_argument("--element", choices=("linear", "hermite"), default="linear")
    p.add_argument("--duration", type=float, default=20.0, help="simulated seconds (default 20)")
    p.add_argument("--rtol", type=float, default=1e-6)
    p.add_argument("--atol", type=float, default=1e-5, help="absolute position tolerance [m]")
    args = p.parse_args(argv)
    own = CASES[args.case].amplitude
    amplitudes = args.amplitudes or ([own / 2, own] if args.quick else [own / 5, own / 2, own])
    ns = sorted(args.ns or ([10, 20, 40, 80] if args.quick else [10, 20, 40, 80, 160]))
    if len(ns) < 2 or ns[0] < 1:
        p.error("--ns needs at least two segment counts, each at least 1")
    ref = reference_csv(args.case)
    print(f"order in N, case {args.case}, {args.element} element, {args.duration:g} s, "
          f"solver auto at {args.rtol:g}/{args.atol:g}")
    rows = []
    for amp in amplitudes:
        runs = {}
        for n in ns:
            runs[n] = run(args.case, n, amp, args.element, args.duration, args.rtol, args.atol)
            print(f"  amplitude {amp:g} m, N = {n}: {runs[n]['steps']} steps, {runs[n]['wall_s']:.1f} s",
                  flush=True)
        prev = None
        for a, b in zip(ns[:-1], ns[1:]):
            d = difference(runs[a]["t"], runs[a]["tension"], runs[b]["tension"])
            order = None if prev is None or d <= 0 else math.log(prev / d, b / a)
            err = (rel_rms_error(runs[a]["t"], runs[a]["tension"], ref)
                   if ref is not None and math.isclose(amp, own) else None)
            rows.append(dict(case=args.case, element=args.element, amplitude_m=amp, N=a, N_fine=b,
                             difference=d, order=order, rel_err_vs_reference=err,
                             least_segment_N=runs[ns[-1]]["least_segment_N"],
                             least_fairlead_N=runs[ns[-1]]["least_fairlead_N"]))
            prev = d
    print_table(rows, [
        ("amp m", "amplitude_m", "g"), ("N", "N", "d"), ("vs", "N_fine", "d"),
        ("diff/std", lambda r: f"{100 * r['difference']:.3f}%", ""),
        ("order", "order", ".2f"),
        ("least seg T kN", lambda r: r["least_segment_N"] / 1e3, ".0f"),
        ("least fairlead kN", lambda r: r["least_fairlead_N"] / 1e3, ".0f"),
        ("err vs ref", lambda r: None if r["rel_err_vs_reference"] is None
         else f"{100 * r['rel_err_vs_reference']:.3f}%", ""),
    ], title="self-convergence of the fairlead |F| (differences between N and 2N over the std; "
             "least tensions of the finest run, t ≥ 0.5 s)")
    write_json(args.json, dict(runs=rows, case=args.case, element=args.element,
                               duration_s=args.duration, rtol=args.rtol, atol=args.atol))
    return 0


if __name__ == "__main__":
    sys.exit(main())
