"""Shared parts of the benchmark scripts: the reference cases, a timed run that
always ends in an outcome, plain-text tables and JSON output.

Timing protocol of every moorjax run (``timed_run``):

1. the static equilibrium at t = 0 (``simulate``'s default initial state) is
   solved once and timed as ``statics_s``, then passed as ``init``;
2. the same ``simulate`` call is made twice (after ``jax.block_until_ready``):
   ``compile_s`` = first − second, ``run_s`` = second. Long runs may instead
   compile on two cheap calls with the fairlead held still (same structure).

A run either completes (outcome ``ok``), or stops with moorjax's
``RuntimeError`` naming the simulated time and cause (outcome ``error: ...``,
the message is kept). A completed run whose outputs are not finite is flagged
``SILENT NaN``, one with absurd tensions ``IMPLAUSIBLE``; neither must happen.

The machine the figures in benchmarks/README.md come from has 2 cores and is
shared with other work: wall times are noisy (±30 % is common); compare ratios
measured in one run of a script rather than numbers from different runs.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import moorjax as mj
from moorjax.dynamics import simulate
from moorjax.examples import example_path
from moorjax.io import build_scene, read_deck
from moorjax.statics import solve_line_statics

#: tensions above this [N] are not plausible for any mooring line
IMPLAUSIBLE_N = 1e9
NOISE_NOTE = ("timings: 2-core machine shared with other work, wall times are noisy "
              "(±30 %); compare within one run")


@dataclass(frozen=True)
class Case:
    """A reference case: bundled deck and the fairlead's x-sine (MoorDyn runs too)."""

    deck: str
    centre: tuple
    amplitude: float  # [m]
    period: float  # [s]

    def path(self, amplitude=None):
        """Fairlead position r(t) [m] (numpy, for MoorDyn)."""
        amp = self.amplitude if amplitude is None else amplitude
        w = 2 * np.pi / self.period
        c = np.asarray(self.centre, float)
        return lambda t: c + np.array([amp * np.sin(w * t), 0.0, 0.0])


CASES = {
    "A": Case("oc3_catenary", (-5.2, 0.0, -70.0), 5.0, 10.0),
    "B": Case("taut_polyester", (0.0, 0.0, -5.0), 2.0, 8.0),
}


def case_scene(case: str, n_segments: int, amplitude: float | None = None, element=None):
    """Scene of reference case ``case`` with N segments (elements), fairlead on its
    sine path; ``element``: ``None`` (linear), ``"hermite"`` or an element object."""
    c = CASES[case]
    if element == "hermite":
        from moorjax.element import HermiteElement

        element = HermiteElement()
    elif element == "linear":
        element = None
    scene = build_scene(read_deck(example_path(c.deck)), segments=n_segments, element=element)
    amp = c.amplitude if amplitude is None else amplitude
    path = mj.SinePath(c.centre, [amp, 0.0, 0.0], c.period)
    return eqx.tree_at(lambda s: s.lines[0].end_b, scene, path)


def with_ea(scene, ea: float):
    """The scene with the (linear) axial stiffness of line 0 set to ``ea`` [N]."""
    return eqx.tree_at(lambda s: s.lines[0].line_type.axial.ea, scene, jnp.asarray(ea, dtype=float))


def reference_dir() -> str:
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    return os.environ.get("MOORJAX_REFERENCE_DIR", os.path.join(here, "..", "shared", "reference"))


def reference_csv(case: str):
    """Path of the MoorDyn N=160 reference history of a case, or None if absent."""
    p = os.path.join(reference_dir(), f"ref_{case}.csv")
    return p if os.path.exists(p) else None


def short_error(msg: str, width: int = 70) -> str:
    """moorjax's failure message without the solver name and the diffrax code."""
    s = msg.split(" [diffrax:")[0]
    if " failed " in s:
        s = s.split(" failed ", 1)[1]
    s = s.replace("Newton did not converge even at the smallest step", "Newton failed")
    s = s.replace("the state became non-finite or the step size collapsed", "non-finite/step collapse")
    s = s.split(" (")[0]
    return s if len(s) <= width else s[: width - 1] + "…"


def _finite(tree) -> bool:
    return all(bool(np.all(np.isfinite(np.asarray(x)))) for x in jax.tree_util.tree_leaves(tree))


def static_init(scene, t0: float = 0.0):
    """Static equilibrium of every line at t0 (the default ``init`` of ``simulate``)."""
    init = tuple(solve_line_statics(line, scene.env, t0).state() for line in scene.lines)
    return jax.block_until_ready(init)


def _call(scene, duration, kwargs):
    """One timed simulate call: (result or None, error message, wall s, CPU s)."""
    t_a, c_a = time.perf_counter(), time.process_time()
    try:
        res = simulate(scene, duration, **kwargs)
        jax.block_until_ready(res.tension_b)
        err = ""
    except RuntimeError as exc:
        res, err = None, str(exc)
    return res, err, time.perf_counter() - t_a, time.process_time() - c_a


def held_still(scene):
    """The scene with line 0's fairlead sine amplitude set to zero (same structure)."""
    return eqx.tree_at(lambda s: s.lines[0].end_b.amplitude, scene,
                       jnp.zeros_like(scene.lines[0].end_b.amplitude))


def timed_run(scene, duration: float, *, warm: str = "repeat", init=None, repeats: int = 1,
              **kwargs) -> dict:
    """Simulate ``duration`` s with statics, compile and run timed apart; never raises.

    The static equilibrium (``init``) is solved first and timed as ``statics_s``
    (moorjax currently recompiles it on every call, so it is kept out of the run
    time). Then, with ``warm="repeat"``, the same ``simulate`` call is made twice:
    ``compile_s`` = first − second, ``run_s`` = second. With ``warm="still"`` (for
    long adaptive runs) the two timing calls hold the fairlead still (same
    structure, cheap) and the real run is made once. ``repeats`` > 1 (with
    ``warm="repeat"``): ``run_s`` and ``cpu_s`` are the least of that many
    calls after the first (the first minus the least is ``compile_s``).

    Returns a dict: ``outcome`` ('ok', 'error: …', 'SILENT NaN', 'IMPLAUSIBLE'),
    ``message`` (full error text), ``statics_s``, ``compile_s``, ``run_s``,
    ``cpu_s`` (process CPU time of the run), ``ms_per_sim_s``, ``steps``,
    ``rejected``, ``max_tension_N`` (ends A and B), ``silent_nan`` (bool) and
    ``result`` (the :class:`SimulationResult`, not JSON-able). ``kwargs`` go to
    :func:`moorjax.dynamics.simulate`.
    """
    out = dict(outcome="ok", message="", statics_s=float("nan"), compile_s=float("nan"),
               run_s=float("nan"), cpu_s=float("nan"), ms_per_sim_s=float("nan"), steps=None,
               rejected=None, max_tension_N=float("nan"), silent_nan=False, result=None)
    if init is None:
        t_a = time.perf_counter()
        try:
            init = static_init(scene, kwargs.get("t0", 0.0))
        except Exception as exc:  # noqa: BLE001 - a failed static solve is an outcome too
            out.update(outcome="error: statics: " + str(exc).splitlines()[-1][:60],
                       message=str(exc))
            return out
        out["statics_s"] = time.perf_counter() - t_a
    kwargs = dict(kwargs, init=init)
    if warm == "still":
        still = held_still(scene)
        _, _, first, _ = _call(still, duration, kwargs)
        _, _, second, _ = _call(still, duration, kwargs)
        res, err, run, cpu = _call(scene, duration, kwargs)
    else:
        _, _, first, _ = _call(scene, duration, kwargs)
        res, err, second, cpu = _call(scene, duration, kwargs)
        for _ in range(max(1, int(repeats)) - 1):
            if res is None:
                break
            res, err, again, cpu_again = _call(scene, duration, kwargs)
            second, cpu = min(second, again), min(cpu, cpu_again)
        run = second
    out.update(compile_s=max(first - second, 0.0), run_s=run, cpu_s=cpu)
    if res is None:
        out.update(outcome="error: " + short_error(err), message=err)
        return out
    out.update(ms_per_sim_s=1e3 * run / duration, result=res, steps=int(res.num_steps),
               rejected=int(res.num_rejected_steps))
    tens = np.concatenate([np.ravel(res.tension_a), np.ravel(res.tension_b)])
    if not _finite((res.tension_a, res.tension_b, res.force_a, res.force_b, res.final_state)):
        out.update(outcome="SILENT NaN", silent_nan=True)
    else:
        out["max_tension_N"] = float(np.max(tens))
        if out["max_tension_N"] > IMPLAUSIBLE_N or np.min(tens) < 0:
            out["outcome"] = "IMPLAUSIBLE"
    return out


def rel_error(run: dict, case: str, column: int = 0):
    """RMS(end-B tension − reference |F|) / std(reference), or None."""
    from benchmarks.moordyn_runner import rel_rms_error

    ref = reference_csv(case)
    res = run.get("result")
    if ref is None or res is None or run["outcome"] != "ok":
        return None
    return rel_rms_error(np.asarray(res.ts), np.asarray(res.tension_b[:, column]), ref)


def fmt(value, spec: str = ".3g", none: str = "-") -> str:
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return none
    return format(value, spec)


def print_table(rows: list[dict], columns: list[tuple], title: str | None = None) -> None:
    """Plain-text table; ``columns`` are (header, key or callable(row), format spec)."""
    cells = [[h for h, _, _ in columns]]
    for r in rows:
        line = []
        for _, key, spec in columns:
            v = key(r) if callable(key) else r.get(key)
            line.append(v if isinstance(v, str) else fmt(v, spec))
        cells.append(line)
    widths = [max(len(c[i]) for c in cells) for i in range(len(columns))]
    if title:
        print(f"\n{title}")
    for j, line in enumerate(cells):
        print("  ".join(c.ljust(w) if i == 0 or not _numeric(c) else c.rjust(w)
                        for i, (c, w) in enumerate(zip(line, widths))).rstrip())
        if j == 0:
            print("  ".join("-" * w for w in widths))


def _numeric(s: str) -> bool:
    try:
        float(s.rstrip("%x"))
        return True
    except ValueError:
        return False


def jsonable(rows: list[dict]) -> list[dict]:
    """Rows without the non-JSON entries (simulation results)."""
    return [{k: v for k, v in r.items() if k != "result"} for r in rows]


def write_json(path: str | None, payload: dict) -> None:
    if not path:
        return
    payload = dict(payload, machine=dict(cpus=os.cpu_count(), note=NOISE_NOTE,
                                         date=time.strftime("%Y-%m-%d %H:%M")))
    with open(path, "w") as f:
        json.dump(payload, f, indent=2, default=_default)
    print(f"\nwrote {path}")


def _default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    return str(o)


def base_parser(doc: str):
    """argparse parser with the options every script has (--quick, --json)."""
    import argparse

    p = argparse.ArgumentParser(description=doc.split("\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=NOISE_NOTE)
    p.add_argument("--quick", action="store_true", help="small run (about 3 minutes)")
    p.add_argument("--json", metavar="PATH", help="write all figures to this JSON file")
    p.add_argument("--reference", metavar="DIR", action=_ReferenceDir,
                   help="folder of the reference data (ref_A.csv, …); default "
                        "$MOORJAX_REFERENCE_DIR, else ../shared/reference beside the repository")
    return p


def _reference_action():
    import argparse

    class ReferenceDir(argparse.Action):
        """Sets the reference folder that :func:`reference_dir` returns."""

        def __call__(self, parser, namespace, values, option_string=None):
            if not os.path.isdir(values):
                parser.error(f"--reference {values}: no such folder")
            os.environ["MOORJAX_REFERENCE_DIR"] = os.path.abspath(values)
            setattr(namespace, self.dest, values)

    return ReferenceDir


_ReferenceDir = _reference_action()
