"""Cost of a gradient of a tension-history loss, relative to one forward simulation.

For the reference catenary (case A: ``oc3_catenary``, fairlead x = −5.2 +
5·sin(2πt/10) m) with N = 20 and 80 segments, 60 s simulated with fixed steps
(kvaerno3, dt = 0.01 s, Newton tolerances 1e-6, outputs every 0.05 s):

- ``forward``: static equilibrium + integration + the misfit to a target history
  (one compiled function);
- ``gradient``: the same misfit *and* its gradient with respect to every array of
  the scene (reverse mode: ``moorjax.identify.misfit_and_gradient``), with the
  adjoint moorjax uses (every step's state checkpointed, no recomputation) and
  with diffrax's default binomial schedule (O(√steps) checkpoints, which
  recomputes steps);
- ``jvp``: one forward-mode directional derivative (``diffrax.ForwardMode``, as
  used for the Gauss–Newton covariance);
- ``dense IFT``: the gradient with diffrax's default implicit-function solve in
  every implicit stage (a dense LU; moorjax.identify replaces it by the Newton's
  block-tridiagonal solve, see ``moorjax/identify/response.py``), for N ≤
  ``--dense-up-to``.

Each function is compiled first (``compile_s``), then run ``--repeats`` times
(min wall time reported, ``run_s``). Memory: the XLA buffers of the compiled
function (``temp``: scratch, ``total``: arguments + outputs + scratch), from
``compiled.memory_analysis()``; and the process's peak resident set size after
each N (``peak_rss_MB``, cumulative over the run: it includes the larger of all
functions compiled so far).

    PYTHONPATH=. python benchmarks/gradients.py [--quick] [--segments 20 80] [--duration 60]
        [--repeats 3] [--no-binomial] [--dense-up-to 20] [--json out.json]

The real-data check of the identification (case A's Cd_normal fitted to
MoorDyn's history) is ``benchmarks/fit_case_a.py``.

Target: gradient/forward ≤ 5. Timings come from a 2-core machine shared with
other work (±30 %); compare the ratios within one run.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import time

import diffrax
import equinox as eqx
import jax
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import moorjax as mj  # noqa: E402
from moorjax.examples import example_path  # noqa: E402
from moorjax.identify import experiment, simulation  # noqa: E402
from moorjax.dynamics import adjoint as adjoint_mod  # noqa: E402
from moorjax.identify import response as response_mod  # noqa: E402
from moorjax.identify.response import structured_implicit_gradients  # noqa: E402
from moorjax.identify.objective import _misfit, model_tensions, tangent  # noqa: E402
from moorjax.io import build_scene, read_deck  # noqa: E402


def case_a(n):
    scene = build_scene(read_deck(example_path("oc3_catenary")), segments=n)
    path = mj.SinePath([-5.2, 0.0, -70.0], [5.0, 0.0, 0.0], 10.0)
    return eqx.tree_at(lambda s: s.lines[0].end_b, scene, path)


def _forward(exp, sim):
    return _misfit(exp.scene, exp.data, exp.sqrt_weight, exp.channels, sim)[0]


def _gradient(exp, sim):
    diff, static = eqx.partition(exp.scene, eqx.is_inexact_array)
    return jax.value_and_grad(
        lambda d: _misfit(eqx.combine(d, static), exp.data, exp.sqrt_weight, exp.channels, sim)[0]
    )(diff)


def _jvp(exp, sim, tang):
    diff, static = eqx.partition(exp.scene, eqx.is_inexact_array)
    f = lambda d: model_tensions(eqx.combine(d, static), exp, sim)[0]  # noqa: E731
    return jax.jvp(f, (diff,), (tang,))


class Variant:
    """A compiled function, its compile time, memory and run times."""

    def __init__(self, fn, args, structured=True):
        dynamic, static = eqx.partition(args, eqx.is_array)
        self.dynamic = dynamic

        def call(d):
            return fn(*eqx.combine(d, static))

        t0 = time.perf_counter()
        # structured: traced as every compiled function of moorjax.identify is;
        # False: diffrax's default dense LU in each implicit stage's derivative
        with structured_implicit_gradients(structured):
            self.compiled = jax.jit(call).lower(dynamic).compile()
        self.compile_s = time.perf_counter() - t0
        self.runs, self.out = [], None
        self.mem = {}
        try:
            ma = self.compiled.memory_analysis()
            self.mem = dict(temp_MB=ma.temp_size_in_bytes / 2**20,
                            total_MB=(ma.temp_size_in_bytes + ma.argument_size_in_bytes
                                      + ma.output_size_in_bytes) / 2**20)
        except Exception:  # noqa: BLE001 - not every backend reports it
            pass

    def run(self):
        t0 = time.perf_counter()
        self.out = jax.block_until_ready(self.compiled(self.dynamic))
        self.runs.append(time.perf_counter() - t0)

    @property
    def best(self):
        return min(self.runs)


def run_case(n, duration, dt, repeats, with_binomial, with_dense):
    scene = case_a(n)
    ts = np.arange(1, int(round(duration / 0.05)) + 1) * 0.05
    sim = simulation(ts, dt=dt)
    truth = np.asarray(response_mod.tension_histories(scene, sim).tension_b)
    # target: the same line with 20 % more normal drag, so the misfit is not zero
    target_scene = eqx.tree_at(lambda s: s.lines[0].line_type.drag.cd_normal, scene,
                               scene.lines[0].line_type.drag.cd_normal * 1.2)
    data = np.asarray(response_mod.tension_histories(target_scene, sim).tension_b)
    exp = experiment(scene, ts, data, name=f"A N={n}")
    row = dict(N=n, duration_s=duration, dt_s=dt, steps=int(round(duration / dt)),
               max_tension_N=float(np.max(truth)))
    variants = {"forward": Variant(_forward, (exp, sim)),
                "gradient": Variant(_gradient, (exp, sim))}
    if with_binomial:
        old = adjoint_mod.CHECKPOINT_BYTES
        adjoint_mod.CHECKPOINT_BYTES = 0  # force diffrax's default O(√steps) schedule
        try:
            variants["binomial"] = Variant(_gradient, (exp, sim))
        finally:
            adjoint_mod.CHECKPOINT_BYTES = old
    variants["jvp"] = Variant(_jvp, (exp, sim.with_adjoint("forward"), tangent(scene, "Cd_normal")))
    if with_dense:
        variants["dense_ift"] = Variant(_gradient, (exp, sim), structured=False)
    # interleaved repeats: load changes on a shared machine hit every variant alike
    for k in range(repeats):
        for name, v in variants.items():
            if name != "dense_ift" or k == 0:
                v.run()
    fwd = variants["forward"].best
    row.update(forward_s=fwd, loss=float(variants["forward"].out))
    v, g = variants["gradient"].out
    row.update(dloss_dCd=float(g.lines[0].line_type.drag.cd_normal),
               gradient_finite=all(bool(np.all(np.isfinite(x))) for x in jax.tree_util.tree_leaves(g)))
    for name, var in variants.items():
        row[f"{name}_compile_s"] = var.compile_s
        row[f"{name}_s"] = var.best
        row[f"{name}_mem"] = var.mem
        row[f"{name}_ratio"] = var.best / fwd
    row["peak_rss_MB"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return row


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--segments", type=int, nargs="+", default=[20, 80])
    p.add_argument("--duration", type=float, default=60.0, help="simulated time [s]")
    p.add_argument("--dt", type=float, default=0.01, help="fixed step [s]")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--quick", action="store_true", help="N = 20 only, 20 s")
    p.add_argument("--no-binomial", action="store_true", help="skip the binomial-checkpoint variant")
    p.add_argument("--dense-up-to", type=int, default=20,
                   help="also time diffrax's default dense implicit-function solve for N <= this "
                        "(200x a forward run at N = 80)")
    p.add_argument("--json", metavar="PATH", help="write the figures to this JSON file")
    a = p.parse_args(argv)
    if a.quick:
        a.segments, a.duration = [20], 20.0
    rows = []
    for n in a.segments:
        row = run_case(n, a.duration, a.dt, a.repeats, not a.no_binomial, n <= a.dense_up_to)
        rows.append(row)
        mem = lambda k: f"{row[k + '_mem'].get('temp_MB', float('nan')):.1f} MB"  # noqa: E731
        parts = [f"forward {row['forward_s']:.2f} s [compile {row['forward_compile_s']:.0f} s, "
                 f"temp {mem('forward')}]"]
        labels = dict(gradient="gradient", binomial="gradient, binomial checkpoints",
                      jvp="jvp (1 direction)", dense_ift="gradient, dense IFT (diffrax default)")
        for k, label in labels.items():
            if f"{k}_s" in row:
                parts.append(f"{label} {row[k + '_s']:.2f} s = {row[k + '_ratio']:.2f}x "
                             f"[temp {mem(k)}]")
        print(f"N={n:3d} {a.duration:g} s ({row['steps']} steps): " + " | ".join(parts), flush=True)
        print("      compile [s]: " + ", ".join(f"{k} {row[k + '_compile_s']:.1f}" for k in
                                             ("forward", *labels) if f"{k}_s" in row)
              + "; total XLA memory [MB]: " + ", ".join(
                  f"{k} {row[k + '_mem'].get('total_MB', float('nan')):.1f}" for k in
                  ("forward", *labels) if f"{k}_s" in row)
              + f"; peak RSS so far {row['peak_rss_MB']:.0f} MB", flush=True)
    print("target: gradient <= 5x forward; timings: 2-core machine shared with other work (±30 %)")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(dict(rows=rows, cpus=os.cpu_count(), jax=jax.__version__,
                           diffrax=diffrax.__version__, date=time.strftime("%Y-%m-%d %H:%M")),
                      f, indent=2, default=str)
        print(f"wrote {a.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
