"""Finite-element statics: accuracy against analytic/MoorPy catenaries, invariances,
implicit-function gradients, fairlead stiffness, line regimes and bad input.

Compilation is the cost here, so every solve goes through a few module-level
``eqx.filter_jit`` wrappers: a wrapper compiles once per line *structure* (segment
count, which optional terms exist) and is then reused for every end position,
length or stiffness (those are array leaves).
"""

from __future__ import annotations

from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from moorpy.Catenary import catenary as moorpy_catenary

import moorjax as mj
from moorjax.io import build_scene, read_deck
from moorjax.statics.catenary import catenary_line_forces
from moorjax.statics.fem import fairlead_stiffness, solve_line_statics

DATA = Path(__file__).parent / "data"

SOLVE = eqx.filter_jit(solve_line_statics)
GRAD_TB = eqx.filter_jit(eqx.filter_grad(lambda line, env: solve_line_statics(line, env).tension_b))
STIFFNESS = eqx.filter_jit(fairlead_stiffness)

# MoorPy values from the project's reference set (80 segments of moorjax must match)
REF = {
    "A": dict(tension_b=911089.02, tension_a=736938.85, grounded=134.78553),
    "B": dict(tension_b=49977.543, tension_a=50560.213),
}


# ----------------------------------------------------------------- helpers


def with_ends(line, ra, rb):
    """The same line (same structure: no recompilation) between new fixed ends."""
    line = eqx.tree_at(lambda ln: ln.end_a, line, mj.FixedEnd(ra))
    return eqx.tree_at(lambda ln: ln.end_b, line, mj.FixedEnd(rb))


def ends(line):
    return np.asarray(line.end_a.position(0.0)), np.asarray(line.end_b.position(0.0))


def wet_weight(line, env):
    return float(line.line_type.wet_weight(env.rho, env.g))


def moorpy_tensions(line, env):
    """(T_A, T_B, grounded length) from MoorPy's catenary; end A must be the lower end."""
    ra, rb = ends(line)
    assert ra[2] <= rb[2]
    xf = float(np.hypot(*(rb - ra)[:2]))
    zf = float(rb[2] - ra[2])
    on_bed = env.seabed is not None and abs(ra[2] + float(env.depth)) < 1e-9
    cb = 0.0 if on_bed else -(ra[2] + float(env.depth))  # CB < 0: seabed this far below A
    fah, fav, fbh, fbv, info = moorpy_catenary(
        xf,
        zf,
        float(line.length),
        float(line.line_type.axial.nominal_ea()),
        wet_weight(line, env),
        CB=cb,
        Tol=1e-10,
        MaxIter=200,
    )
    return float(np.hypot(fah, fav)), float(np.hypot(fbh, fbv)), float(info["LBot"])


def rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def _f(x):
    """A float64 array leaf that is not weakly typed (a weak type would recompile)."""
    return jnp.asarray(x, dtype=float)


def _deck_case(name, segments=80):
    scene = build_scene(read_deck(DATA / f"case_{name}.dat"), segments=segments)
    assert len(scene.lines) == 1
    return scene.lines[0], scene.env


def retarget(line, env, *, d, m, ea, length, ra, rb, depth):
    """A new line/environment with the *structure* of ``line``/``env``, so that solves
    reuse the compilation of the deck case (drag, damping and added mass in the deck
    line type play no role in statics)."""
    line = eqx.tree_at(
        lambda ln: (ln.line_type.diameter, ln.line_type.mass_per_length, ln.line_type.axial.ea, ln.length),
        line,
        (_f(d), _f(m), _f(ea), _f(length)),
    )
    return with_ends(line, ra, rb), eqx.tree_at(lambda e: e.depth, env, _f(depth))


# Fully suspended line, no seabed (built on case B's structure: no seabed term)
SUSP = dict(ea=384.243e6, d=0.09, m=77.7066, length=700.0, ra=(-600.0, 0.0, -250.0), rb=(0.0, 0.0, -20.0))


def suspended_line(n):
    """(line, env) of the suspended case at n segments."""
    line, env = _deck_case("B", n)
    assert env.seabed is None
    return retarget(line, env, d=SUSP["d"], m=SUSP["m"], ea=SUSP["ea"], length=SUSP["length"],
                    ra=SUSP["ra"], rb=SUSP["rb"], depth=500.0)


def heavy_chain(anchor_x, case):
    """Chain-like heavy line (d 0.2 m, 200 kg/m, EA 2 GN, L 400 m) in 150 m of water,
    built on case A's structure (seabed contact)."""
    line, env = case["A"]
    return retarget(line, env, d=0.2, m=200.0, ea=2e9, length=400.0,
                    ra=(-anchor_x, 0.0, -150.0), rb=(0.0, 0.0, -10.0), depth=150.0)


@pytest.fixture(scope="module")
def case():
    """Lines and environments of reference cases A and B at 80 segments."""
    return {name: _deck_case(name) for name in ("A", "B")}


@pytest.fixture(scope="module")
def solved(case):
    return {name: SOLVE(*case[name]) for name in case}


@pytest.fixture(scope="module")
def susp80():
    line, env = suspended_line(80)
    return line, env, SOLVE(line, env)


# ------------------------------------------------------------ accuracy


@pytest.mark.slow
def test_converges_to_analytic_catenary_at_second_order(susp80):
    line80, env, st80 = susp80
    ra, rb = ends(line80)
    w = wet_weight(line80, env)
    sol, fa_exact, fb_exact = catenary_line_forces(
        jnp.asarray(ra), jnp.asarray(rb), SUSP["length"], SUSP["ea"], w, seabed=False
    )
    assert bool(sol.converged) and float(sol.grounded_length) == 0.0
    ns = [20, 40, 80]
    err_b, err_a = [], []
    for n in ns:
        st = st80 if n == 80 else SOLVE(*suspended_line(n))
        assert bool(st.converged)
        err_b.append(rel(st.force_b, fb_exact))
        err_a.append(rel(st.force_a, fa_exact))
    order_b = -np.polyfit(np.log(ns), np.log(err_b), 1)[0]
    order_a = -np.polyfit(np.log(ns), np.log(err_a), 1)[0]
    assert 1.8 < order_b < 2.3, (err_b, order_b)
    assert 1.8 < order_a < 2.3, (err_a, order_a)
    assert err_b[-1] < 1e-4, err_b
    assert err_a[-1] < 2e-4, err_a
    assert err_b[0] > err_b[1] > err_b[2]


def test_suspended_shape_matches_analytic_profile(susp80):
    """Node positions lie on the analytic catenary at their unstretched arc length."""
    from moorjax.statics.catenary import catenary_nodes

    line, env, st = susp80
    ra, rb = ends(line)
    w = wet_weight(line, env)
    sol, _, _ = catenary_line_forces(jnp.asarray(ra), jnp.asarray(rb), SUSP["length"], SUSP["ea"], w, seabed=False)
    s = line.segment_length * jnp.arange(81)
    exact = np.asarray(catenary_nodes(sol, jnp.asarray(ra), jnp.asarray(rb), s))
    pos = np.asarray(st.positions)
    dev = np.abs(pos - exact).max()
    assert dev < 0.05, dev  # 5 cm on a 700 m line at 80 segments
    np.testing.assert_array_equal(pos[[0, -1]], np.stack([ra, rb]))


@pytest.mark.parametrize("name", ["A", "B"])
def test_reference_cases_match_moorpy(case, solved, name):
    line, env = case[name]
    st = solved[name]
    assert bool(st.converged)
    ta, tb, lbot = moorpy_tensions(line, env)
    ref = REF[name]
    # the stored reference numbers are MoorPy's: the live MoorPy must reproduce them
    assert tb == pytest.approx(ref["tension_b"], rel=1e-5)
    assert ta == pytest.approx(ref["tension_a"], rel=1e-5)
    for t_live, t_ref, t_fe in ((ta, ref["tension_a"], st.tension_a), (tb, ref["tension_b"], st.tension_b)):
        assert float(t_fe) == pytest.approx(t_ref, rel=5e-4)
        assert float(t_fe) == pytest.approx(t_live, rel=5e-4)
    assert float(st.tension_b) == pytest.approx(float(jnp.linalg.norm(st.force_b)), rel=1e-14)
    if name == "A":
        assert lbot == pytest.approx(ref["grounded"], abs=1e-3)
        assert abs(float(st.grounded_length) - ref["grounded"]) < 1.0
        assert abs(float(st.grounded_length) - lbot) < 1.0
    else:
        assert float(st.grounded_length) == 0.0


def test_case_a_touchdown_and_seabed(case, solved):
    """Grounded nodes rest on the seabed (penetration = w/(kBot·d)), the rest are above it."""
    line, env = case["A"]
    st = solved["A"]
    z = np.asarray(st.positions[:, 2])
    depth = float(env.depth)
    w = wet_weight(line, env)
    d = float(line.line_type.diameter)
    pen_expected = w / (float(env.seabed.stiffness) * d)  # static penetration of a resting node
    s = float(line.segment_length) * np.arange(81)
    lbot = REF["A"]["grounded"]
    on_bed = (s < lbot - 15.0) & (s > 0)
    above = s > lbot + 15.0
    np.testing.assert_allclose(z[on_bed], -depth - pen_expected, rtol=0, atol=0.1 * pen_expected)
    assert np.all(z[above] > -depth)
    # without friction the grounded chain carries the anchor's horizontal tension
    tens = np.asarray(st.tensions)
    n_bed = int(np.sum(on_bed))
    np.testing.assert_allclose(tens[:n_bed], float(st.force_a[0]), rtol=1e-3)


@pytest.mark.parametrize("name", ["susp", "B"])
def test_end_forces_balance_wet_weight(case, solved, susp80, name):
    """Without seabed contact the ends carry the whole wet weight: F_A + F_B = −w·L·e_z."""
    line, env, st = susp80 if name == "susp" else (*case[name], solved[name])
    total = np.asarray(st.force_a + st.force_b)
    w_l = wet_weight(line, env) * float(line.length)
    np.testing.assert_allclose(total, [0.0, 0.0, -w_l], rtol=0, atol=1e-6 * float(st.tension_b))
    assert float(st.max_residual) < 1e-6 * float(st.tension_b)


# ------------------------------------------------------------ invariances


def _base(name, case, solved, susp80):
    if name == "susp":
        return susp80
    if name == "hang":
        # a suspended heavy line whose anchor sits on the seabed: the line leaves it
        # upwards (MoorPy: no grounded length, VA ≈ 0.08·HA), built on case A's
        # structure so that its gradients reuse case A's compilations
        line, env = heavy_chain(370.0, case)
        return line, env, None
    return (*case[name], solved[name])


@pytest.mark.parametrize("name", ["susp", "A", "B"])
def test_swapping_ends_swaps_forces(case, solved, susp80, name):
    line, env, st = _base(name, case, solved, susp80)
    ra, rb = ends(line)
    sw = SOLVE(with_ends(line, rb, ra), env)
    assert bool(sw.converged)
    scale = float(st.tension_b)
    np.testing.assert_allclose(np.asarray(sw.force_a), np.asarray(st.force_b), rtol=0, atol=1e-8 * scale)
    np.testing.assert_allclose(np.asarray(sw.force_b), np.asarray(st.force_a), rtol=0, atol=1e-8 * scale)
    assert float(sw.tension_a) == pytest.approx(float(st.tension_b), rel=1e-8)
    assert float(sw.tension_b) == pytest.approx(float(st.tension_a), rel=1e-8)
    np.testing.assert_allclose(np.asarray(sw.positions), np.asarray(st.positions)[::-1], rtol=0, atol=1e-6)
    np.testing.assert_allclose(np.asarray(sw.tensions), np.asarray(st.tensions)[::-1], rtol=1e-8)
    assert float(sw.grounded_length) == pytest.approx(float(st.grounded_length), rel=1e-8, abs=1e-8)


def _rot(deg):
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


TRANSFORMS = {
    "mirror_y": np.diag([1.0, -1.0, 1.0]),
    "mirror_x": np.diag([-1.0, 1.0, 1.0]),
    "rot90": _rot(90.0),
    "rot-127": _rot(-127.0),
}


@pytest.fixture(scope="module")
def rotated_A(case):
    """Case A turned 30° about z, so that both horizontal components are non-zero."""
    line, env = case["A"]
    ra, rb = ends(line)
    q = _rot(30.0)
    line = with_ends(line, q @ ra, q @ rb)
    return line, env, SOLVE(line, env)


@pytest.mark.parametrize("tname", sorted(TRANSFORMS))
def test_mirror_and_rotation_about_z_rotate_forces(rotated_A, tname):
    line, env, st = rotated_A
    q = TRANSFORMS[tname]
    ra, rb = ends(line)
    st2 = SOLVE(with_ends(line, q @ ra, q @ rb), env)
    assert bool(st2.converged)
    scale = float(st.tension_b)
    np.testing.assert_allclose(np.asarray(st2.force_a), q @ np.asarray(st.force_a), rtol=0, atol=1e-8 * scale)
    np.testing.assert_allclose(np.asarray(st2.force_b), q @ np.asarray(st.force_b), rtol=0, atol=1e-8 * scale)
    np.testing.assert_allclose(np.asarray(st2.positions), np.asarray(st.positions) @ q.T, rtol=0, atol=1e-6)
    assert float(st2.tension_b) == pytest.approx(scale, rel=1e-8)
    assert float(st2.grounded_length) == pytest.approx(float(st.grounded_length), rel=1e-8)
    # the horizontal force on the fairlead points from it towards the anchor
    horiz = np.asarray(st2.force_b[:2])
    towards_anchor = (q @ ra - q @ rb)[:2]
    cos = horiz @ towards_anchor / np.linalg.norm(horiz) / np.linalg.norm(towards_anchor)
    assert cos == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize(
    "name, shift",
    [
        ("A", (123.0, -45.0, 0.0)),
        ("B", (123.0, -45.0, 0.0)),
        ("susp", (123.0, -45.0, 0.0)),
        ("susp", (0.0, 0.0, -30.0)),  # no seabed: vertical shifts do not matter either
    ],
)
def test_translation_leaves_tensions_unchanged(case, solved, susp80, name, shift):
    line, env, st = _base(name, case, solved, susp80)
    ra, rb = ends(line)
    d = np.asarray(shift)
    st2 = SOLVE(with_ends(line, ra + d, rb + d), env)
    assert float(st2.tension_b) == pytest.approx(float(st.tension_b), rel=1e-8)
    assert float(st2.tension_a) == pytest.approx(float(st.tension_a), rel=1e-8)
    np.testing.assert_allclose(np.asarray(st2.force_b), np.asarray(st.force_b), rtol=0, atol=1e-8 * float(st.tension_b))
    np.testing.assert_allclose(np.asarray(st2.positions), np.asarray(st.positions) + d, rtol=0, atol=1e-6)


# ------------------------------------------------------------ gradients

GRAD_PARAMS = {
    # name: (getter on the line, central-FD step relative to the value)
    "EA": (lambda ln: ln.line_type.axial.ea, 1e-5),  # weak sensitivity: a larger step
    "length": (lambda ln: ln.length, 1e-6),
    "mass_per_length": (lambda ln: ln.line_type.mass_per_length, 1e-6),
    "diameter": (lambda ln: ln.line_type.diameter, 1e-6),
}


def _fd(f, x0, h):
    return (f(x0 + h) - f(x0 - h)) / (2 * h)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["hang", "A"])
def test_tension_gradients_match_finite_differences(case, solved, name):
    """Suspended ("hang") and partly grounded (A) lines."""
    line, env, _ = _base(name, case, solved, None)
    g = GRAD_TB(line, env)
    if name == "hang":
        st = SOLVE(line, env)
        assert float(st.grounded_length) == 0.0
        assert np.all(np.asarray(st.positions[1:, 2]) > -float(env.depth))
        assert float(st.force_a[2]) > 0  # the line lifts off its anchor
    for pname, (get, step) in GRAD_PARAMS.items():
        x0 = float(get(line))
        ad = float(get(g))

        def tb(x, get=get):
            return float(SOLVE(eqx.tree_at(get, line, _f(x)), env).tension_b)

        fd = _fd(tb, x0, step * x0)
        assert np.isfinite(ad)
        assert ad == pytest.approx(fd, rel=1e-5), (pname, ad, fd)
    # physical signs: a heavier, stiffer or shorter line pulls harder at the fairlead
    assert float(g.line_type.mass_per_length) > 0
    assert float(g.line_type.axial.ea) > 0
    assert float(g.length) < 0

    # end-B position in three random directions
    rng = np.random.default_rng(7 if name == "hang" else 11)
    ra, rb = ends(line)
    gb = np.asarray(g.end_b.point)
    assert np.all(np.isfinite(gb))
    for _ in range(3):
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)

        def tb_dir(a):
            return float(SOLVE(with_ends(line, ra, rb + a * u), env).tension_b)

        fd = _fd(tb_dir, 0.0, 1e-6 * np.linalg.norm(rb - ra))
        assert gb @ u == pytest.approx(fd, rel=1e-5), (u, gb @ u, fd)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["hang", "A"])
def test_fairlead_stiffness_matches_finite_differences(case, solved, name):
    """Suspended and partly grounded lines (both on case A's structure: one compilation)."""
    line, env, _ = _base(name, case, solved, None)
    k = np.asarray(STIFFNESS(line, env))
    assert k.shape == (3, 3) and np.all(np.isfinite(k))
    ra, rb = ends(line)
    h = 1e-6 * np.linalg.norm(rb - ra)
    k_fd = np.zeros((3, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = h
        fp = np.asarray(SOLVE(with_ends(line, ra, rb + e), env).force_b)
        fm = np.asarray(SOLVE(with_ends(line, ra, rb - e), env).force_b)
        k_fd[:, j] = -(fp - fm) / (2 * h)
    np.testing.assert_allclose(k, k_fd, rtol=1e-5, atol=1e-5 * np.abs(k).max())
    # pulling the fairlead away from the anchor (+x here) stiffens the line, and the
    # in-plane (x, z) and out-of-plane (y) responses decouple
    assert k[0, 0] > 0
    np.testing.assert_allclose(k[1, [0, 2]], 0.0, atol=1e-9 * np.abs(k).max())
    np.testing.assert_allclose(k[[0, 2], 1], 0.0, atol=1e-9 * np.abs(k).max())
    # out of plane: a pendulum-like restoring stiffness, positive
    assert k[1, 1] > 0


# ------------------------------------------------------------ regimes


def test_suspended_regime(susp80):
    line, env, st = susp80
    assert bool(st.converged)
    z = np.asarray(st.positions[:, 2])
    assert np.all(z > -float(env.depth))
    assert float(st.grounded_length) == 0.0
    assert np.all(np.asarray(st.tensions) > 0)
    # a heavy line sags below its chord
    ra, rb = ends(line)
    chord_z = ra[2] + np.linspace(0, 1, 81) * (rb[2] - ra[2])
    assert np.all(z[1:-1] < chord_z[1:-1])


def test_partly_grounded_regime(solved):
    st = solved["A"]
    assert bool(st.converged)
    assert 100.0 < float(st.grounded_length) < 170.0
    # the anchor force is nearly horizontal: the chain near it lies on the seabed
    fa = np.asarray(st.force_a)
    assert abs(fa[2]) < 0.02 * abs(fa[0])


def test_taut_buoyant_regime(case, solved):
    line, env = case["B"]
    st = solved["B"]
    assert bool(st.converged)
    assert wet_weight(line, env) < 0  # buoyant
    assert env.seabed is None  # a scene of buoyant lines gets no seabed term
    strains = np.linalg.norm(np.diff(np.asarray(st.positions), axis=0), axis=1) / float(line.segment_length) - 1
    assert np.all(strains > 0)  # taut everywhere
    assert np.all(np.asarray(st.tensions) > 0)
    # a buoyant line bows above its chord, and its tension is largest at the anchor
    ra, rb = ends(line)
    z = np.asarray(st.positions[:, 2])
    chord_z = ra[2] + np.linspace(0, 1, 81) * (rb[2] - ra[2])
    assert np.all(z[1:-1] > chord_z[1:-1])
    assert float(st.tension_a) > float(st.tension_b)


@pytest.mark.parametrize(
    "anchor_x, grounded",
    [
        (380.0, False),  # chord 405 m > 400 m: taut, ~25 MN
        (340.0, True),  # 164 m on the seabed
        (320.0, True),  # 212 m on the seabed (stalled the damped Newton before the energy descent)
        (300.0, True),  # 238 m on the seabed
    ],
)
def test_heavy_chain_matches_moorpy(case, anchor_x, grounded):
    line, env = heavy_chain(anchor_x, case)
    try:
        st = SOLVE(line, env)
    except Exception as exc:  # noqa: BLE001 - report which geometry failed
        pytest.fail(f"heavy chain, anchor at x = -{anchor_x} m: {str(exc).splitlines()[0]}")
    assert bool(st.converged)
    ta, tb, lbot = moorpy_tensions(line, env)
    assert (lbot > 0) == grounded
    assert float(st.tension_b) == pytest.approx(tb, rel=5e-4)
    # the anchor tension of a mostly grounded chain is the small horizontal tension,
    # whose touchdown discretisation error is compared with the fairlead tension
    assert abs(float(st.tension_a) - ta) < (2e-3 * tb if grounded else 5e-4 * ta)
    assert float(st.grounded_length) == pytest.approx(lbot, abs=1.0)


@pytest.fixture(scope="module")
def far_seabed(case, susp80):
    """The suspended line again, in case A's structure: a seabed 250 m below end A."""
    line, env, st = susp80
    ra, rb = ends(line)
    line_a, env_a = case["A"]
    far, far_env = retarget(line_a, env_a, d=SUSP["d"], m=SUSP["m"], ea=SUSP["ea"], length=SUSP["length"],
                            ra=ra, rb=rb, depth=500.0)
    return st, SOLVE(far, far_env)


def test_far_seabed_does_not_change_solution(far_seabed):
    st, st2 = far_seabed
    assert bool(st2.converged)
    assert float(st2.grounded_length) == 0.0
    assert float(st2.tension_b) == pytest.approx(float(st.tension_b), rel=1e-9)
    np.testing.assert_allclose(np.asarray(st2.positions), np.asarray(st.positions), atol=1e-6)


def test_far_seabed_does_not_change_newton_cost(far_seabed):
    """The analytic-catenary start should be as good with a distant seabed as without."""
    st, st2 = far_seabed
    assert int(st2.iterations) <= int(st.iterations) + 5, (int(st2.iterations), int(st.iterations))


# ------------------------------------------------------------ bad input


@pytest.mark.parametrize("which", ["a", "b"])
def test_end_below_seabed_is_rejected(case, which):
    line, env = heavy_chain(340.0, case)
    ra, rb = ends(line)
    if which == "a":
        ra = ra + np.array([0.0, 0.0, -10.0])
    else:
        rb = np.array([0.0, 0.0, -200.0])
    with pytest.raises(ValueError, match="below the seabed") as info:
        solve_line_statics(with_ends(line, ra, rb), env)
    assert f"end {which.upper()}" in str(info.value)


def test_impossible_geometry_is_rejected(susp80):
    line, env, _ = susp80
    ra = np.array([-1200.0, 0.0, -250.0])  # chord ≈ 1221 m > 1.5 × 700 m
    with pytest.raises(ValueError, match="impossible geometry") as info:
        solve_line_statics(with_ends(line, ra, np.array(SUSP["rb"])), env)
    assert "700" in str(info.value)


@pytest.fixture(scope="module")
def one_step():
    """A 20-segment suspended line started from its (compressed) chord, one Newton step."""
    line, env = suspended_line(20)

    def run(throw):
        return eqx.filter_jit(
            lambda ln, e: solve_line_statics(ln, e, init=ln.straight_state(), max_steps=1, throw=throw)
        )(line, env)

    return run


def test_nonconverging_solve_reports_not_converged(one_step):
    st = one_step(False)
    assert not bool(st.converged)
    assert int(st.iterations) <= 3
    # whatever it returns, it is not presented as an equilibrium
    assert not float(st.max_residual) < 1e-6 * float(jnp.max(jnp.abs(st.tensions)))


def test_nonconverging_solve_raises_when_asked(one_step):
    with pytest.raises(Exception) as info:
        jax.block_until_ready(one_step(True))
    assert "did not converge" in str(info.value)
