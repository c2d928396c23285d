"""Compile time as a user sees it: ``moorjax simulate --stats`` in fresh processes.

For each mode (the integration compiled while the statics run, the default;
and one after the other, ``MOORJAX_COMPILE_AHEAD=0``) two processes run the
same command on an empty cache folder: the first compiles everything, the
second loads the stored programs (issue 17's "first call" and "same structure
again in a new process"). Reported per process: ``compile_s`` and ``run_s``
from ``--stats`` and the wall time of the whole command.

    python benchmarks/compile_time.py [--deck example:oc3_catenary] [--duration 10]
                                      [--modes ahead serial] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time


def run_once(deck, duration, cache, ahead, extra=()):
    env = dict(os.environ, MOORJAX_CACHE_DIR=cache, MOORJAX_COMPILATION_CACHE="1",
               MOORJAX_COMPILE_AHEAD="1" if ahead else "0")
    with tempfile.TemporaryDirectory() as out:
        cmd = [sys.executable, "-m", "moorjax", "simulate", deck, "--duration", str(duration),
               "--stats", "--quiet", "--out", os.path.join(out, "run.nc"), *extra]
        t0 = time.perf_counter()
        p = subprocess.run(cmd, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(p.stderr[-2000:])
    stats = json.loads([ln for ln in p.stderr.splitlines() if ln.startswith("{")][-1])
    return dict(wall_s=wall, compile_s=stats["compile_s"], run_s=stats["run_s"],
                solver=stats.get("solver"), steps=stats.get("steps"))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--deck", default="example:oc3_catenary")
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--modes", nargs="+", default=["ahead", "serial"], choices=["ahead", "serial"])
    ap.add_argument("--json", help="write the figures here")
    a = ap.parse_args(argv)
    rows = []
    for mode in a.modes:
        with tempfile.TemporaryDirectory() as cache:
            for k in ("first", "second"):
                r = run_once(a.deck, a.duration, cache, mode == "ahead")
                r.update(mode=mode, process=k, deck=a.deck)
                rows.append(r)
                print(f"{mode:6s} {k:6s} process: compile_s {r['compile_s']:6.2f}  run_s "
                      f"{r['run_s']:5.2f}  whole command {r['wall_s']:6.2f} s", flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(dict(duration=a.duration, cpus=os.cpu_count(), rows=rows), f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
