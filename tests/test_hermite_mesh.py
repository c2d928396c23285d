"""Graded Hermite elements (``HermiteElement(mesh=...)``) and the touchdown mesh.

The elements of a Hermite line may have unequal lengths (relative lengths,
normalised to the line's). ``touchdown_mesh`` puts an element boundary at a
grounded line's static touchdown and grades the elements away from it; on the
drawn lines of ``tests/test_hermite_statics_property.py`` that takes the
grounded lines' end-tension error at 10 elements from a median 4.6e-3 to
1.0e-4 of the largest tension.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from moorpy.Catenary import catenary as moorpy_catenary

import moorjax as mj
from moorjax.element import HermiteElement
from moorjax.element.hermite import element_lengths
from moorjax.element.hermite_motion import _assemble, element_mass, unpack_hermite
from moorjax.io import build_scene, read_deck
from moorjax.statics.fem import solve_line_statics
from moorjax.statics.hermite import UnresolvedTouchdownWarning, graded_mesh, touchdown_mesh

pytestmark = pytest.mark.slow

DATA = Path(__file__).parent / "data"
SOLVE = eqx.filter_jit(lambda line, env: solve_line_statics(line, env, throw=False))
LT = mj.LineType(0.09, 77.7066, 384.243e6)
ENV = mj.Environment(300.0)
RA, RB = (-600.0, 0.0, -250.0), (0.0, 0.0, -20.0)
# MoorPy's statics of reference case A (/work/shared/reference/statics.csv)
CASE_A = (736938.85, 911089.02, 134.78553)


def line_with(mesh, length=700.0, n=8):
    return mj.Line(LT, length, n, mj.FixedEnd(RA), mj.FixedEnd(RB), element=HermiteElement(mesh=mesh))


def moorpy_free_hanging(length=700.0):
    w = float(LT.wet_weight(ENV.rho, ENV.g))
    fah, fav, fbh, fbv, _ = moorpy_catenary(RB[0] - RA[0], RB[2] - RA[2], length, 384.243e6, w,
                                            CB=-(RA[2] + 300.0), Tol=1e-12, MaxIter=200)
    return float(np.hypot(fah, fav)), float(np.hypot(fbh, fbv))


def case_a(n=10, mesh=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = build_scene(read_deck(DATA / "case_A.dat"), segments=n)
    (line,) = scene.lines
    return mj.Line(line.line_type, line.length, n, line.end_a, line.end_b,
                   element=HermiteElement(mesh=mesh)), scene.env


def test_equal_relative_lengths_are_the_uniform_element():
    a, b = SOLVE(line_with(None), ENV), SOLVE(line_with(np.full(8, 3.0)), ENV)
    np.testing.assert_allclose(a.positions, b.positions, rtol=0, atol=1e-9)
    np.testing.assert_allclose([a.tension_a, a.tension_b], [b.tension_a, b.tension_b], rtol=1e-12)


def test_unequal_elements_still_agree_with_moorpy():
    """A random mesh of a free-hanging line: every element's own length enters the
    shape functions, the quadrature and the tension field."""
    mesh = np.random.default_rng(3).uniform(0.3, 2.0, 8)
    line = line_with(mesh)
    np.testing.assert_allclose(element_lengths(line), 700.0 * mesh / mesh.sum(), rtol=1e-14)
    st = SOLVE(line, ENV)
    ta, tb = moorpy_free_hanging()
    assert bool(st.converged)
    assert abs(float(st.tension_a) / ta - 1) < 1e-4 and abs(float(st.tension_b) / tb - 1) < 1e-4


def test_the_mass_of_unequal_elements_is_the_line_mass():
    """A rigid translation (positions 1, slopes 0) has the line's mass in the
    consistent mass of graded elements (slopes scaled by their own lengths)."""
    mesh = np.random.default_rng(4).uniform(0.3, 2.0, 8)
    line = mj.Line(mj.LineType(0.09, 77.7066, 384.243e6), 700.0, 8, mj.FixedEnd(RA), mj.FixedEnd(RB),
                   element=HermiteElement(mesh=mesh))
    st = SOLVE(line, ENV)
    q = st.rest_state.packed()
    s = unpack_hermite(line, q)
    from moorjax.element.hermite import HermiteDofs

    r = jnp.concatenate([jnp.asarray(RA)[None], s.r, jnp.asarray(RB)[None]])
    dofs = HermiteDofs(r=r, dr=s.d / line.segment_length, lam=jnp.zeros(17))
    m = _assemble(element_mass(line, ENV, dofs))
    u = np.zeros((18, 3))
    u[0::2, 0] = 1.0  # every node moves 1 m in x, no slope changes
    assert abs(float(u.reshape(-1) @ m @ u.reshape(-1)) / (77.7066 * 700.0) - 1) < 1e-12


def test_a_bad_mesh_is_refused():
    with pytest.raises(ValueError, match="positive relative element lengths"):
        HermiteElement(mesh=[1.0, -1.0, 2.0])
    with pytest.raises(ValueError, match="has shape"):
        SOLVE(line_with(np.ones(5)), ENV)


def test_graded_mesh_puts_a_boundary_at_the_touchdown():
    mesh = graded_mesh(1000.0, 10, 0.0, 333.0, 5.0)
    assert mesh.shape == (10,) and np.all(mesh > 0) and abs(mesh.sum() - 1) < 1e-14
    edges = 1000.0 * np.concatenate([[0.0], np.cumsum(mesh)])
    assert np.min(np.abs(edges - 333.0)) < 1e-9
    k = int(np.argmin(np.abs(edges - 333.0)))
    assert abs(edges[k + 1] - edges[k] - 5.0) < 1e-9  # the suspended side starts at H/w
    assert edges[k] - edges[k - 1] < 100.0  # the grounded side grows from it too (capped)
    sizes = np.diff(edges)
    for side in (sizes[:k], sizes[k:]):  # geometric on each side, growth at most 3
        ratios = side[1:] / side[:-1]
        assert np.all(ratios < 3.0 + 1e-9) and np.all(ratios > 1 / 3.0 - 1e-9)
    # a gentle catenary (H/w longer than an element): equal elements on each side,
    # the straight grounded stretch with half its share of them
    np.testing.assert_allclose(graded_mesh(100.0, 10, 0.0, 50.0, 100.0), [0.5 / 3] * 3 + [0.5 / 7] * 7)


def test_touchdown_mesh_on_reference_case_a():
    """Case A (a chain resting 135 m on the bed) at 10 elements: the boundary at
    MoorPy's touchdown, end tensions within 1e-4 and the grounded length within
    0.1 m (equal elements: 2.1e-4 and 0.1 m)."""
    line, env = case_a()
    graded = touchdown_mesh(line, env)
    mesh = np.asarray(graded.element.mesh)
    edges = float(line.length) * np.concatenate([[0.0], np.cumsum(mesh)])
    assert np.min(np.abs(edges - CASE_A[2])) < 0.5
    st = SOLVE(graded, env)
    ta, tb, lb = CASE_A
    assert bool(st.converged)
    assert abs(float(st.tension_a) / ta - 1) < 1e-4 and abs(float(st.tension_b) / tb - 1) < 1e-4
    assert abs(float(st.grounded_length) - lb) < 0.1
    # swapping the ends grades the mirror image
    swapped = mj.Line(line.line_type, line.length, 10, line.end_b, line.end_a, element=HermiteElement())
    np.testing.assert_allclose(np.asarray(touchdown_mesh(swapped, env).element.mesh)[::-1], mesh,
                               rtol=1e-6)


def test_lines_off_the_bed_and_linear_lines_are_not_graded():
    assert touchdown_mesh(line_with(None), ENV).element.mesh is None
    line, env = case_a()
    linear = mj.Line(line.line_type, line.length, 10, line.end_a, line.end_b)
    assert touchdown_mesh(linear, env) is linear
    assert touchdown_mesh(line, mj.Environment(300.0)) is line  # no seabed


def test_solve_line_statics_warns_where_equal_elements_miss_the_touchdown():
    """A 1500 m chain with 1.1 km on the bed: 10 equal Hermite elements
    converge with the anchor's tension 5.8 % below MoorPy's (the touchdown
    bends within 0.31 of an element). Solved outside jit, the statics say so
    (``check_resolution``); under jit, on the graded mesh (within 1e-3 of
    MoorPy) and while ``touchdown_mesh`` grades it, they do not."""
    bed = mj.Environment(depth=300.0, seabed=mj.Seabed(stiffness=3e6, damping=3e5))
    line = mj.Line(LT, 1500.0, 10, mj.FixedEnd((-1300.0, 0.0, -300.0)), mj.FixedEnd((0.0, 0.0, -20.0)),
                   element=HermiteElement(), label="long")
    w = float(LT.wet_weight(bed.rho, bed.g))
    fah, fav, fbh, fbv, _ = moorpy_catenary(1300.0, 280.0, 1500.0, 384.243e6, w, CB=0.0, Tol=1e-12,
                                            MaxIter=200)
    ta = float(np.hypot(fah, fav))

    def solved(fn, *args):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            out = fn(*args)
        return out, [str(x.message) for x in caught if issubclass(x.category, UnresolvedTouchdownWarning)]

    st, said = solved(lambda: solve_line_statics(line, bed, throw=False))
    assert bool(st.converged) and abs(float(st.tension_a) / ta - 1) > 0.05
    assert len(said) == 1 and "line long" in said[0] and "end A" in said[0] and "touchdown_mesh" in said[0]
    assert solved(SOLVE, line, bed)[1] == []
    graded, said = solved(touchdown_mesh, line, bed)
    assert said == [] and graded.element.mesh is not None
    st, said = solved(lambda: solve_line_statics(graded, bed, throw=False))
    assert said == [] and abs(float(st.tension_a) / ta - 1) < 1e-3


def test_ensemble_members_are_checked_for_their_touchdown():
    """Ensembles solve their statics batched (vmapped, inside jit), where
    ``solve_line_statics``' check on values cannot run. They run the same
    comparison batched (``resolution_offsets``) and warn once per line, naming
    the members: the 1500 m chain above from anchors 1300, 1440 and 1460 m
    away. The first member's touchdown is not resolved (5.67 %), the others'
    are (measured 3.9e-4 and 2.5e-4); each member's offset is the one
    ``check_resolution`` measures on the line alone."""
    from moorjax.ensemble import stack
    from moorjax.ensemble.run import _equilibrium, equilibrium
    from moorjax.statics.hermite import RESOLUTION_TOL, check_resolution

    bed = mj.Environment(depth=300.0, seabed=mj.Seabed(stiffness=3e6, damping=3e5))
    lines = [mj.Line(LT, 1500.0, 10, mj.FixedEnd((x, 0.0, -300.0)), mj.FixedEnd((0.0, 0.0, -20.0)),
                     element=HermiteElement(), label="long") for x in (-1300.0, -1440.0, -1460.0)]
    scenes = [mj.Scene(lines=(line,), env=bed) for line in lines]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _, ok = equilibrium(scenes)
        alone = [check_resolution(line, bed, solve_line_statics(line, bed, throw=False)) for line in lines]
    said = [str(x.message) for x in caught if issubclass(x.category, UnresolvedTouchdownWarning)]
    assert np.all(np.asarray(ok))
    ensemble = [m for m in said if "ensemble members" in m]
    assert len(ensemble) == 1 and "line long" in ensemble[0] and "1 of 3 ensemble members [0]" in ensemble[0]
    _, _, off = _equilibrium(stack(scenes), 0.0)
    worst = np.nanmax(off[:, 0, :], axis=1)
    assert worst[0] > RESOLUTION_TOL > max(worst[1:]), worst
    np.testing.assert_allclose(worst, alone, rtol=1e-6)


def test_derivative_of_a_sharp_grounded_line_at_equal_elements():
    """The same 1500 m chain: the derivative of the fairlead force with respect
    to the fairlead's height, forward and reverse, equals central differences.
    It used to raise (lineax: "non-finite input") under ``jax.jacfwd`` and
    ``jax.linearize``, so a body scene with this line could not start: the
    implicit derivatives were optimistix's, taken at its Newton's value, and
    the strain closure's Newton fails on this line (a singular Jacobian; the
    start falls back to Wu's equilibrium), so lineax met its NaN. Now the root
    kept gets it (``moorjax.statics.fem.implicit_root``, never raising)."""
    import jax

    bed = mj.Environment(depth=300.0, seabed=mj.Seabed(stiffness=3e6, damping=3e5))

    def force_b(zb):
        line = mj.Line(LT, 1500.0, 10, mj.FixedEnd((-1300.0, 0.0, -300.0)),
                       mj.FixedEnd(jnp.stack([0.0, 0.0, zb])), element=HermiteElement())
        return solve_line_statics(line, bed, throw=False).force_b

    zb, h = -20.0, 1e-2
    central = (np.asarray(force_b(zb + h)) - np.asarray(force_b(zb - h))) / (2 * h)
    for jac in (jax.jacfwd, jax.jacrev):
        d = np.asarray(jac(force_b)(zb))
        assert np.all(np.isfinite(d)) and np.allclose(d, central, rtol=1e-6, atol=1e-6 * abs(central).max()), (
            d, central)  # measured: 6e-8 of |d| apart


def test_cli_statics_grades_hermite_lines_at_the_touchdown(capsys):
    from moorjax.cli import main

    rows = {}
    for mesh in ("touchdown", "uniform"):
        assert main(["statics", "example:oc3_catenary", "--segments", "10", "--element", "hermite",
                     "--hermite-mesh", mesh, "--json"]) == 0
        (rows[mesh],) = json.loads(capsys.readouterr().out)
    ta, tb, lb = CASE_A
    err = {k: abs(r["tension_b"] / tb - 1) for k, r in rows.items()}
    assert err["touchdown"] < 1e-4 < err["uniform"], err
    assert abs(rows["touchdown"]["grounded_length"] - lb) < 0.1


def test_a_line_sagging_onto_the_bed_is_graded_at_both_touchdowns():
    """Both ends 100 m above the bed, 1000 m of chain over a 940 m span: the
    middle 540 m rest on the bed. By symmetry (frictionless bed) each half is MoorPy's
    anchored catenary from the midpoint; 10 elements graded at both touchdowns
    agree with it within 5e-4 (measured 2.0e-4: three elements per suspended
    stretch), equal elements do not (8.2e-3)."""
    env = mj.Environment(300.0, seabed=mj.Seabed(stiffness=3e6, damping=3e5))
    w = float(LT.wet_weight(env.rho, env.g))
    _, _, fbh, fbv, info = moorpy_catenary(470.0, 100.0, 500.0, 384.243e6, w, CB=0.0, Tol=1e-12, MaxIter=200)
    t_end, grounded = float(np.hypot(fbh, fbv)), 2.0 * float(info["LBot"])
    assert 500.0 < grounded < 600.0
    line = mj.Line(LT, 1000.0, 10, mj.FixedEnd((-470.0, 0.0, -200.0)), mj.FixedEnd((470.0, 0.0, -200.0)),
                   element=HermiteElement())
    graded = touchdown_mesh(line, env)
    edges = 1000.0 * np.concatenate([[0.0], np.cumsum(np.asarray(graded.element.mesh))])
    for knot in (500.0 - grounded / 2, 500.0 + grounded / 2):
        assert np.min(np.abs(edges - knot)) < 0.5, (knot, edges)
    st, equal = SOLVE(graded, env), SOLVE(line, env)
    assert bool(st.converged)
    err = max(abs(float(st.tension_a) / t_end - 1), abs(float(st.tension_b) / t_end - 1))
    err_equal = max(abs(float(equal.tension_a) / t_end - 1), abs(float(equal.tension_b) / t_end - 1))
    assert err < 5e-4 and err_equal > 10 * err, (err, err_equal)
    assert abs(float(st.grounded_length) - grounded) < 0.5


def test_hermite_lines_piled_on_the_bed_are_warned_about():
    """A Hermite line longer than its path along the seabed (horizontal distance
    of its ends plus their heights above the bed) lies piled with a corner the
    cubics cannot represent: solve_line_statics warns before solving; shorter
    lines and the linear element do not."""
    import warnings

    import moorjax as mj
    from moorjax.element import HermiteElement
    from moorjax.examples import example_path
    from moorjax.io import build_scene, read_deck
    from moorjax.statics import solve_line_statics
    from moorjax.statics.hermite import PiledLineWarning, check_piled

    scene = build_scene(read_deck(example_path("oc3_catenary")), segments=10)
    lt, env = scene.lines[0].line_type, scene.env

    def line(length, element):
        return mj.Line(lt, length, 10, mj.FixedEnd([-1100.0, 0.0, -320.0]), mj.FixedEnd([0.0, 0.0, -70.0]),
                       element=element)

    # the path: 1100 m along the bed and 250 m up to the fairlead
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        assert not check_piled(line(1349.0, HermiteElement()), env)
        assert not check_piled(line(1500.0, None), env)
        solve_line_statics(line(1500.0, HermiteElement()), env, throw=False)
    piled = [w for w in seen if issubclass(w.category, PiledLineWarning)]
    assert len(piled) == 1 and "1350 m" in str(piled[0].message) and "linear element" in str(piled[0].message)



def test_ensembles_name_their_members_with_piled_hermite_lines():
    """An ensemble's members are checked before the batched statics (which run
    under ``vmap``, where a line's own check is skipped): one warning per line
    naming the members whose Hermite line is piled on the bed (longer than its
    1350 m path), none for the others."""
    import warnings

    import moorjax as mj
    from moorjax.element import HermiteElement
    from moorjax.ensemble.run import _check_members
    from moorjax.examples import example_path
    from moorjax.io import build_scene, read_deck
    from moorjax.statics.hermite import PiledLineWarning

    base = build_scene(read_deck(example_path("oc3_catenary")), segments=10)
    lt, env = base.lines[0].line_type, base.env

    def member(length, element=HermiteElement()):
        line = mj.Line(lt, length, 10, mj.FixedEnd([-1100.0, 0.0, -320.0]),
                       mj.FixedEnd([0.0, 0.0, -70.0]), element=element)
        return mj.Scene([line], env)

    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        _check_members([member(1300.0), member(1400.0), member(1340.0), member(1500.0)], 0.0)
        _check_members([member(1300.0), member(1500.0, None)], 0.0)  # the linear element follows it
    piled = [str(w.message) for w in seen if issubclass(w.category, PiledLineWarning)]
    assert len(piled) == 1, piled
    assert "2 of 4 ensemble members [1, 3]" in piled[0] and "150 m" in piled[0]
    assert "linear element" in piled[0]
