"""Hermite statics at 10 elements over the drawn lines of
``tests/test_statics_property.py`` (same seed, same 200 lines, MoorPy's
analytic catenary as the oracle).

With a seabed the Hermite statics start from the linear element's equilibrium
at twice the segments and damp Newton's steps (``moorjax/statics/hermite.py``).
Measured on these draws at 10 elements:

- from the flat catenary with plain Newton (before), 16 of 200 failed (14
  grounded); now 2 fail, both grounded lines whose touchdown is far sharper
  than an element (draw 47: catenary parameter H/w = 0.017 element lengths;
  draw 188: 1.25, which converges at 8, 12, 16 and 20 elements; since
  session 37 draw 188 converges too, see below);
- lines that do not rest on the bed (MoorPy's grounded length 0: suspended,
  taut, near-straight and floating lines, and lines leaving an anchor on the
  bed upwards; 102 of them) all converge, worst end-tension error 1.1e-6 of
  its own tension: issue 13's 5e-4 at 10 elements holds for them;
- lines with a grounded stretch do not meet it. Those whose catenary
  parameter H/w is at least 3.75 element lengths (the property test's rule for
  a touchdown that 80 linear segments resolve) converge with worst error
  4.3e-3 (draw 71: 49 % of the line on the bed); an element that holds the
  touchdown holds the kink of the line's curvature, which a cubic cannot
  follow (more quadrature points change nothing: 12 points per element, worst
  5.1e-3). All grounded lines: median error 1.0e-2 of the largest tension,
  against 3.5e-2 for the linear element at 10 segments.

(An earlier version of this test counted the grounded lines of the second
class as "resolved" together with the first, and its notes called them
suspended.)

Graded at the touchdown (:func:`moorjax.statics.hermite.touchdown_mesh`: an
element boundary at the static touchdown, elements growing geometrically away
from it from the catenary's length scale H/w), still 10 elements. All 98
grounded lines are graded and converge. Over the 91 whose H/w is at least 0.05
element lengths: worst end-tension error 4.8e-4 of the largest tension, median
1.0e-4 (equal elements: median 4.6e-3 over all grounded lines). The worst,
draw 147 (polyester, H/w = 0.8 element lengths), is 4.8e-4 or 5.2e-4 as the
touchdown iteration stops at 1e-3 or 1e-4 of an element, and converges fast
with more elements (4.3e-5 at 20, 3.3e-6 at 40); draw 82 (wire) stays at 4e-4
at 40 elements and with the linear element at 400 segments: the penalty
seabed's penetration against MoorPy's rigid bed. Hence the bound 6e-4. The 7
sharper touchdowns (H/w 0.016–0.046 element lengths): five within 4e-4, draw 47
at 6.2e-4 and draw 90 at 1.06e-3 (both H/w ≈ 0.016 elements; at 12 graded
elements 5.7e-5 and 2.2e-5; the linear element at 400 segments: 1.7e-3 and
5.9e-4). Against its own value the grounded end of draw 90 is 26 % off
(2858 N against 2271 N; at 12, 16, 20 graded elements 1.3e-3, 3.1e-4,
3.1e-5), draw 108's 0.33 % (0.71 % at 12 elements, 0.061 % at 16), so
``touchdown_mesh`` warns (``UnresolvedTouchdownWarning``) for the lines whose
H/w stays below SHARP of a mean element: exactly these 7. Their errors depend
on rounding: on an AMD EPYC host (session 24; the figures above are from an
Intel one) the 7 are 2.7e-5, 6.2e-4, 7.7e-4, 1.1e-5, 2.05e-3 (H/w 0.022
elements), 3.9e-4 and 9.4e-6, so the bound for them is 2.5e-3, and three of
them (not two) are above 5e-4; the 91 resolved
lines are unchanged (worst 4.8e-4, median 1.0e-4).

Session 37: a grounded line that does not converge from the linear
equilibrium at 2 segments per element is solved again from 8 (a graded mesh:
from 8, then 2; ``GUESS_SEGMENTS`` in ``moorjax/statics/hermite.py``), and
optimistix's Newton after the damped one keeps the damped iterate where it
would raise the imbalance. Equal elements: only draw 47 fails (its imbalance
3.9e4 N instead of 1e15); draw 108 no longer lands on the root it did (253 N at
the grounded end for MoorPy's 5797 N) but converges again, as sharp touchdowns
do at equal elements, far off (equal elements do not resolve it: graded, 6e-3).
Graded: the sharper touchdowns' errors are 8.4e-6 … 6.2e-4 of the largest
tension (draws 90 and 108: 2.9e-5 and 2.5e-4, from 1.1e-3 and 2.1e-3, which
converged or diverged with the rounding of the linear solve that started them);
against their own value the 7 warned lines are within 1.3e-2 (was 26 %), the
91 others within 1.1e-3. The same figures with the linear statics of session
36's reverted change (a different rounding of the start).

Session 38: equal elements converge on 25 grounded lines more than 5e-2 off
MoorPy at an end (up to 56x, draw 122), ``converged`` True; draws 122 and 132
with a larger horizontal pull than MoorPy's, so H/w against the element does
not single them out. ``check_resolution`` (run by ``solve_line_statics``
outside jit) compares with the linear element at 8 segments per element and
warns for these 25 and for draw 39 (4.78e-2 off); the 71 others are within
4.9e-2.

Until session 18 the first touchdown came from equal Hermite elements only:
draws 47 and 188 failed with every mesh, and on draws 90 and 108 equal
elements converged on a horizontal pull 2–50× too small, so the graded mesh
started at a millimetre (draw 90's solve failed and it kept its equal
elements, 3.7e-2; draw 108 landed at 3.2e-3). The first touchdown now comes
from the linear element at 8 segments per element where equal elements fail
or bend within 0.05 of an element (``FINE_SEGMENTS``, ``SHARP`` in
``moorjax/statics/hermite.py``): draw 188 1.6e-4, 108 8.9e-5, 47 and 90 as above.
"""

from __future__ import annotations

import warnings

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import moorjax as mj
from moorjax.element import HermiteElement
from moorjax.statics.fem import solve_line_statics
from moorjax.statics.hermite import RESOLUTION_TOL, UnresolvedTouchdownWarning, check_resolution, touchdown_mesh

from test_statics_property import (N_DRAWS, SEED, _errors, _resolved, _stiffness_against_differences, build,
                                   draw_line, moorpy_oracle, oracle_top)

pytestmark = pytest.mark.slow

N = 10
SOLVE = eqx.filter_jit(lambda line, env: solve_line_statics(line, env, throw=False))


@pytest.fixture(scope="module")
def solved():
    rng = np.random.default_rng(SEED)
    draws = []
    while len(draws) < N_DRAWS:
        c = draw_line(rng)
        if c["w"] < 0 and oracle_top(c) > 0.0:
            continue
        c["oracle"] = moorpy_oracle(c)
        draws.append(c)
    out = []
    for c in draws:
        line, env = build(c, N)
        hermite = mj.Line(line.line_type, line.length, N, line.end_a, line.end_b, element=HermiteElement())
        out.append((c, SOLVE(hermite, env), SOLVE(line, env)))
    return out


@pytest.fixture(scope="module")
def graded(solved):
    """The grounded draws, each with its line graded at the touchdown, its statics and
    whether ``touchdown_mesh`` warned that the touchdown is unresolved."""
    out = []
    for c, _, _ in solved:
        if c["oracle"][3] > 0.0:
            line, env = build(c, N)
            hermite = mj.Line(line.line_type, line.length, N, line.end_a, line.end_b, element=HermiteElement())
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                g = touchdown_mesh(hermite, env)
            warned = any(issubclass(x.category, UnresolvedTouchdownWarning) for x in caught)
            out.append((c, g, SOLVE(g, env), warned))
    return out


def test_grounded_lines_graded_at_the_touchdown_agree_with_moorpy(graded):
    """Issue 13's 5e-4 at 10 elements on grounded lines, with the elements graded
    at the touchdown: every line whose touchdown 10 graded elements resolve
    (H/w ≥ SHARP element lengths) converges within 6e-4, the sharper ones within
    2.5e-3, all but three of them within 5e-4 (see the module notes)."""
    assert len(graded) > 90
    resolved = [(c, line, st) for c, line, st, _ in graded if _gentle(c)]
    ok = [(c, st) for c, line, st in resolved if line.element.mesh is not None and bool(st.converged)]
    errors = np.array([_errors(c, st)[1] for c, st in ok])
    print(f"\n{len(ok)} of {len(resolved)} grounded lines with H/w >= {SHARP} elements graded and "
          f"converged: worst error {errors.max():.2e}, median {np.median(errors):.2e}")
    assert len(resolved) > 85 and len(ok) == len(resolved), (len(ok), len(resolved))
    assert errors.max() < 6e-4, errors.max()
    assert np.median(errors) < 2e-4, np.median(errors)
    sharp = [(c, line, st) for c, line, st, _ in graded if not _gentle(c)]
    for c, line, st in sharp:
        print(f"sharper touchdown (H/w {c['oracle'][2] / abs(c['w']) / (c['length'] / N):.3f} elements): "
              f"graded {line.element.mesh is not None}, converged {bool(st.converged)}, "
              f"error {_errors(c, st)[1]:.2e}")
    assert len(sharp) >= 5
    assert all(line.element.mesh is not None and bool(st.converged) for _, line, st in sharp)
    sharp_errors = np.array([_errors(c, st)[1] for c, _, st in sharp])
    assert sharp_errors.max() < 2.5e-3, sharp_errors
    assert np.sum(sharp_errors < 5e-4) >= len(sharp) - 3, sharp_errors
    for c, line, _, _ in graded:  # the mesh: 10 elements summing to the line, graded
        if line.element.mesh is not None:
            mesh = np.asarray(line.element.mesh)
            assert mesh.shape == (N,) and np.all(mesh > 0) and abs(mesh.sum() - 1.0) < 1e-12


def test_touchdown_mesh_warns_exactly_where_the_touchdown_is_unresolved(graded):
    """``touchdown_mesh`` warns for the grounded lines whose touchdown bends within
    SHARP of an element (H/w from MoorPy's horizontal pull) and for no other; the
    lines it does not warn for get both end tensions, the grounded one included,
    within 2e-3 of their own value, the warned ones within 5e-2 (measured
    1.3e-2, see the module notes)."""
    warned = [warn for _, _, _, warn in graded]
    expected = [not _gentle(c) for c, _, _, _ in graded]
    assert sum(expected) >= 5 and warned == expected, [i for i, (a, b) in enumerate(zip(warned, expected)) if a != b]
    own = np.array([_errors(c, st)[0] for c, _, st, warn in graded if not warn])
    sharp = np.array([_errors(c, st)[0] for c, _, st, warn in graded if warn])
    print(f"\nend tensions against their own value: {len(own)} lines without the warning, worst "
          f"{own.max():.2e}, median {np.median(own):.2e}; {len(sharp)} warned, worst {sharp.max():.2e}")
    assert own.max() < 2e-3, own.max()
    assert sharp.max() < 0.05, sharp  # measured 1.3e-2 (26 % before session 37's second start)


def test_equal_elements_warn_where_their_grounded_end_is_off(solved):
    """``converged`` only says the discrete equations are solved. On equal
    elements a grounded line whose touchdown the cubics do not follow converges
    on end tensions up to 56 times off (draw 122; draws 90, 108: 98 %, 96 %),
    some with a larger horizontal pull than MoorPy's (so H/w against the
    element does not tell). ``check_resolution`` (what ``solve_line_statics``
    runs outside jit) compares with the linear element at 8 segments per
    element: it warns for every line more than 2·RESOLUTION_TOL off MoorPy (own
    value), for none within RESOLUTION_TOL/2, and for no line off the bed.
    Measured: the 26 warned lines 4.8e-2 … 56 off, the others at most 4.9e-2."""
    warned, quiet, skipped = [], [], 0
    for c, st, _ in solved:
        line, env = build(c, N)
        hermite = mj.Line(line.line_type, line.length, N, line.end_a, line.end_b, element=HermiteElement())
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            off = check_resolution(hermite, env, st)
        warn = any(issubclass(x.category, UnresolvedTouchdownWarning) for x in caught)
        if c["oracle"][3] == 0.0 or not bool(st.converged):
            assert not warn
            skipped += off is None
            continue
        assert off is not None and warn == (off > RESOLUTION_TOL)
        (warned if warn else quiet).append(_errors(c, st)[0])
    warned, quiet = np.array(warned), np.array(quiet)
    print(f"\n{len(warned)} grounded lines warned (MoorPy error {warned.min():.2e} … {warned.max():.2e}), "
          f"{len(quiet)} not (at most {quiet.max():.2e}); {skipped} lines off the bed skipped")
    assert skipped > 90 and len(warned) >= 10 and len(quiet) >= 50
    assert warned.min() > RESOLUTION_TOL / 2, warned.min()
    assert quiet.max() < 2 * RESOLUTION_TOL, quiet.max()
    assert warned.max() > 10.0  # draw 122 among them


#: H/w, in element lengths, below which a touchdown is sharper than 10 graded
#: elements resolve reliably (the catenary bends within 1/20 of a mean element)
SHARP = 0.05


def _gentle(c):
    return c["oracle"][2] / abs(c["w"]) >= SHARP * c["length"] / N


def test_lines_off_the_bed_converge_and_agree_with_moorpy(solved):
    """Issue 13's 5e-4 at 10 elements, for every line that does not rest on the bed."""
    free = [(c, st) for c, st, _ in solved if c["oracle"][3] == 0.0]
    assert len(free) > 90 and {c["regime"] for c, _ in free} >= {"suspended", "taut", "straight", "floating"}
    failed = [i for i, (c, st) in enumerate(free) if not bool(st.converged)]
    assert failed == []
    worst = max(_errors(c, st)[0] for c, st in free)
    print(f"\n{len(free)} lines off the bed: worst end-tension error {worst:.2e}")
    assert worst < 1e-5, worst


def test_grounded_lines_with_a_gentle_touchdown_converge(solved):
    """Grounded lines whose touchdown curvature spans several elements (H/w at
    least 3.75 element lengths): all converge, within 5e-3 (not issue 13's 5e-4)."""
    gentle = [(c, st) for c, st, _ in solved if c["oracle"][3] > 0.0 and _resolved(c, 80)]
    assert len(gentle) > 10
    assert all(bool(st.converged) for _, st in gentle)
    worst = max(_errors(c, st)[0] for c, st in gentle)
    print(f"\n{len(gentle)} grounded lines with H/w >= 3.75 elements: worst error {worst:.2e}")
    assert worst < 5e-3, worst


def test_all_but_one_drawn_line_converge(solved):
    """At 10 equal elements every drawn line but draw 47 (a grounded line whose
    touchdown bends within 0.017 of an element) converges, and a failure is a
    finite imbalance, not a run-off Newton's (1e15 N before session 37)."""
    failed = [(i, c["regime"]) for i, (c, st, _) in enumerate(solved) if not bool(st.converged)]
    assert len(failed) <= 1 and all(regime == "grounded" for _, regime in failed), failed
    worst = max(float(st.max_residual) / max(float(st.tension_a), float(st.tension_b))
                for c, st, _ in solved if not bool(st.converged)) if failed else 0.0
    assert worst < 1.0, worst


def test_grounded_lines_beat_the_linear_element_per_element(solved):
    grounded = [(c, h, lin) for c, h, lin in solved if c["regime"] == "grounded" and bool(h.converged)]
    assert len(grounded) > 50
    hermite = np.median([_errors(c, h)[1] for c, h, _ in grounded])
    linear = np.median([_errors(c, lin)[1] for c, _, lin in grounded])
    print(f"grounded, median error of the largest tension: Hermite {hermite:.2e}, linear {linear:.2e}")
    assert hermite < 0.5 * linear, (hermite, linear)


def test_a_converged_line_gives_a_finite_start_for_the_dynamics(solved, graded):
    """The dynamics start from each static solution's ``rest_state`` (the strain
    closure's equilibrium). On a drawn grounded line whose Wu equilibrium was
    compressed along the bed that state was NaN while ``converged`` said True;
    the closure's solve now falls back to Wu's equilibrium where it fails."""
    states = [st for _, st, _ in solved] + [st for _, _, st, _ in graded]
    bad = [i for i, st in enumerate(states)
           if bool(st.converged) and not all(bool(np.all(np.isfinite(x)))
                                             for x in (st.rest_state.r, st.rest_state.d))]
    assert bad == [], bad


def test_derivatives_never_raise_and_equal_differences(solved, graded):
    """Issue 13's statics with implicit-function gradients, over the drawn lines:
    ``jax.jacfwd`` of the force on each line's higher end with respect to that
    end's position (its 3x3 stiffness, what a body's Newton iteration uses)
    against central differences (h = 1e-5 m).

    - It never raises and is finite on all 200 lines at equal elements (draw
      47 too, whose solve does not converge) and on the 98 graded ones.
    - It equals the differences within 1e-5 (measured: 1.7e-7) on every
      converged line at equal elements but where ``check_resolution`` warns
      that the touchdown is unresolved: on three of those 26 (draws 90, 108,
      122) the solve lands on different discrete roots a millimetre apart
      (draw 122: 3741 N or 2013 N at the grounded end), so the force is not a
      differentiable function of the position there. Graded at the touchdown
      every grounded line, draws 90, 108, 122 and 47 included, equals its
      differences within 1e-5 (measured 7.7e-8).
    - Draw 47 graded took the derivative of a regular Jacobian as singular
      (its pivot ratio below 1e-12 unscaled: lengths graded 250-fold, unknowns
      in metres, radians and newtons) and came out 0.99 off the differences;
      ``MinimumNorm`` now equilibrates rows and columns before it judges.
    """
    equal = []
    for c, st, _ in solved:
        line, env = build(c, N)
        hermite = mj.Line(line.line_type, line.length, N, line.end_a, line.end_b, element=HermiteElement())
        k, err = _stiffness_against_differences(hermite, env, c)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            off = check_resolution(hermite, env, st)
        equal.append((bool(st.converged), off is not None and off > RESOLUTION_TOL, bool(np.all(np.isfinite(k))), err))
    assert all(fin for _, _, fin, _ in equal)
    quiet = np.array([err for ok, warned, _, err in equal if ok and not warned])
    hops = [i for i, (ok, warned, _, err) in enumerate(equal) if ok and warned and err > 1e-5]
    print(f"\nequal elements: {len(quiet)} converged lines not warned, worst {quiet.max():.2e}; "
          f"warned lines off their differences: {hops}")
    assert len(quiet) > 150 and quiet.max() < 1e-5, quiet.max()
    assert len(hops) <= 5, hops
    grad = []
    for c, line, st, _ in graded:
        _, env = build(c, N)
        k, err = _stiffness_against_differences(line, env, c)
        grad.append((bool(st.converged), bool(np.all(np.isfinite(k))), err))
    errors = np.array([err for ok, _, err in grad if ok])
    print(f"graded: {len(errors)} of {len(grad)} converged, worst {errors.max():.2e}")
    assert all(fin for _, fin, _ in grad) and len(errors) == len(grad) > 90
    assert errors.max() < 1e-5, errors.max()


@eqx.filter_jit
def _solved_moved(line, env, upper, d, init):
    """The static solve with the line's higher end (``upper`` 1.0: B) moved by ``d`` [m], from ``init``."""
    moved = eqx.tree_at(lambda li: (li.end_a, li.end_b), line,
                        (mj.FixedEnd(line.end_a.position(0.0) + (1.0 - upper) * d),
                         mj.FixedEnd(line.end_b.position(0.0) + upper * d)))
    return solve_line_statics(moved, env, init=init, throw=False)


def test_warm_starts_converge(solved):
    """A body scene's start solves its Hermite lines again at every trial pose,
    each from its solution at the last one (``LineStatics.warm_start``). Over
    the drawn lines that converge cold, a solve from the line's own warm start
    with its higher end moved by 0 and 1 m converges every time; at 0 m on the
    same tensions. The warm start used to be the line's dynamic state (the
    strain closure's rest shape, its tension field rebuilt from its stretch):
    it failed on 8 (0 m) and 11 (1 m) of these lines, and a body start on such
    lines stopped at its first iteration (two of seven drawn point scenes)."""
    failed, moved_off, checked = [], [], 0
    for i, (c, st, _) in enumerate(solved):
        if not bool(st.converged):
            continue
        checked += 1
        line, env = build(c, N)
        hermite = mj.Line(line.line_type, line.length, N, line.end_a, line.end_b, element=HermiteElement())
        upper = jnp.asarray(float(c["rb"][2] >= c["ra"][2]))
        same = _solved_moved(hermite, env, upper, jnp.zeros(3), st.warm_start())
        moved = _solved_moved(hermite, env, upper, jnp.array([1.0, 0.0, 0.0]), st.warm_start())
        if not (bool(same.converged) and bool(moved.converged)):
            failed.append(i)
            continue
        top = max(float(st.tension_a), float(st.tension_b))
        assert abs(float(same.tension_a) - float(st.tension_a)) < 1e-6 * top, i
        assert abs(float(same.tension_b) - float(st.tension_b)) < 1e-6 * top, i
    assert checked > 190 and failed == [], failed
