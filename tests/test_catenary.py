"""Tests of the analytic elastic catenary (moorjax.statics.catenary), cross-checked with MoorPy."""

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from moorjax.statics.catenary import (  # noqa: E402
    catenary_line_forces,
    catenary_nodes,
    catenary_profile,
    raise_if_not_converged,
    solve_catenary,
)

moorpy_catenary = pytest.importorskip("moorpy.Catenary").catenary

RHO, G = 1025.0, 9.80665
W_A = (77.7066 - RHO * np.pi * 0.09**2 / 4) * G  # chain, sinks [N/m]
W_B = (10.8 - RHO * np.pi * 0.12**2 / 4) * G  # buoyant rope [N/m], < 0
CHORD_A = np.hypot(848.67, 250.0)

# name: (XF, ZF, L, EA, W, CB), MoorPy ProfileType expected
CASES = {
    "A_grounded": ((848.67, 250.0, 902.2, 384.243e6, W_A, 0.0), 2),
    "B_buoyant_taut": ((80.5168, 75.0, 110.0, 1.5e8, W_B, 0.0), 1),
    "suspended": ((830.0, 250.0, 870.0, 384.243e6, W_A, 0.0), 1),
    "friction_0.5": ((848.67, 250.0, 902.2, 384.243e6, W_A, 0.5), 2),
    "friction_1.0": ((848.67, 250.0, 902.2, 384.243e6, W_A, 1.0), 2),
    "friction_1.0_slack_anchor": ((700.0, 250.0, 902.2, 384.243e6, W_A, 1.0), 3),
    "friction_0.5_slack_anchor": ((700.0, 250.0, 902.2, 384.243e6, W_A, 0.5), 3),
    "taut_2pct_short": ((848.67, 250.0, 0.98 * CHORD_A, 384.243e6, W_A, 0.0), 1),
    "buoyant_slack": ((60.0, 75.0, 110.0, 1.5e8, W_B, 0.0), 1),
}


def _moorpy(args, nodes=0):
    out = moorpy_catenary(*args, Tol=1e-10, MaxIter=500, nNodes=max(nodes, 2), plots=int(nodes > 0))
    return out


def _close(a, b, rtol, scale=None):
    scale = abs(b) if scale is None else scale
    return abs(a - b) <= rtol * scale


def test_case_A_reference_values():
    sol = solve_catenary(848.67, 250.0, 902.2, 384.243e6, W_A, 0.0)
    assert bool(sol.converged)
    assert float(jnp.hypot(sol.HF, sol.VF)) == pytest.approx(911.09e3, rel=2e-5)
    assert float(sol.HF) == pytest.approx(736.94e3, rel=2e-5)
    assert float(sol.VF) == pytest.approx(535.73e3, rel=2e-5)
    assert float(sol.grounded_length) == pytest.approx(134.79, abs=0.01)
    assert float(sol.VA) == 0.0 and float(sol.HA) == pytest.approx(float(sol.HF), rel=1e-14)


def test_case_B_buoyant_reference_values():
    sol = solve_catenary(80.5168, 75.0, 110.0, 1.5e8, W_B, 0.0)
    assert bool(sol.converged) and float(sol.grounded_length) == 0.0
    assert float(jnp.hypot(sol.HF, sol.VF)) == pytest.approx(49.98e3, rel=1e-4)  # fairlead
    assert float(jnp.hypot(sol.HA, sol.VA)) == pytest.approx(50.56e3, rel=1e-4)  # anchor
    # buoyancy: the anchor carries more tension than the fairlead, VA - VF = -W L > 0
    assert float(sol.VA - sol.VF) == pytest.approx(-W_B * 110.0, rel=1e-12)


@pytest.mark.parametrize("name", list(CASES))
def test_against_moorpy(name):
    args, ptype = CASES[name]
    sol = solve_catenary(*args)
    fAH, fAV, fBH, fBV, info = _moorpy(args)
    assert info["ProfileType"] == ptype  # compare like with like
    assert bool(sol.converged) and float(sol.residual) < 1e-9
    T = float(jnp.hypot(sol.HF, sol.VF))
    for mine, ref in [(sol.HF, -fBH), (sol.VF, -fBV), (sol.HA, fAH), (sol.VA, fAV)]:
        assert _close(float(mine), ref, 1e-6, scale=max(abs(ref), 1e-3 * T)), (name, mine, ref)
    assert _close(float(sol.grounded_length), info["LBot"], 1e-6, scale=args[2])
    assert _close(float(sol.HF), -fBH, 1e-6) and _close(float(jnp.hypot(sol.HF, sol.VF)),
                                                         np.hypot(fBH, fBV), 1e-6)


@pytest.mark.parametrize("name", ["A_grounded", "friction_1.0_slack_anchor", "suspended",
                                  "B_buoyant_taut"])
def test_profile_against_moorpy(name):
    args, _ = CASES[name]
    sol = solve_catenary(*args)
    info = _moorpy(args, nodes=21)[4]
    s = jnp.asarray(info["s"])
    x, z, T = catenary_profile(sol, s)
    L, EA, CB = args[2], args[3], args[5]
    # MoorPy leaves the grounded part unstretched when CB = 0 (its XF equation does stretch it),
    # so there compare the seabed nodes with the exact x = s (1 + HF/EA) instead
    on_bed = np.asarray(s < sol.grounded_length) & (CB == 0)
    x_ref = np.where(on_bed, np.asarray(s) * (1.0 + float(sol.HF) / EA), info["X"])
    np.testing.assert_allclose(x, x_ref, rtol=0, atol=1e-6 * L)
    np.testing.assert_allclose(z, info["Z"], rtol=0, atol=1e-6 * L)
    np.testing.assert_allclose(T, info["Te"], rtol=0, atol=1e-6 * float(jnp.hypot(sol.HF, sol.VF)))


@pytest.mark.parametrize("name", list(CASES))
def test_profile_end_points_and_equilibrium(name):
    args, _ = CASES[name]
    XF, ZF, L, EA, W, CB = args
    sol = solve_catenary(*args)
    x, z, T = catenary_profile(sol, jnp.array([0.0, L]))
    assert abs(float(x[0])) < 1e-12 and abs(float(z[0])) < 1e-12
    assert abs(float(x[1]) - XF) < 1e-9 * L and abs(float(z[1]) - ZF) < 1e-9 * L
    assert _close(float(T[1]), float(jnp.hypot(sol.HF, sol.VF)), 1e-12)
    assert _close(float(T[0]), float(jnp.hypot(sol.HA, sol.VA)), 1e-12, scale=float(T[1]))
    # Independent check of the shape: along the line |dr/ds| = 1 + T/EA (Hooke) and the slope
    # dz/dx equals V(s)/H(s) with V(s) = VF - W (L - s) on the suspended part (equilibrium).
    LB = float(sol.grounded_length)
    f = np.linspace(0.01, 0.99, 8)
    s = np.concatenate([f * LB, LB + f * (L - LB)]) if LB > 0 else np.linspace(0.01, 0.99, 16) * L
    dxs, dzs, Ts = _slopes(sol, jnp.asarray(s))
    np.testing.assert_allclose(jnp.hypot(dxs, dzs), 1.0 + Ts / EA, rtol=1e-12)
    sus = s > LB
    V = sol.VF - W * (L - s)
    np.testing.assert_allclose((dzs * sol.HF)[sus], (V * dxs)[sus], rtol=1e-10,
                               atol=1e-10 * float(jnp.max(Ts)))
    np.testing.assert_allclose(dzs[~sus], 0.0, atol=1e-15)


@jax.jit
def _slopes(sol, s):
    """dx/ds, dz/ds [-] and tension [N] of the profile at arc lengths s."""
    d = [jax.vmap(jax.grad(lambda q, i=i: catenary_profile(sol, q)[i]))(s) for i in (0, 1)]
    return d[0], d[1], catenary_profile(sol, s)[2]


def test_friction_zone_on_seabed():
    args, _ = CASES["friction_1.0_slack_anchor"]
    XF, ZF, L, EA, W, CB = args
    sol = solve_catenary(*args)
    LB, HF = float(sol.grounded_length), float(sol.HF)
    s0 = LB - HF / (CB * W)  # beyond s0 from touchdown the grounded line carries no tension
    assert s0 > 0 and float(sol.HA) == 0.0
    _, z, T = catenary_profile(sol, jnp.array([0.3 * s0, 0.9 * s0, 0.5 * (s0 + LB), LB]))
    np.testing.assert_allclose(z, 0.0, atol=1e-15)
    np.testing.assert_allclose(T, [0.0, 0.0, 0.5 * HF, HF], rtol=1e-12, atol=1e-9 * HF)


def test_stiffness_matches_moorpy():
    args, _ = CASES["A_grounded"]
    def hv(XF, ZF):
        sol = solve_catenary(XF, ZF, *args[2:])
        return sol.HF, sol.VF

    x, z = jnp.asarray(args[0]), jnp.asarray(args[1])
    cols = [jax.jvp(hv, (x, z), t)[1] for t in ((1.0, 0.0), (0.0, 1.0))]
    K = np.array(cols).T  # K[i, j] = d(HF, VF)_i / d(XF, ZF)_j
    Kmp = _moorpy(args)[4]["stiffnessB"]
    np.testing.assert_allclose(K, Kmp, rtol=1e-6, atol=1e-6 * np.abs(Kmp).max())


@pytest.mark.parametrize("name", ["A_grounded", "friction_0.5", "friction_1.0_slack_anchor",
                                  "suspended", "B_buoyant_taut", "taut_2pct_short"])
def test_gradients_match_finite_differences(name):
    args, _ = CASES[name]
    theta0 = np.array(args[:5])

    def hf(theta):
        return solve_catenary(*theta, args[5], rtol=1e-14).HF

    grad = np.asarray(jax.grad(hf)(jnp.asarray(theta0)))
    def at(i, dx):
        t = theta0.copy()
        t[i] += dx
        return float(hf(t))

    # XF, L, EA, W: 5-point central differences, O(h^4); geometry needs small steps (taut lines
    # stiffen quickly), EA and W larger ones (HF is weakly sensitive, solver noise dominates)
    for i, rel in ((0, 1e-6), (2, 1e-6), (3, 1e-4), (4, 1e-4)):
        h = rel * abs(theta0[i])
        fd = (8 * (at(i, h) - at(i, -h)) - (at(i, 2 * h) - at(i, -2 * h))) / (12 * h)
        assert _close(grad[i], fd, 1e-6), (name, i, grad[i], fd)
    assert np.all(np.isfinite(grad))


def test_jit_and_batch_consistent():
    names = list(CASES)
    cols = [jnp.array([CASES[n][0][k] for n in names]) for k in range(6)]
    batch = solve_catenary(*cols)
    @jax.jit
    def one(*a):
        sol = solve_catenary(*a)
        return sol.HF, sol.converged

    for j, n in enumerate(names):
        ref = solve_catenary(*CASES[n][0])
        assert bool(batch.converged[j])
        assert _close(float(batch.HF[j]), float(ref.HF), 1e-10)
        assert _close(float(one(*CASES[n][0])[0]), float(ref.HF), 1e-10)
    # invalid values under jit cannot raise; they must be flagged instead
    args = list(CASES["A_grounded"][0])
    args[2] = -1.0
    assert not bool(one(*args)[1])


def test_near_neutral_and_mirror_symmetry():
    XF, ZF, L, EA = 80.0, 60.0, 99.5, 1e8
    exact = EA * (np.hypot(XF, ZF) / L - 1.0) * XF / np.hypot(XF, ZF)  # straight elastic bar
    for W in (0.0, 1e-9, -1e-9):
        sol = solve_catenary(XF, ZF, L, EA, W)
        assert bool(sol.converged) and _close(float(sol.HF), exact, 1e-8)
    slack = solve_catenary(XF, ZF, 110.0, EA, 1e-6, seabed=False)  # tiny weight, slack line
    assert bool(slack.converged) and 0 < float(slack.HF) < 1e-3
    # a buoyant line is the mirror image of a heavy one (without seabed contact)
    a = solve_catenary(60.0, 75.0, 110.0, 1.5e8, W_B)
    b = solve_catenary(60.0, -75.0, 110.0, 1.5e8, -W_B, seabed=False)
    assert _close(float(a.HF), float(b.HF), 1e-12) and _close(float(a.VF), -float(b.VF), 1e-12)


def test_vertical_line():
    sol = solve_catenary(0.0, 100.0, 99.0, 1e9, 500.0)
    assert bool(sol.converged) and float(sol.HF) < 1e-3
    assert _close(float(sol.VF), 1e9 * (100.0 / 99.0 - 1.0) + 0.5 * 500.0 * 99.0, 1e-6)


@pytest.mark.parametrize("kwargs,match", [
    (dict(L=0.0), r"L \(unstretched line length\).*m"),
    (dict(L=-5.0), r"L \(unstretched line length\).*-5.0 m.*> 0"),
    (dict(EA=0.0), r"EA \(axial stiffness\).*N.*> 0"),
    (dict(XF=-1.0), r"XF .*-1.0 m.*>= 0"),
    (dict(XF=float("nan")), r"XF .*not finite"),
    (dict(ZF=float("inf")), r"ZF .*not finite"),
    (dict(W=float("nan")), r"W .*N/m.*not finite"),
    (dict(CB=-0.2), r"CB .*>= 0"),
])
def test_bad_inputs_raise(kwargs, match):
    args = dict(XF=848.67, ZF=250.0, L=902.2, EA=384.243e6, W=W_A, CB=0.0)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        solve_catenary(**args)


def test_non_convergence_is_reported_not_nan():
    pile = solve_catenary(0.0, 50.0, 100.0, 1e9, 500.0)  # slack vertical chain: not modelled
    assert not bool(pile.converged)
    with pytest.raises(RuntimeError, match="did not converge"):
        raise_if_not_converged(pile)
    with pytest.raises(RuntimeError, match="did not converge"):
        solve_catenary(848.67, 250.0, 902.2, 384.243e6, W_A, max_steps=1, throw=True)
    short = solve_catenary(848.67, 250.0, 902.2, 384.243e6, W_A, max_steps=1)
    assert not bool(short.converged) and np.isfinite(float(short.HF))
    assert raise_if_not_converged(solve_catenary(*CASES["A_grounded"][0])).converged


def test_3d_forces_and_nodes():
    args, _ = CASES["A_grounded"]
    XF, ZF, L, EA, W, CB = args
    th = 0.7
    r_a = jnp.array([10.0, -20.0, -250.0])
    r_b = r_a + jnp.array([XF * np.cos(th), XF * np.sin(th), ZF])
    sol, fa, fb = catenary_line_forces(r_a, r_b, L, EA, W)
    e = np.array([np.cos(th), np.sin(th), 0.0])
    np.testing.assert_allclose(fb, -float(sol.HF) * e - [0, 0, float(sol.VF)], rtol=1e-12, atol=1e-6)
    np.testing.assert_allclose(fa, float(sol.HA) * e + [0, 0, float(sol.VA)], rtol=1e-12, atol=1e-6)
    assert fb[2] < 0 and fa[0] * e[0] > 0  # fairlead pulled down, anchor pulled towards fairlead
    # swapping the ends swaps the forces (the lower end stays the anchor)
    _, fa2, fb2 = catenary_line_forces(r_b, r_a, L, EA, W)
    np.testing.assert_allclose(fa2, fb, rtol=1e-12)
    np.testing.assert_allclose(fb2, fa, rtol=1e-12)
    s = jnp.linspace(0.0, L, 5)
    pts = catenary_nodes(sol, r_a, r_b, s)
    assert pts.shape == (5, 3)
    np.testing.assert_allclose(pts[0], r_a, atol=1e-9)
    np.testing.assert_allclose(pts[-1], r_b, atol=1e-7)
    pts2 = catenary_nodes(sol, r_b, r_a, s)  # s measured from the first argument
    np.testing.assert_allclose(pts2[::-1], pts, atol=1e-7)
    # a suspended frictionless line: end forces balance its weight
    args, _ = CASES["suspended"]
    r_b = r_a + jnp.array([args[0], 0.0, args[1]])
    sol, fa, fb = catenary_line_forces(r_a, r_b, *args[2:])
    assert float(sol.grounded_length) == 0.0
    np.testing.assert_allclose(fa + fb, [0.0, 0.0, -args[4] * args[2]], atol=1e-6 * float(sol.HF))
    # gradients of 3D forces w.r.t. the fairlead position are finite
    _, dfb = jax.jvp(lambda x: catenary_line_forces(r_a, r_b.at[0].add(x), *args[2:])[2],
                     (0.0,), (1.0,))
    assert np.all(np.isfinite(dfb)) and dfb[0] < 0  # restoring horizontal stiffness
