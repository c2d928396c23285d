"""Statics converges for every drawn line and agrees with MoorPy's catenary.

Two statics are tested. ``method="auto"`` (what ``moorjax statics`` reports) is the
line's own equilibrium: the exact elastic catenary where it describes the line,
the finite-element equilibrium elsewhere; it must agree with MoorPy within 5e-4 at
any segment count. ``method="fem"`` (the discrete model's equilibrium, where
dynamics start) must converge for every line; its error is the discretisation's.

Property test over randomly drawn single lines (fixed seed): chain, wire rope,
polyester and buoyant lines; depths 20–2000 m; grounded (down to H/w below one
segment), suspended, taut, near-straight (length = span ± 1 cm), both ends above
the seabed, either end the lower one, any azimuth. The oracle is MoorPy's
analytic elastic catenary (rigid seabed, no friction), independent of moorjax; it
has no free surface, so buoyant lines that would arch above it are redrawn.

What 80 segments can resolve: a lumped-mass line represents the touchdown kink
only to within about one segment, so where the catenary parameter H/w is below
``RESOLVED`` segment lengths the error at 80 segments is the discretisation's
(measured up to 1.5e-2 of the line's largest tension; the worst resolved line is
at 3.2e-4 with this threshold, 5.1e-4 with 20 segment lengths; MoorDyn's own
80-segment solution of such lines is off by 1–6 % on draws like these). Those lines must
still converge at 80 segments, and their error must fall with refinement
(measured: worst 1.5e-2 of the largest tension at 80 segments, 1.3e-3 at 320).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from moorpy.Catenary import catenary as moorpy_catenary

import moorjax as mj
from moorjax.statics.fem import solve_line_statics

pytestmark = pytest.mark.slow  # long physics/compile checks: CI runs them, `-m "not slow"` skips

G, RHO = 9.80665, 1025.0
N_DRAWS = 200
SEED = 20261130
#: lines whose catenary parameter H/w is at least this many segment lengths have
#: their touchdown (if any) resolved at 80 segments
RESOLVED = 30.0

SOLVE = eqx.filter_jit(lambda line, env: solve_line_statics(line, env, throw=False))
#: what ``moorjax statics`` reports: the exact catenary where it applies, else the FEM
AUTO = eqx.filter_jit(lambda line, env: solve_line_statics(line, env, throw=False, method="auto"))


def _material(rng, kind):
    dn = rng.uniform(0.04, 0.2)  # nominal diameter [m]
    if kind == "chain":  # studless: volume-equivalent d = 1.8 dn
        return 1.8 * dn, 19.9e3 * dn**2, 0.854e11 * dn**2
    if kind == "wire":
        return dn, 5.0e3 * dn**2, 9.0e10 * dn**2
    if kind == "polyester":  # slightly heavier than water
        return 0.86 * dn, 0.8e3 * dn**2, 1.1e9 * dn**2 * rng.uniform(5, 20)
    d = 2 * dn  # buoyant (riser with floats): half the displaced mass
    return d, 0.5 * RHO * np.pi * d * d / 4, 1e10 * dn**2


def draw_line(rng):
    """One random line: a dict of SI values (the ends are 3-vectors [m])."""
    kind = rng.choice(["chain", "wire", "polyester", "buoyant"], p=[0.35, 0.25, 0.25, 0.15])
    d, m, ea = _material(rng, kind)
    w = (m - RHO * np.pi * d * d / 4) * G
    depth = float(np.exp(rng.uniform(np.log(20), np.log(2000))))
    regime = rng.choice(["grounded", "suspended", "taut", "straight", "floating"],
                        p=[0.4, 0.2, 0.15, 0.1, 0.15])
    if w < 0 and regime == "grounded":
        regime = "suspended"
    az = rng.uniform(0, 2 * np.pi)
    e = np.array([np.cos(az), np.sin(az), 0.0])
    if regime == "floating":  # both ends above the seabed
        za = -depth * rng.uniform(0.2, 0.9)
        zb = za + (-za) * rng.uniform(0.1, 0.9)
    else:
        za = -depth
        zb = -depth * rng.uniform(0.0, 0.8)
    zb = min(zb, -1.0)
    h = max(zb - za, 1.0)
    zb = za + h
    length = h * rng.uniform(1.2, 6.0)
    slack_x, taut_x = length - h, np.sqrt(length**2 - h * h)  # pile-up and straight limits
    if regime == "grounded":
        x = slack_x + rng.uniform(0.02, 0.6) * (taut_x - slack_x)
    elif regime in ("suspended", "floating"):
        x = slack_x + rng.uniform(0.6, 0.995) * (taut_x - slack_x)
    elif regime == "taut":
        x = np.sqrt((length * (1 + rng.uniform(0.0, 0.01))) ** 2 - h * h)
    else:  # near-straight: length = chord ± 1 cm
        x = taut_x
        length = np.hypot(x, h) + rng.uniform(-0.01, 0.01)
    ra = np.array([0.0, 0.0, za]) + rng.uniform(-500, 500, 3) * np.array([1.0, 1.0, 0.0])
    rb = ra + x * e + np.array([0.0, 0.0, h])
    if rng.random() < 0.5:
        ra, rb = rb, ra
    return dict(kind=str(kind), regime=str(regime), d=d, m=m, ea=ea, w=w, depth=depth,
                length=float(length), ra=ra, rb=rb)


def build(c, n, friction=False):
    lt = mj.LineType(diameter=c["d"], mass_per_length=c["m"], axial=mj.LinearEA(c["ea"]))
    bed = mj.Seabed(stiffness=3e6, damping=3e5,
                    friction=mj.SeabedFriction(0.5) if friction else None)
    env = mj.Environment(depth=c["depth"], seabed=bed)
    line = mj.Line(lt, length=c["length"], n_segments=n,
                   end_a=mj.FixedEnd(c["ra"]), end_b=mj.FixedEnd(c["rb"]))
    return line, env


def moorpy_oracle(c):
    """(T_A, T_B, H, grounded length) from MoorPy; the seabed is rigid and frictionless."""
    ra, rb = c["ra"], c["rb"]
    lo, hi = (ra, rb) if ra[2] <= rb[2] else (rb, ra)
    xf = float(np.hypot(*(hi - lo)[:2]))
    zf = float(hi[2] - lo[2])
    cb = 0.0 if abs(lo[2] + c["depth"]) < 1e-9 else -(lo[2] + c["depth"])  # < 0: bed below
    fah, fav, fbh, fbv, info = moorpy_catenary(xf, zf, c["length"], c["ea"], c["w"], CB=cb,
                                               Tol=1e-10, MaxIter=500)
    t_lo, t_hi = float(np.hypot(fah, fav)), float(np.hypot(fbh, fbv))
    ta, tb = (t_lo, t_hi) if ra[2] <= rb[2] else (t_hi, t_lo)
    return ta, tb, float(info["HF"]), float(info.get("LBot", 0.0))


def oracle_top(c):
    """Height [m] of the highest point of MoorPy's catenary profile (200 points)."""
    ra, rb = c["ra"], c["rb"]
    lo, hi = (ra, rb) if ra[2] <= rb[2] else (rb, ra)
    cb = 0.0 if abs(lo[2] + c["depth"]) < 1e-9 else -(lo[2] + c["depth"])
    *_, info = moorpy_catenary(float(np.hypot(*(hi - lo)[:2])), float(hi[2] - lo[2]), c["length"],
                               c["ea"], c["w"], CB=cb, Tol=1e-10, MaxIter=500, plots=1, nNodes=200)
    return float(lo[2] + np.max(info["Z"]))


@pytest.fixture(scope="module")
def draws():
    """N_DRAWS lines that stay under the water: MoorPy's catenary has no free
    surface, moorjax's lines are buoyant only where wet (a buoyant line arching
    above the surface is redrawn; such lines: ``tests/test_surface_piercing.py``)."""
    rng = np.random.default_rng(SEED)
    out, above = [], 0
    while len(out) < N_DRAWS:
        c = draw_line(rng)
        if c["w"] < 0 and oracle_top(c) > 0.0:
            above += 1
            continue
        c["oracle"] = moorpy_oracle(c)
        out.append(c)
    assert above < 0.05 * N_DRAWS, above
    return out


@pytest.fixture(scope="module")
def solved80(draws):
    return [SOLVE(*build(c, 80)) for c in draws]


def _resolved(c, n):
    _, _, h, lbot = c["oracle"]
    return lbot == 0.0 or h / abs(c["w"]) >= RESOLVED * c["length"] / n


def _errors(c, st):
    ta, tb, _, _ = c["oracle"]
    own = max(abs(float(st.tension_a) / ta - 1), abs(float(st.tension_b) / tb - 1))
    of_max = max(abs(float(st.tension_a) - ta), abs(float(st.tension_b) - tb)) / max(ta, tb)
    return own, of_max


def test_draws_cover_every_regime(draws):
    kinds = {c["kind"] for c in draws}
    regimes = {c["regime"] for c in draws}
    assert kinds == {"chain", "wire", "polyester", "buoyant"}
    assert regimes == {"grounded", "suspended", "taut", "straight", "floating"}
    depths = np.array([c["depth"] for c in draws])
    assert depths.min() < 30 and depths.max() > 1500
    grounded = [c for c in draws if c["oracle"][3] > 0]
    short = [c for c in grounded if c["oracle"][2] / abs(c["w"]) < c["length"] / 80]
    assert len(grounded) > 60 and len(short) >= 5  # H/w below one segment is drawn


def test_every_drawn_line_converges(draws, solved80):
    iters = np.array([int(st.iterations) for st in solved80])
    failed = [(i, c["kind"], c["regime"], float(st.max_residual))
              for i, (c, st) in enumerate(zip(draws, solved80)) if not bool(st.converged)]
    assert not failed, failed
    eps = np.finfo(float).eps
    for c, st in zip(draws, solved80):
        r = np.asarray(st.positions)
        assert np.all(np.isfinite(r))
        # force imbalance below 1e-6 of the tension, or at float64's resolution of
        # the positions (light short lines: EA/l · eps · |r| exceeds it)
        floor = 1600 * eps * c["ea"] / (c["length"] / 80) * max(np.abs(r).max(), c["length"])
        tmax = max(float(np.max(np.abs(st.tensions))), 1.0)
        assert float(st.max_residual) <= max(1e-6 * tmax, floor)
    print(f"\n{len(draws)} lines: Newton iterations mean {iters.mean():.1f}, max {iters.max()}")
    assert iters.max() < 500  # none ran into the iteration limit


def test_resolved_lines_agree_with_moorpy_at_80_segments(draws, solved80):
    errs = [(_errors(c, st)[0], i, c["kind"], c["regime"])
            for i, (c, st) in enumerate(zip(draws, solved80)) if _resolved(c, 80)]
    assert len(errs) > 100
    worst = max(errs)
    print(f"\nresolved at 80 segments: {len(errs)} lines, worst end-tension error {worst[0]:.2e}")
    assert worst[0] < 5e-4, worst


def test_underresolved_touchdowns_converge_with_segments(draws, solved80):
    """Where H/w is below RESOLVED segments the error is the touchdown's
    discretisation: ≤ 2e-2 of the largest tension at 80 segments, and it falls
    with refinement (at 320 segments ≤ 2e-3, typically 4× smaller)."""
    idx = [i for i, c in enumerate(draws) if not _resolved(c, 80)]
    assert len(idx) >= 20
    e80 = np.array([_errors(draws[i], solved80[i])[1] for i in idx])
    e320 = []
    for i in idx:
        st = SOLVE(*build(draws[i], 320))
        assert bool(st.converged), i
        e320.append(_errors(draws[i], st)[1])
    e320 = np.array(e320)
    ratio = np.median(e320 / np.maximum(e80, 1e-12))
    print(f"\nunder-resolved touchdowns: {len(idx)} lines, worst error / max tension "
          f"{e80.max():.2e} at 80 segments, {e320.max():.2e} at 320 (median ratio {ratio:.2f})")
    assert e80.max() < 2e-2, e80.max()
    assert e320.max() < 2e-3, e320.max()
    assert ratio < 0.35, ratio


@pytest.mark.parametrize("n", [3, 10, 400])
def test_drawn_lines_converge_at_any_segment_count(draws, n):
    for i, c in enumerate(draws[:40]):
        st = SOLVE(*build(c, n))
        assert bool(st.converged), (n, i, c["kind"], c["regime"])
        # the ends carry the wet weight not resting on the bed, whatever the resolution
        total = np.asarray(st.force_a + st.force_b)
        assert np.all(np.isfinite(total))


def test_seabed_friction_does_not_change_statics(draws, solved80):
    """Statics has no friction (node velocities are zero, as in MoorDyn): a bed with
    friction gives the same equilibrium, and converges as well."""
    for i, c in enumerate(draws[:30]):
        st = SOLVE(*build(c, 80, friction=True))
        assert bool(st.converged), i
        ref = solved80[i]
        assert float(st.tension_b) == pytest.approx(float(ref.tension_b), rel=1e-9, abs=1e-6)


def test_pile_up_gives_an_answer():
    """MoorPy's pile-up case (length > span + height): the excess lies slack on the
    bed; the fairlead carries the hanging weight w·h (as MoorPy's profile type 4)."""
    c = dict(kind="chain", regime="pile", d=0.2, m=500.0, ea=2e9, depth=300.0, length=890.0,
             ra=np.array([-400.0, 0.0, -300.0]), rb=np.array([0.0, 0.0, 0.0]))
    c["w"] = (c["m"] - RHO * np.pi * c["d"] ** 2 / 4) * G
    st = SOLVE(*build(c, 80))
    assert bool(st.converged)
    _, tb, _, _ = moorpy_oracle(c)
    assert float(st.tension_b) == pytest.approx(c["w"] * 300.0, rel=2.5e-2)
    assert float(st.tension_b) == pytest.approx(tb, rel=2.5e-2)
    assert float(st.tension_a) < 1e-3 * tb


# ------------------------------------------------ the reported statics (method="auto")


@pytest.mark.parametrize("n", [80, 3, 400])
def test_reported_statics_agree_with_moorpy_for_every_drawn_line(draws, n):
    """Every drawn line, every regime, any touchdown sharpness: within 5e-4 of MoorPy's
    end tensions (measured: 7e-11 worst at 80 segments, 0 fallbacks to the FEM)."""
    sample = draws if n == 80 else draws[::5]
    errs = []
    for i, c in enumerate(sample):
        line, env = build(c, n)
        st = AUTO(line, env)
        assert bool(st.converged), (n, i, c["kind"], c["regime"])
        errs.append((_errors(c, st)[0], i, c["kind"], c["regime"]))
        # the nodes lie on the line: unstretched spacing times (1 + strain) apart
        seg = np.linalg.norm(np.diff(np.asarray(st.positions), axis=0), axis=1)
        stretch = 1 + np.asarray(st.tensions) / c["ea"]
        assert np.all(seg <= c["length"] / n * stretch * (1 + 1e-9))
    worst = max(errs)
    print(f"\nreported statics at {n} segments: {len(errs)} lines, worst error {worst[0]:.2e}")
    assert worst[0] < 5e-4, worst


def test_reported_statics_falls_back_to_the_fem_where_no_catenary_applies():
    """Both ends above the bed with a sag that would pass under it (the line rests on
    the bed in between), and the pile-up: the catenary has no solution there, so the
    reported statics is the converged FEM equilibrium."""
    d, m, ea = 0.15, 400.0, 1.5e9
    c = dict(kind="chain", regime="floating", d=d, m=m, ea=ea, depth=100.0, length=600.0,
             ra=np.array([0.0, 0.0, -60.0]), rb=np.array([400.0, 0.0, -60.0]))
    c["w"] = (m - RHO * np.pi * d * d / 4) * G
    line, env = build(c, 60)
    st, fem = AUTO(line, env), SOLVE(line, env)
    assert bool(st.converged)
    np.testing.assert_allclose(np.asarray(st.positions), np.asarray(fem.positions), atol=1e-9)
    assert float(np.min(np.asarray(st.positions)[:, 2])) < -99.0  # it does rest on the bed
    pile = dict(c, ra=np.array([-400.0, 0.0, -300.0]), rb=np.array([0.0, 0.0, 0.0]),
                depth=300.0, length=890.0)
    line, env = build(pile, 80)
    st = AUTO(line, env)
    assert bool(st.converged)
    assert float(st.tension_b) == pytest.approx(float(SOLVE(line, env).tension_b), rel=1e-12)


def test_reported_statics_keeps_the_fem_for_what_the_catenary_does_not_model():
    """A current: ``auto`` is the FEM, and
    ``method="catenary"`` is refused with a message naming what it needs."""
    c = dict(kind="chain", regime="grounded", d=0.1, m=200.0, ea=8e8, depth=100.0,
             length=400.0, ra=np.array([-350.0, 0.0, -100.0]), rb=np.array([0.0, 0.0, -10.0]))
    c["w"] = (c["m"] - RHO * np.pi * c["d"] ** 2 / 4) * G
    line, env = build(c, 40)
    env = eqx.tree_at(lambda e: e.current, env, mj.UniformCurrent([0.5, 0.0, 0.0]),
                      is_leaf=lambda x: x is None)
    auto, fem = AUTO(line, env), SOLVE(line, env)
    assert float(auto.tension_b) == float(fem.tension_b)
    with pytest.raises(ValueError, match="catenary.*LinearEA"):
        solve_line_statics(line, env, method="catenary")
    with pytest.raises(ValueError, match="method must be one of"):
        solve_line_statics(line, env, method="exact")


def test_reported_statics_treats_only_a_negligible_bending_stiffness_as_a_cable():
    """EI = 0.8 N·m² on a chain (MoorDyn decks' placeholder; bending length ~mm) keeps
    the catenary; a stiff beam (bending length comparable to the line) gets the FEM
    with bending."""
    c = dict(kind="chain", regime="grounded", d=0.1, m=200.0, ea=8e8, depth=100.0,
             length=400.0, ra=np.array([-350.0, 0.0, -100.0]), rb=np.array([0.0, 0.0, -10.0]))
    c["w"] = (c["m"] - RHO * np.pi * c["d"] ** 2 / 4) * G
    c["oracle"] = moorpy_oracle(c)
    line, env = build(c, 20)
    for ei, exact in ((0.8, True), (5e7, False)):
        bent = eqx.tree_at(lambda ln: ln.line_type.ei, line, np.float64(ei),
                           is_leaf=lambda x: x is None)
        auto, fem = AUTO(bent, env), SOLVE(bent, env)
        assert bool(auto.converged)
        if exact:
            assert _errors(c, auto)[0] < 1e-9
        else:
            assert float(auto.tension_b) == float(fem.tension_b)


@eqx.filter_jit
def _upper_force(line, env, upper, d):
    """The force [N] on the line's higher end (``upper`` 1.0: end B, 0.0: end A)
    with that end moved by ``d`` [m] (one program for both orientations)."""
    moved = eqx.tree_at(lambda li: (li.end_a, li.end_b), line,
                        (mj.FixedEnd(line.end_a.position(0.0) + (1.0 - upper) * d),
                         mj.FixedEnd(line.end_b.position(0.0) + upper * d)))
    st = solve_line_statics(moved, env, throw=False)
    return jnp.where(upper > 0.5, st.force_b, st.force_a)


@eqx.filter_jit
def _upper_stiffness(line, env, upper):
    return jax.jacfwd(lambda d: _upper_force(line, env, upper, d))(jnp.zeros(3))


def _stiffness_against_differences(line, env, c, h=1e-5):
    """(∂F/∂r of the higher end by ``jax.jacfwd``, its largest difference from
    central differences with step h [m], over the differences' largest entry
    or, where the force hardly depends on the position (a line piled on the
    bed, slack: no stiffness), over the geometric stiffness |F|/L of the line)."""
    upper = jnp.asarray(float(c["rb"][2] >= c["ra"][2]))
    k = np.asarray(_upper_stiffness(line, env, upper))
    fd = np.stack([(np.asarray(_upper_force(line, env, upper, h * e)) - np.asarray(_upper_force(line, env, upper, -h * e)))
                   / (2 * h) for e in np.eye(3)], axis=1)
    floor = np.linalg.norm(np.asarray(_upper_force(line, env, upper, np.zeros(3)))) / c["length"]
    return k, float(np.abs(k - fd).max() / max(np.abs(fd).max(), floor))


def test_derivatives_of_the_drawn_lines_equal_differences(draws):
    """Statics with implicit-function gradients, for every drawn line:
    ``jax.jacfwd`` of the force on the line's higher end with respect to its
    position (its 3x3 stiffness), at 20 segments, is finite and equals central
    differences within 1e-3 on every line. The linear statics stop at a force
    imbalance of about 1e-8 of the tension, which is noise in differences of
    1e-4 m on the soft lines, and the taut ones curve within 1e-3 m, so each line
    takes the better of h = 1e-3 and 1e-4 m (measured: worst 1.7e-4, draw 162
    (floating); 7.9e-4 and 1.4e-3 at one step alone). The lines piled on the
    bed at 20 segments (draws 47, 92: a slack grounded segment) have no
    horizontal stiffness, and their derivative is zero as their differences are."""
    errors = []
    for c in draws:
        line, env = build(c, 20)
        both = [_stiffness_against_differences(line, env, c, h) for h in (1e-3, 1e-4)]
        assert all(np.all(np.isfinite(k)) for k, _ in both)
        errors.append(min(err for _, err in both))
    errors = np.array(errors)
    worst = int(np.argmax(errors))
    print(f"\nworst {errors[worst]:.2e} (draw {worst}, {draws[worst]['regime']}), median {np.median(errors):.2e}")
    assert errors.max() < 1e-3, errors.max()
