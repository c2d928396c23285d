"""Make MoorDyn 2.7.2 reference data for moorjax's deck tests (run by hand; the
tests read the JSON it writes and never import MoorDyn).

    python tests/data/make_moordyn_reference.py DECK T_SETTLE T_TRANSIENT OUT.json [--free P1,P2]
        [--kinematics FILE.py:NAME [--dt-kinematics DT]]

For DECK (all points fixed, or free points ``--free``): MoorDyn's initial
condition (its own IC solver, which runs *without* currents: MoorDyn reads the
current files "for runtime" after the IC), the history of every line's end
segment tensions and of the free points' positions from that state every 0.05 s
for T_TRANSIENT s, and the state after T_SETTLE s of dynamics (drag settles
the line under the current), with the node positions of every line. Output
files MoorDyn writes (``*.out``, ``*.log``) are removed. Coupled points are held
at their deck positions.

``--kinematics FILE.py:NAME`` (a ``WaveKin = 1`` deck): before every step of
``--dt-kinematics`` s (default 0.01) the function ``NAME(r, t) -> (u, a)`` of
FILE.py is evaluated at MoorDyn's kinematics points
(``ExternalWaveKinGetCoordinates``) and set with ``ExternalWaveKinSet``, as
MoorDyn's ``tests/wavekin.cpp`` does; MoorDyn holds them until the next set.
"""

import importlib.util
import json
import sys
from pathlib import Path

import moordyn
import numpy as np


def _snapshot(s, n_lines, free):
    out = {"lines": [], "points": {}}
    for i in range(1, n_lines + 1):
        ln = moordyn.GetLine(s, i)
        n = moordyn.GetLineN(ln)
        out["lines"].append({
            "positions": [list(moordyn.GetLineNodePos(ln, k)) for k in range(n + 1)],
            "tension_a": float(np.linalg.norm(moordyn.GetLineNodeTen(ln, 0))),
            "tension_b": float(np.linalg.norm(moordyn.GetLineNodeTen(ln, n))),
            "mid": list(moordyn.GetLineNodePos(ln, n // 2)),
        })
    for p in free:
        out["points"][str(p)] = list(moordyn.GetPointPos(moordyn.GetPoint(s, p)))
    return out


def _option(argv, name, default=None):
    return argv[argv.index(name) + 1] if name in argv else default


def _kinematics(spec):
    path, _, name = spec.rpartition(":")
    spec_ = importlib.util.spec_from_file_location("_kinematics", path)
    module = importlib.util.module_from_spec(spec_)
    spec_.loader.exec_module(module)
    return getattr(module, name)


def main(argv):
    deck, t_settle, t_trans, dest = argv[0], float(argv[1]), float(argv[2]), argv[3]
    free_arg = _option(argv, "--free")
    free = [int(x) for x in free_arg.split(",")] if free_arg else []
    kin_spec = _option(argv, "--kinematics")
    kin = _kinematics(kin_spec) if kin_spec else None
    dt_kin = float(_option(argv, "--dt-kinematics", 0.01))
    s = moordyn.Create(deck)
    coupled = [i for i in range(1, moordyn.GetNumberPoints(s) + 1)
               if moordyn.GetPointType(moordyn.GetPoint(s, i)) == -1]
    x = [c for i in coupled for c in moordyn.GetPointPos(moordyn.GetPoint(s, i))]
    v = [0.0] * len(x)
    moordyn.Init(s, x, v)
    if kin is not None:
        moordyn.ExternalWaveKinInit(s)
    n_lines = moordyn.GetNumberLines(s)
    ref = {"deck": Path(deck).name, "moordyn": "2.7.2", "initial": _snapshot(s, n_lines, free)}
    if kin is not None:
        ref["kinematics"] = {"function": Path(kin_spec).name, "dt": dt_kin}
    hist = {"t": [], "tension_a": [], "tension_b": [], "mid": [], "points": {str(p): [] for p in free}}
    t, dt_out = 0.0, 0.05
    while t < t_settle - 1e-9:
        if kin is None:
            moordyn.Step(s, x, v, t, dt_out)
        else:
            n_sub = max(1, round(dt_out / dt_kin))
            for k in range(n_sub):
                tk = t + k * dt_out / n_sub
                r = np.asarray(moordyn.ExternalWaveKinGetCoordinates(s), dtype=float).reshape(-1, 3)
                u, a = kin(r, tk)
                u = np.broadcast_to(np.asarray(u, dtype=float), r.shape)
                a = np.broadcast_to(np.asarray(a, dtype=float), r.shape)
                moordyn.ExternalWaveKinSet(s, u.tolist(), a.tolist(), tk)
                moordyn.Step(s, x, v, tk, dt_out / n_sub)
        t += dt_out
        if t <= t_trans + 1e-9:
            snap = _snapshot(s, n_lines, free)
            hist["t"].append(round(t, 10))
            hist["tension_a"].append([ln["tension_a"] for ln in snap["lines"]])
            hist["tension_b"].append([ln["tension_b"] for ln in snap["lines"]])
            hist["mid"].append([ln["mid"] for ln in snap["lines"]])
            for p in free:
                hist["points"][str(p)].append(snap["points"][str(p)])
    ref["history"] = hist
    ref["settled"] = dict(_snapshot(s, n_lines, free), t=t)
    moordyn.Close(s)
    Path(dest).write_text(json.dumps(ref))
    stem = Path(deck).with_suffix("")
    for ext in (".out", ".log"):
        for f in Path(deck).parent.glob(stem.name + "*" + ext):
            f.unlink()


if __name__ == "__main__":
    main(sys.argv[1:])
