"""Analytic 2D elastic catenary with seabed contact and Coulomb seabed friction.

The quasi-static line model of Irvine (1981) in the form of Jonkman (2007, NREL/TP-500-41958,
ch. 4), solved for the fairlead tension components (HF, VF) by a damped Newton iteration in
``(log HF, VF)`` and differentiated with the implicit-function theorem (``jax.custom_jvp``), so
gradients w.r.t. XF, ZF, L, EA, W, CB are exact derivatives of the converged solution.

Frame: end A ("anchor") at the origin, end B ("fairlead") at ``(XF, ZF)``, x horizontal from A
towards B, z up.  Units SI: lengths [m], forces [N], W [N/m] (wet weight per *unstretched* length,
W < 0 = buoyant), EA [N], CB [-].  HF, VF are the tension components at B (the line pulls B with
``(-HF, -VF)``); HA, VA at A (the line pulls A with ``(+HA, +VA)``).  Regimes:

* suspended: ``XF = HF/W [asinh(VF/HF) - asinh(VA/HF)] + HF L/EA``, ``VA = VF - W L``, HA = HF;
* partly grounded (``seabed=True``, W > 0, ZF >= 0, ``L_B = L - VF/W > 0``): the first ``L_B`` of
  the line lies on the seabed (z = 0); its tension rises linearly from 0 (or from HA) to HF at the
  touchdown point because of Coulomb friction ``CB W`` per metre; ``VA = 0``,
  ``HA = max(HF - CB W L_B, 0)``.

Differences of asinh / sqrt are evaluated in cancellation-free forms that contain no ``1/W``, so
the suspended model stays accurate (and differentiable) for tiny |W| and is exact at W = 0 when the
line is taut.  Limits (the result then has ``converged=False``, never a silent NaN): a slack line
with W = 0; slack lines whose excess length would have to pile up (XF + ZF < L for a chain on the
seabed, e.g. a slack vertical line; MoorPy's profile types 4/5); a slack line lying flat on the
seabed (ZF = 0).  Buoyant lines are never in contact (no sea-surface/ceiling contact), and with
W > 0 and ZF < 0 the line simply hangs below the anchor.  For XF -> 0 the iteration drives HF
towards 0 linearly (more steps, HF ~ tolerance-small).  Gradients (any order) are those of the
converged solution; they are meaningless where ``converged`` is False.  Float64 is required
(``import moorjax`` enables it).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from .._checks import check_finite, check_nonnegative, check_positive
from .._numerics import safe_unit

Array = jax.Array

__all__ = ["CatenarySolution", "solve_catenary", "catenary_profile", "raise_if_not_converged",
           "catenary_line_forces", "catenary_nodes"]


class CatenarySolution(eqx.Module):
    """Converged catenary state (all fields are arrays; broadcast shape of the inputs)."""

    HF: Array  # [N] horizontal tension at the fairlead (end B), > 0
    VF: Array  # [N] vertical tension at the fairlead; > 0: the line pulls B downward
    HA: Array  # [N] horizontal tension at the anchor (end A)
    VA: Array  # [N] vertical tension at the anchor; > 0: the line pulls A upward
    grounded_length: Array  # [m] unstretched length resting on the seabed (0 if suspended)
    converged: Array  # bool: inputs valid and end-point residual <= rtol * max(L, chord)
    XF: Array  # [m] horizontal fairlead offset from the anchor
    ZF: Array  # [m] vertical fairlead offset from the anchor
    L: Array  # [m] unstretched length
    EA: Array  # [N] axial stiffness
    W: Array  # [N/m] wet weight per unstretched length
    CB: Array  # [-] seabed friction coefficient
    residual: Array  # [m] max |end-point mismatch| of the returned (HF, VF)
    steps: Array  # Newton iterations used


def _asinhc(d):
    """asinh(d)/d, smooth through d = 0."""
    small = jnp.abs(d) < 1e-3
    ds = jnp.where(small, 1.0, d)
    d2 = d * d
    return jnp.where(small, 1.0 - d2 / 6.0 + 0.075 * d2 * d2, jnp.arcsinh(ds) / ds)


def _asinh_ratio(a, b, diff):
    """(asinh a - asinh b)/diff where ``diff = a - b`` is supplied without cancellation."""
    sa, sb = jnp.sqrt(1.0 + a * a), jnp.sqrt(1.0 + b * b)
    same = a * b > 0  # then a*sb - b*sa = (a^2 - b^2)/(a*sb + b*sa), denominator cannot vanish
    g_same = (a + b) / jnp.where(same, a * sb + b * sa, 1.0)
    nz = diff != 0  # opposite signs: a*sb - b*sa has no cancellation; diff = 0 only at a = b = 0
    g_opp = jnp.where(nz, (a * sb - b * sa) / jnp.where(nz, diff, 1.0), 1.0)
    g = jnp.where(same, g_same, g_opp)
    return g * _asinhc(diff * g)


def _suspended(H, V0, W, EA, sig):
    """Suspended segment of unstretched length ``sig`` [m] starting with tension (H, V0) [N].

    Returns the offsets x, z [m] of its far end and the tension magnitude there [N]."""
    b = V0 / H
    diff = W * sig / H
    a = b + diff
    sa, sb = jnp.sqrt(1.0 + a * a), jnp.sqrt(1.0 + b * b)
    x = sig * _asinh_ratio(a, b, diff) + H * sig / EA
    z = sig * (a + b) / (sa + sb) + (V0 * sig + 0.5 * W * sig * sig) / EA
    return x, z, H * sa


def _grounded(HF, LB, W, CB, EA, s):
    """Grounded part: stretched x [m] and tension [N] at arc length s in [0, LB] from the anchor."""
    cbw = CB * W
    HA = jnp.maximum(HF - cbw * LB, 0.0)
    slack = cbw * LB > HF  # tension vanishes on [0, s0], s0 = LB - HF/(CB W)
    s0 = jnp.where(slack, LB - HF / jnp.where(slack, cbw, 1.0), 0.0)
    T = jnp.maximum(HF - cbw * (LB - s), 0.0)
    return s + 0.5 * (T + HA) * jnp.maximum(s - s0, 0.0) / EA, T


def _ends(HF, VF, p, seabed):
    """Grounded length [m], VA [N], HA [N] implied by the fairlead tension (HF, VF)."""
    XF, ZF, L, EA, W, CB = p
    grounded = (W > 0) & (VF < W * L) & (ZF >= 0) & seabed
    LB = jnp.where(grounded, L - VF / jnp.where(grounded, W, 1.0), 0.0)
    VA = jnp.where(grounded, 0.0, VF - W * L)
    HA = jnp.where(grounded, jnp.maximum(HF - CB * W * LB, 0.0), HF)
    return LB, VA, HA


def _residual(HF, VF, p, seabed):
    """Model fairlead position minus (XF, ZF) [m]; continuous across the touchdown switch."""
    XF, ZF, L, EA, W, CB = p
    LB, VA, _ = _ends(HF, VF, p, seabed)
    xs, zs, _ = _suspended(HF, VA, W, EA, L - LB)
    xg, _ = _grounded(HF, LB, W, CB, EA, LB)
    return xg + xs - XF, zs - ZF


def _jac(fun, u0, u1):
    """Values and 2x2 Jacobian (elementwise over batch) of fun(u0, u1) -> (f0, f1).

    One evaluation of ``fun`` and one (batched) of its linearisation for both
    columns: a compiled program with a single copy of each (two ``jvp`` calls
    would hold the function twice and its tangent twice)."""
    f, lin = jax.linearize(fun, u0, u1)
    one, zero = jnp.ones_like(u0), jnp.zeros_like(u0)
    (j00, j01), (j10, j11) = jax.vmap(lin, out_axes=0)(jnp.stack([one, zero]), jnp.stack([zero, one]))
    return f, (j00, j01, j10, j11)


def _solve2(J, r0, r1):
    j00, j01, j10, j11 = J
    det = j00 * j11 - j01 * j10
    return (r0 * j11 - r1 * j01) / det, (j00 * r1 - j10 * r0) / det


def _initial_guess(p, seabed):
    """Standard (Jonkman/Peyrot) guess; a straight-bar guess for taut lines; and, for a slack
    line that a rigid catenary says touches down, the rigid touchdown catenary (bisection)."""
    XF, ZF, L, EA, W, CB = p
    chord = jnp.sqrt(XF * XF + ZF * ZF)
    xs = jnp.where(XF > 0, XF, 1.0)
    q = jnp.maximum((L * L - ZF * ZF) / (xs * xs) - 1.0, 1e-12)
    lam = jnp.where(XF <= 0, 1e6, jnp.where(L <= chord, 0.2, jnp.sqrt(3.0 * q)))
    floor = jnp.maximum(1e-6 * jnp.abs(W) * L, 1e-12 * EA)
    HF0 = jnp.maximum(jnp.abs(W * XF / (2.0 * lam)), floor)
    VF0 = 0.5 * W * L + 0.5 * jnp.abs(W) * ZF / jnp.tanh(lam)
    ch = jnp.where(chord > 0, chord, 1.0)
    T0 = EA * (chord / L - 1.0)  # straight elastic bar
    taut = (L <= chord) & (T0 * XF / ch > HF0)
    HF0 = jnp.where(taut, T0 * XF / ch, HF0)
    VF0 = jnp.where(taut, T0 * ZF / ch + 0.5 * W * L, VF0)
    # rigid touchdown catenary, parameter c = HF/W [m]: XF = L - Ls + c asinh(Ls/c),
    # Ls = sqrt(ZF^2 + 2 ZF c); touchdown iff the root lies below c_max (where Ls = L)
    zp = jnp.maximum(ZF, 1e-9 * L)
    gap = lambda lc: _touchdown_gap(jnp.exp(lc), zp, L, XF)  # noqa: E731
    hi = jnp.log(jnp.maximum((L * L - zp * zp) / (2.0 * zp), 1e-300))
    lo = hi - 60.0
    grounded = seabed & (W > 0) & (ZF > 0) & (L > chord) & (gap(hi) > 0) & (gap(lo) < 0)
    def bisect(_, b):
        mid = 0.5 * (b[0] + b[1])
        up = gap(mid) > 0
        return jnp.where(up, b[0], mid), jnp.where(up, mid, b[1])
    lo, hi = lax.fori_loop(0, 60, bisect, (lo, hi))
    c = jnp.exp(0.5 * (lo + hi))
    HF0 = jnp.where(grounded, jnp.maximum(W * c, floor), HF0)
    VF0 = jnp.where(grounded, W * jnp.sqrt(zp * zp + 2.0 * zp * c), VF0)
    return jnp.log(HF0), VF0


def _touchdown_gap(c, ZF, L, XF):
    Ls = jnp.sqrt(ZF * ZF + 2.0 * ZF * c)
    return L - Ls + Ls * _asinhc(Ls / c) - XF


_ALPHAS = (1.0, 0.5, 0.25, 0.125, 1 / 16, 1 / 64, 1 / 256)


def _newton(p, seabed, rtol, max_steps):
    """Damped Newton on u = (log HF, VF) with Deuflhard's natural monotonicity test (the
    simplified Newton correction must shrink), vectorised over any batch shape of p."""
    XF, ZF, L, EA, W, CB = p
    tol = rtol * jnp.maximum(L, jnp.sqrt(XF * XF + ZF * ZF))
    F = lambda lh, vf: _residual(jnp.exp(lh), vf, p, seabed)  # noqa: E731

    def body(state):
        lh, vf, k, done = state
        (f0, f1), J = _jac(F, lh, vf)
        ok = jnp.isfinite(f0) & jnp.isfinite(f1)
        done = done | ~ok | (jnp.maximum(jnp.abs(f0), jnp.abs(f1)) <= tol)
        d0, d1 = _solve2(J, -f0, -f1)
        shrink = jnp.minimum(1.0, 3.0 / jnp.maximum(jnp.abs(d0), 1e-300))  # |dlog HF| <= 3
        d0, d1 = d0 * shrink, d1 * shrink
        vs = jnp.exp(lh) + jnp.abs(vf)  # [N] scale of VF in the correction norm
        n0 = jnp.hypot(d0, d1 / vs)
        al = jnp.asarray(_ALPHAS).reshape((-1,) + (1,) * lh.ndim)  # all trial steps at once
        g0, g1 = F(lh + al * d0, vf + al * d1)
        e0, e1 = _solve2(J, g0, g1)
        acc = (jnp.hypot(e0, e1 / vs) <= (1.0 - 0.25 * al) * n0) & jnp.isfinite(e0 + e1)
        alpha = jnp.max(jnp.where(acc, al, 0.0), axis=0)  # largest acceptable step
        alpha = jnp.where(alpha > 0, alpha, 0.125)  # none passes: cautious step
        step_ok = jnp.isfinite(d0) & jnp.isfinite(d1)
        move = ~done & step_ok
        done = done | ~step_ok
        return (jnp.where(move, lh + alpha * d0, lh), jnp.where(move, vf + alpha * d1, vf),
                k + jnp.where(done, 0, 1), done)

    def cond(state):
        return ~jnp.all(state[3]) & (jnp.max(state[2]) < max_steps)

    lh0, vf0 = _initial_guess(p, seabed)
    k0 = jnp.zeros(lh0.shape, jnp.int32)
    lh, vf, k, _ = lax.while_loop(cond, body, (lh0, vf0, k0, jnp.zeros(lh0.shape, bool)))
    f0, f1 = F(lh, vf)
    res = jnp.maximum(jnp.abs(f0), jnp.abs(f1))
    valid = (jnp.isfinite(XF) & jnp.isfinite(ZF) & jnp.isfinite(W) & jnp.isfinite(CB)
             & (XF >= 0) & (L > 0) & (EA > 0) & (CB >= 0) & jnp.isfinite(L) & jnp.isfinite(EA))
    conv = valid & jnp.isfinite(res) & (res <= tol) & jnp.isfinite(vf) & jnp.isfinite(lh)
    return jnp.exp(lh), vf, conv, jnp.where(jnp.isfinite(res), res, jnp.inf), k


_newton_jit = jax.jit(_newton)


@jax.custom_jvp
def _core(p, seabed, rtol, max_steps):
    """(HF, VF, converged, residual, steps); derivatives by the implicit-function theorem."""
    return _newton_jit(p, seabed, rtol, max_steps)


@_core.defjvp
def _core_jvp(primals, tangents):
    p, seabed, rtol, max_steps = primals
    out = _newton_jit(p, seabed, rtol, max_steps)
    HF, VF = out[0], out[1]
    _, J = _jac(lambda h, v: _residual(h, v, p, seabed), HF, VF)
    _, (g0, g1) = jax.jvp(lambda pp: _residual(HF, VF, pp, seabed), (p,), (tangents[0],))
    dHF, dVF = _solve2(J, -g0, -g1)  # F(y(p), p) = 0  =>  dy = -J^{-1} dF/dp dp
    f0 = lambda x: np.zeros(jnp.shape(x), jax.dtypes.float0)  # noqa: E731
    return out, (dHF, dVF, f0(out[2]), jnp.zeros_like(out[3]), f0(out[4]))


@jax.jit
def _finish(p, HF, VF, conv, res, k, seabed):
    LB, VA, HA = _ends(HF, VF, p, seabed)
    return CatenarySolution(HF, VF, HA, VA, LB, conv, *p, residual=res, steps=k)


def solve_catenary(XF, ZF, L, EA, W, CB=0.0, *, seabed=True, rtol=1e-12, max_steps=100,
                   throw=False) -> CatenarySolution:
    """Solve the elastic catenary for the fairlead/anchor tensions.

    Args (broadcastable arrays, SI): XF >= 0 [m] horizontal and ZF [m] vertical offset of the
    fairlead from the anchor; L > 0 [m] unstretched length; EA > 0 [N] axial stiffness; W [N/m]
    wet weight per unstretched length (< 0: buoyant, never grounded); CB >= 0 [-] seabed friction.
    seabed: allow seabed contact (anchor on the seabed at z = 0; needs W > 0 and ZF >= 0).
    rtol: end-point tolerance relative to max(L, chord) (keep >= ~1e-14); max_steps: Newton cap.
    throw: raise RuntimeError if not converged (only when values are concrete).

    Raises ValueError for invalid concrete inputs; under jit invalid inputs give converged=False.
    """
    check_nonnegative(XF, "XF (horizontal fairlead offset)", "m")
    check_finite(ZF, "ZF (vertical fairlead offset)", "m")
    check_positive(L, "L (unstretched line length)", "m")
    check_positive(EA, "EA (axial stiffness)", "N")
    check_finite(W, "W (wet weight per unit length)", "N/m")
    check_nonnegative(CB, "CB (seabed friction coefficient)", "-")
    p = tuple(jnp.broadcast_arrays(*[jnp.asarray(v, float) for v in (XF, ZF, L, EA, W, CB)]))
    seabed = jnp.asarray(seabed, bool)
    out = _core(p, seabed, jnp.asarray(rtol, float), jnp.asarray(max_steps, jnp.int32))
    sol = _finish(p, *out, seabed)
    if throw:
        raise_if_not_converged(sol)
    return sol


def raise_if_not_converged(sol: CatenarySolution) -> CatenarySolution:
    """Raise RuntimeError (with inputs and residual) if any element of ``sol`` did not converge."""
    if isinstance(sol.converged, jax.core.Tracer):
        raise TypeError("raise_if_not_converged needs concrete values (call it outside jit)")
    if not bool(jnp.all(sol.converged)):
        raise RuntimeError(
            "catenary Newton iteration did not converge: "
            f"XF={sol.XF} m, ZF={sol.ZF} m, L={sol.L} m, EA={sol.EA} N, W={sol.W} N/m, "
            f"CB={sol.CB}; end-point residual={sol.residual} m after {sol.steps} steps "
            f"(HF={sol.HF} N, VF={sol.VF} N). Check that the geometry is feasible (a slack line "
            "needs W != 0; a grounded solution needs XF > 0).")
    return sol


@jax.jit
def catenary_profile(sol: CatenarySolution, s):
    """Line shape at unstretched arc length ``s`` [m] from the anchor (0 <= s <= L).

    Returns ``(x, z, T)``: position relative to the anchor [m] and tension magnitude [N];
    ``s`` broadcasts against the fields of ``sol``.
    """
    s = jnp.asarray(s, float)
    LB = sol.grounded_length
    xg, Tg = _grounded(sol.HF, LB, sol.W, sol.CB, sol.EA, jnp.minimum(s, LB))
    xs, zs, Ts = _suspended(sol.HF, sol.VA, sol.W, sol.EA, jnp.maximum(s - LB, 0.0))
    return xg + xs, zs, jnp.where(s < LB, Tg, Ts)


@jax.jit
def _frame(r_a, r_b):
    """Lower end, horizontal unit vector towards the upper end, XF, ZF, swap flag."""
    r_a, r_b = jnp.asarray(r_a, float), jnp.asarray(r_b, float)
    swap = r_a[..., 2] > r_b[..., 2]
    lo = jnp.where(swap[..., None], r_b, r_a)
    d = jnp.where(swap[..., None], r_a, r_b) - lo
    e, XF = safe_unit(d[..., :2])
    e = jnp.where(XF[..., None] > 0, e, jnp.array([1.0, 0.0]))
    return lo, jnp.concatenate([e, jnp.zeros_like(e[..., :1])], -1), XF, d[..., 2], swap


@jax.jit
def _end_forces(sol, e, swap):
    ez = jnp.array([0.0, 0.0, 1.0])
    f_lo = sol.HA[..., None] * e + sol.VA[..., None] * ez
    f_hi = -sol.HF[..., None] * e - sol.VF[..., None] * ez
    return jnp.where(swap[..., None], f_hi, f_lo), jnp.where(swap[..., None], f_lo, f_hi)


def catenary_line_forces(r_a, r_b, L, EA, W, CB=0.0, seabed=True, **kwargs):
    """Forces [N] a line exerts on its ends at r_a, r_b [m] (3-vectors, or (..., 3); z up).

    The lower end plays the anchor role (on the seabed at its own height if contact is possible);
    the returned ``sol`` describes the line from the lower to the upper end.  kwargs go to
    solve_catenary.  Returns ``(sol, force_on_a, force_on_b)``.
    """
    _, e, XF, ZF, swap = _frame(r_a, r_b)
    sol = solve_catenary(XF, ZF, L, EA, W, CB, seabed=seabed, **kwargs)
    return (sol, *_end_forces(sol, e, swap))


@jax.jit
def catenary_nodes(sol: CatenarySolution, r_a, r_b, s):
    """Points (len(s), 3) [m] of one line at unstretched arc length s [m] measured from end A."""
    lo, e, _, _, swap = _frame(r_a, r_b)
    return nodes_in_frame(sol, lo, e, swap, s)


def nodes_in_frame(sol: CatenarySolution, lo, e, swap, s):
    """:func:`catenary_nodes` in the frame ``_frame(r_a, r_b)`` already gives
    (its lower end, horizontal unit vector and swap flag)."""
    s = jnp.asarray(s, float)
    x, z, _ = catenary_profile(sol, jnp.where(swap, sol.L - s, s))
    return lo + x[..., None] * e + z[..., None] * jnp.array([0.0, 0.0, 1.0])
