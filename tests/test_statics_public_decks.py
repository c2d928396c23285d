"""Public MoorDyn/MoorPy decks whose statics once failed, against MoorPy's catenary.

Each line is solved between its deck end points (``moorjax statics DECK``) and
compared with MoorPy's analytic elastic catenary on the same ends. Sources of
the decks: ``tests/data/README.md``.
"""

from __future__ import annotations

from pathlib import Path

import equinox as eqx
import numpy as np
import pytest
from moorpy.Catenary import catenary as moorpy_catenary

from moorjax.io import build_scene, read_deck
from moorjax.statics.fem import solve_line_statics

pytestmark = pytest.mark.slow  # long physics/compile checks: CI runs them, `-m "not slow"` skips

PUBLIC = Path(__file__).parent / "data" / "public"
SOLVE = eqx.filter_jit(lambda line, env: solve_line_statics(line, env, throw=False))


def lines_of(name, segments, length=None):
    scene = build_scene(read_deck(PUBLIC / name), segments=segments)
    # MoorPy's catenary is a cable: compare the decks' lines without bending stiffness
    lines = [eqx.tree_at(lambda ln: ln.line_type.ei, ln, None, is_leaf=lambda x: x is None)
             for ln in scene.lines]
    if length is not None:
        lines = [eqx.tree_at(lambda ln: ln.length, ln, np.float64(length)) for ln in lines]
    return lines, scene.env


def moorpy(line, env, dry=False):
    """(T_A, T_B) of MoorPy's catenary between the line's ends; ``dry``: a line in
    air (MoorDyn's and moorjax's lines are buoyant only under the surface, MoorPy's
    everywhere), weighing m·g."""
    ra, rb = np.asarray(line.end_a.position(0.0)), np.asarray(line.end_b.position(0.0))
    lo, hi = (ra, rb) if ra[2] <= rb[2] else (rb, ra)
    depth = float(env.depth)
    cb = 0.0 if abs(lo[2] + depth) < 1e-6 else -(lo[2] + depth)
    lt = line.line_type
    w = float(lt.mass_per_length * env.g if dry else lt.wet_weight(env.rho, env.g))
    fah, fav, fbh, fbv, _ = moorpy_catenary(
        float(np.hypot(*(hi - lo)[:2])), float(hi[2] - lo[2]), float(line.length),
        float(line.line_type.axial.nominal_ea()), w, CB=cb, Tol=1e-10, MaxIter=500)
    t_lo, t_hi = float(np.hypot(fah, fav)), float(np.hypot(fbh, fbv))
    return (t_lo, t_hi) if ra[2] <= rb[2] else (t_hi, t_lo)


def errors(name, segments, length=None):
    """Per line: (converged, iterations, rel. error of T_A, of T_B, T_A/T_B oracle)."""
    lines, env = lines_of(name, segments, length)
    out = []
    for line in lines:
        st = SOLVE(line, env)
        z = np.asarray(st.positions)[:, 2]
        assert z.min() >= 0.0 or z.max() <= 0.0, "a surface-piercing line has no MoorPy oracle"
        ta, tb = moorpy(line, env, dry=bool(z.min() >= 0.0 and z.max() > 0.0))
        out.append((bool(st.converged), int(st.iterations), float(st.tension_a) / ta - 1,
                    float(st.tension_b) / tb - 1, ta, tb))
    return out


def test_mhk_rm1_grounded_chains():
    """Six short heavy chains with long seabed contact (H/w ≈ 3 segments at 80):
    line 2 once stopped at a 1.5e6 N imbalance. All converge at 30 (the deck's),
    80 and 320 segments; the touchdown discretisation error falls below 5e-4 of
    the end tensions at 320."""
    for conv, it, *_ in errors("MHK_RM1_Floating_MoorDyn.dat", 30):
        assert conv and it < 200
    for conv, it, ea, eb, ta, tb in errors("MHK_RM1_Floating_MoorDyn.dat", 80):
        assert conv and it < 200
        assert abs(eb) < 2e-3 and abs(ea) * ta < 2e-3 * tb
    for conv, _, ea, eb, _, _ in errors("MHK_RM1_Floating_MoorDyn.dat", 320):
        assert conv and abs(ea) < 5e-4 and abs(eb) < 5e-4, (ea, eb)


def test_moorpy_case9_line_far_above_the_seabed():
    """Line 5 joins two body points 80 m above the bed: a free catenary (the start
    no longer assumes a touchdown)."""
    res = errors("moorpy_case9.dat", 80)
    for conv, it, ea, eb, _, _ in res:
        assert conv
        assert abs(ea) < 5e-4 and abs(eb) < 5e-4
    assert res[4][1] <= 10  # Newton-like from the free catenary


def test_moorpy_case5_shortened_to_690_m():
    """case5's chain at 690 m (once a 4.3e7 N imbalance after 2 iterations): 388 m
    grounded, H/w ≈ 0.4 segment at 80 segments."""
    for n, tol in ((40, 5e-3), (80, 1e-2), (320, 5e-4)):
        ((conv, _, ea, eb, ta, tb),) = errors("moorpy_case5.dat", n, length=690.0)
        assert conv
        assert abs(eb) < tol and abs(ea) * ta < tol * tb, (n, ea, eb)


@pytest.mark.parametrize("extra", [0.0, 0.01, -0.01])
def test_beam_simply_supported_length_equal_to_span(extra):
    """MoorDyn's BeamSimplySupported deck: unstretched length = span (once NaN),
    and 1 cm longer or shorter; its EI is dropped for the comparison with MoorPy's
    cable (the beam with EI: ``tests/test_bending.py``)."""
    (res,) = errors("BeamSimplySupported.txt", 80, length=10.0 + extra)
    conv, it, ea, eb, _, _ = res
    assert conv and it < 50
    assert abs(ea) < 2e-4 and abs(eb) < 2e-4, (ea, eb)


@pytest.mark.parametrize("name, length", [("MHK_RM1_Floating_MoorDyn.dat", None),
                                          ("moorpy_case5.dat", 690.0),
                                          ("moorpy_case9.dat", None)])
def test_reported_statics_of_the_public_decks_agree_with_moorpy_at_80_segments(name, length):
    """What ``moorjax statics DECK --segments 80`` reports (``method="auto"``: the exact
    catenary for these cable lines) agrees with MoorPy within 5e-4 at 80 segments,
    where the FEM equilibrium above needs 320 on the sharp touchdowns."""
    lines, env = lines_of(name, 80, length)
    for line in lines:
        st = solve_line_statics(line, env, throw=False, method="auto")
        ta, tb = moorpy(line, env)
        assert bool(st.converged)
        assert abs(float(st.tension_a) / ta - 1) < 5e-4 and abs(float(st.tension_b) / tb - 1) < 5e-4
