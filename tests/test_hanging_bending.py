"""A heavy line with bending stiffness hung between two fixed points, against MoorDyn.

``tests/data/hanging_ei.dat``: a 20 m line of 902 N/m wet weight, EA = 1e8 N,
EI = 3.4e4 N·m², pinned at two points 17 m apart at the same depth (span
0.85·L). Its bending length √(EI/H) ≈ 2.2 m is 11 % of L: EI lifts the sag by
2.2 cm (0.47 %) and takes 12 % off the horizontal end force (7634 N without EI,
6747 N with it: the ends carry a bending shear). Well posed: the ends pull the
line apart, nothing is compressed, the hanging shape is the one equilibrium
the statics reaches from the catenary (for the Hermite element through its EI
continuation, :data:`moorjax.statics.hermite.EI_STAGES`).

MoorDyn's settled state: its IC solver (the stationary scheme, 400 s, error
2.3e-6 m/s² per state), then 3 s of dynamics that move no node by more than
3e-7 m. Run in a child process (MoorDyn's library in the test process was
followed by segfaults in later XLA compilations; see ``test_deck_bodies``).
"""

from __future__ import annotations

import json
import subprocess
import sys
import warnings
from pathlib import Path

import equinox as eqx
import numpy as np
import pytest

import moorjax as mj
from moorjax.element import HermiteElement
from moorjax.io import build_scene, read_deck
from moorjax.statics.fem import solve_line_statics

DECK = Path(__file__).parent / "data" / "hanging_ei.dat"

_MOORDYN = """
import contextlib, io, json, moordyn
with contextlib.redirect_stdout(io.StringIO()):
    s = moordyn.Create({deck!r})
    moordyn.Init(s, [], [])
    ln = moordyn.GetLine(s, 1)
    n = moordyn.GetLineN(ln)
    r0 = [list(moordyn.GetLineNodePos(ln, k)) for k in range(n + 1)]
    for i in range(3):
        moordyn.Step(s, [], [], float(i), 1.0)
    out = dict(r0=r0, r=[list(moordyn.GetLineNodePos(ln, k)) for k in range(n + 1)],
               force_a=list(moordyn.GetLineNodeForce(ln, 0)), force_b=list(moordyn.GetLineNodeForce(ln, n)))
    moordyn.Close(s)
print(json.dumps(out))
"""


def moordyn_settled():
    pytest.importorskip("moordyn")
    run = subprocess.run([sys.executable, "-c", _MOORDYN.format(deck=str(DECK))], capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    out = json.loads(run.stdout.strip().splitlines()[-1])
    return {k: np.asarray(v) for k, v in out.items()}


def deck_line(n, element=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = build_scene(read_deck(DECK), segments=n)
    (line,) = scene.lines
    if element is not None:
        line = mj.Line(line.line_type, line.length, n, line.end_a, line.end_b, element=element)
    return line, scene.env


def statics(n, element=None, ei=True):
    line, env = deck_line(n, element)
    if not ei:
        line = eqx.tree_at(lambda ln: ln.line_type.ei, line, None, is_leaf=lambda x: x is None)
    st = solve_line_statics(line, env)
    assert bool(st.converged)
    return -20.0 - float(st.positions[n // 2, 2]), np.asarray(st.force_b)


@pytest.mark.slow
def test_hanging_line_with_ei_matches_moordyn():
    """Measured (sag [m], horizontal end force [N]): MoorDyn 40 segments
    4.659754, 6747.30; moorjax linear 40 segments 4.659679, 6746.26 (the same
    discretisation up to MoorDyn's stretched-length curvature, 4·sin(θ/2)/(l₁+l₂)
    against our 2·tan(θ/2)/l: 1.6e-5 and 1.6e-4 apart); Hermite 8 elements
    4.658635, 6748.41 (16: 4.658440, 6748.40, the continuum, which MoorDyn at
    40 segments is 2.8e-4 and 1.6e-4 from). Without EI: 4.637751, 7633.97, so
    EI's effect is 30× (sag) and 700× (force) the elements' disagreement. ~170 s
    (MoorDyn's 400 s IC solve ~30 s, three compilations)."""
    md = moordyn_settled()
    assert np.abs(md["r"] - md["r0"]).max() < 1e-6  # settled
    md_sag, md_fb = -20.0 - md["r"][20, 2], md["force_b"]
    sag, fb = statics(40)
    assert abs(sag / md_sag - 1) < 5e-5, sag / md_sag - 1
    assert abs(fb[0] / md_fb[0] - 1) < 5e-4 and abs(fb[2] / md_fb[2] - 1) < 1e-5, (fb, md_fb)
    sag_h, fb_h = statics(8, HermiteElement())
    assert abs(sag_h / md_sag - 1) < 5e-4 and abs(fb_h[0] / md_fb[0] - 1) < 5e-4, (sag_h, fb_h)
    sag0, fb0 = statics(40, ei=False)
    assert sag - sag0 > 30 * abs(sag - md_sag) and abs(fb0[0] - fb[0]) > 0.1 * abs(fb[0])
