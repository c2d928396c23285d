"""Radiation memory of a floating body: the retardation function and its state-space fit.

Radiation (Cummins): F_rad = −A∞ ẍ − ∫₀ᵗ K(t−τ) ẋ(τ) dτ with the retardation
function K(t) = (2/π) ∫₀^∞ B(ω) cos(ωt) dω, whose Fourier transform is
K̂(ω) = ∫₀^∞ K(t) e^{−iωt} dt = B(ω) + iω (A(ω) − A∞).
:func:`fit_radiation` replaces the integral by ξ̇ = A ξ + B ẋ, F = −C ξ
(Wu et al. Eq. 1), a :class:`RadiationStateSpace` the body integrates with its
motion. The damping B(ω) comes from a :class:`~moorjax.body.hydro.HydroCoefficients`
table (6 DOF about the body's reference point: surge, sway, heave [m], roll,
pitch, yaw [rad]).

Everything here but :class:`RadiationStateSpace` is preprocessing in NumPy (it
runs once, outside ``jit``).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

if TYPE_CHECKING:
    from .hydro import HydroCoefficients


def retardation_function(coeffs: HydroCoefficients, t, *, tail_power: float = 3.0) -> np.ndarray:
    """K(t) = (2/π) ∫₀^∞ B(ω) cos(ωt) dω, (T, 6, 6) [N/m, N, N·m/rad] (damping per s).

    B is the symmetric part of the table's damping. Between the table's
    frequencies B is linear; below the first it falls linearly to B(0) = 0; above
    the last, ω_K, it decays as B(ω_K)·(ω_K/ω)^p with p = ``tail_power`` (sampled
    to 50 ω_K, beyond which the tail is dropped). The integral of this
    piecewise-linear B times cos(ωt) is evaluated exactly (no aliasing in t).
    """
    om, b = _damping_nodes(coeffs, tail_power)
    t = np.asarray(t, dtype=float)
    return _cosine_transform(om, b.reshape(om.shape[0], 36), t).reshape(t.shape + (6, 6))


def _damping_nodes(coeffs, tail_power):
    om = np.asarray(coeffs.omega)
    bd = np.asarray(coeffs.damping)
    bd = 0.5 * (bd + np.swapaxes(bd, 1, 2))
    tail = om[-1] * np.geomspace(1.0, 50.0, 600)[1:]
    bt = bd[-1][None] * (om[-1] / tail)[:, None, None] ** tail_power
    nodes = np.concatenate([[0.0], om, tail])
    vals = np.concatenate([np.zeros((1, 6, 6)), bd, bt])
    return nodes, vals


def _cosine_transform(om, f, t):
    """(2/π)∫ f cos(ωt) dω for piecewise-linear f on nodes ``om``; f (S, n) → (T, n)."""
    a, b = om[:-1], om[1:]
    fa, fb = f[:-1], f[1:]
    slope = (fb - fa) / (b - a)[:, None]
    out = np.empty((t.shape[0], f.shape[1]))
    zero = t == 0
    out[zero] = np.sum(0.5 * (fa + fb) * (b - a)[:, None], axis=0)
    tt = t[~zero][:, None]
    if tt.size:
        sa, sb, ca, cb = np.sin(a * tt), np.sin(b * tt), np.cos(a * tt), np.cos(b * tt)
        out[~zero] = ((sb / tt) @ fb - (sa / tt) @ fa + ((cb - ca) / tt**2) @ slope)
    return 2.0 / np.pi * out


class RadiationStateSpace(eqx.Module):
    """Radiation memory as a linear system: ξ̇ = A ξ + B ẋ, F_rad,memory = −C ξ.

    With ξ(0) = 0, −C ξ(t) ≈ −∫₀ᵗ K(t−τ) ẋ(τ) dτ [N, N·m]. A (m, m) is block
    diagonal with stable blocks, one subsystem per fitted entry K_ij (input ẋ_j,
    output to force i).
    """

    A: Array
    B: Array
    C: Array

    def __init__(self, A, B, C):
        A, B, C = (jnp.asarray(x, dtype=float) for x in (A, B, C))
        m = A.shape[0]
        if A.shape != (m, m) or B.shape != (m, 6) or C.shape != (6, m):
            raise ValueError(f"radiation state space needs A (m, m), B (m, 6), C (6, m); "
                             f"got {A.shape}, {B.shape}, {C.shape}")
        self.A, self.B, self.C = A, B, C

    @property
    def n_states(self) -> int:
        return int(self.A.shape[0])

    def init(self) -> Array:
        """ξ = 0: the body at rest since −∞."""
        return jnp.zeros(self.A.shape[0])

    def rate(self, x, velocity) -> Array:
        """dξ/dt (m,) for the body velocity ẋ (6,) [m/s, rad/s]."""
        return self.A @ x + self.B @ velocity

    def force(self, x) -> Array:
        """Memory part of the radiation force (6,) [N, N·m]."""
        return -(self.C @ x)

    def transfer(self, omega) -> Array:
        """K̂(ω) = C (iωI − A)⁻¹ B, (…, 6, 6) complex: B(ω) + iω(A(ω) − A∞) of the fit."""
        om = jnp.asarray(omega, dtype=float)
        eye = jnp.eye(self.A.shape[0])
        solve = jax.vmap(lambda w: self.C @ jnp.linalg.solve(1j * w * eye - self.A, self.B + 0j))
        return solve(om.reshape(-1)).reshape(om.shape + (6, 6))


@dataclasses.dataclass(frozen=True)
class RadiationFitReport:
    """What :func:`fit_radiation` did, entry by entry ((i, j) 0-based DOF pairs).

    Attributes:
        order: number of states of each fitted entry.
        k_error: relative L2 error ‖K_fit − K‖/‖K‖ of K_ij(t) on the fit's time grid.
        b_error: relative L2 error of the fit's B_ij(ω) against the (symmetrised)
            table on the table's frequencies.
        dropped: entries not fitted, with their size max|B_ij| relative to
            √(max|B_ii|·max|B_jj|).
        t: (T,) time grid [s]; kernel, kernel_fit: (T, 6, 6) K(t) and its fit.
        tail_power: exponent of the damping's high-frequency tail.
    """

    order: dict
    k_error: dict
    b_error: dict
    dropped: dict
    t: np.ndarray
    kernel: np.ndarray
    kernel_fit: np.ndarray
    tail_power: float

    def __str__(self):
        names = ("surge", "sway", "heave", "roll", "pitch", "yaw")
        rows = [f"{'entry':<14}{'states':>7}{'K err %':>9}{'B err %':>9}"]
        for ij in sorted(self.order):
            rows.append(f"{names[ij[0]] + '-' + names[ij[1]]:<14}{self.order[ij]:>7d}"
                        f"{100 * self.k_error[ij]:>9.2f}{100 * self.b_error[ij]:>9.2f}")
        if self.dropped:
            rows.append("dropped: " + ", ".join(f"{names[i]}-{names[j]} ({r:.1e})"
                                                for (i, j), r in sorted(self.dropped.items())))
        return "\n".join(rows)


def fit_radiation(coeffs: HydroCoefficients, order: int = 10, *, tol: float = 0.01,
                  threshold: float = 0.02, dt: float = 0.5, t_max: float | None = None,
                  tail_power: float = 3.0):
    """Fit a stable state-space model to the retardation functions K_ij(t).

    Method, per entry: K_ij(t) (see :func:`retardation_function`) is sampled every
    ``dt`` [s] up to ``t_max`` (default 4π/Δω_min of the table, at most 200 s);
    an eigensystem realisation (Hankel SVD) of order n gives the poles, unstable
    poles are reflected into the left half plane (and Nyquist-aliased ones
    dropped), then the residues are fitted by linear least squares to K_ij(t).
    The order n is raised (2, 4, … ``order``) until the relative L2 error of K_ij(t)
    is below ``tol``; otherwise the best fit is kept.

    Entries: every diagonal entry with nonzero damping, and every off-diagonal
    entry whose max|B_ij| exceeds ``threshold``·√(max|B_ii|·max|B_jj|) (for a
    body symmetric about xz and yz: surge–pitch and sway–roll). K_ij and K_ji are
    the same symmetrised function, each with its own states. Others are dropped
    and listed in the report.

    Returns:
        (RadiationStateSpace, RadiationFitReport).
    """
    om = np.asarray(coeffs.omega)
    if t_max is None:
        t_max = min(200.0, 4 * np.pi / np.min(np.diff(om)))
    if not (dt > 0 and t_max > 20 * dt):
        raise ValueError(f"fit_radiation needs dt > 0 and t_max > 20·dt [s]; got dt = {dt}, t_max = {t_max}")
    if order < 1:
        raise ValueError(f"fit_radiation order (states per entry) must be >= 1, got {order}")
    t = np.arange(0.0, t_max + 0.5 * dt, dt)
    kern = retardation_function(coeffs, t, tail_power=tail_power)
    bsym = np.asarray(coeffs.damping)
    bsym = 0.5 * (bsym + np.swapaxes(bsym, 1, 2))
    bmax = np.max(np.abs(bsym), axis=0)

    blocks, order_of, kerr, berr, dropped = [], {}, {}, {}, {}
    kfit = np.zeros_like(kern)
    for i in range(6):
        for j in range(i, 6):
            if i == j:
                size = 1.0 if bmax[i, i] > 0 else 0.0
            else:
                scale = np.sqrt(bmax[i, i] * bmax[j, j])
                size = bmax[i, j] / scale if scale > 0 else 0.0
            if size <= (0.0 if i == j else threshold):
                dropped[(i, j)] = float(size)
                if i != j:
                    dropped[(j, i)] = float(size)
                continue
            a, b, c, ke, fit = _fit_entry(t, kern[:, i, j], order, tol)
            bfit = np.real(_siso_transfer(a, b, c, om))
            be = np.linalg.norm(bfit - bsym[:, i, j]) / max(np.linalg.norm(bsym[:, i, j]), 1e-300)
            for (p, q) in ([(i, j)] if i == j else [(i, j), (j, i)]):
                blocks.append((p, q, a, b, c))
                order_of[(p, q)], kerr[(p, q)], berr[(p, q)] = a.shape[0], ke, float(be)
                kfit[:, p, q] = fit
    m = sum(blk[2].shape[0] for blk in blocks)
    A, B, C = np.zeros((m, m)), np.zeros((m, 6)), np.zeros((6, m))
    s = 0
    for p, q, a, b, c in blocks:
        n = a.shape[0]
        A[s:s + n, s:s + n], B[s:s + n, q], C[p, s:s + n] = a, b, c
        s += n
    report = RadiationFitReport(order_of, kerr, berr, dropped, t, kern, kfit, float(tail_power))
    return RadiationStateSpace(A, B, C), report


def _siso_transfer(a, b, c, omega):
    """c (iωI − a)⁻¹ b at each ω (K,) → (K,) complex."""
    lhs = 1j * omega[:, None, None] * np.eye(a.shape[0]) - a
    return np.linalg.solve(lhs, np.broadcast_to(b + 0j, (omega.shape[0], b.shape[0]))[..., None])[..., 0] @ c


def _fit_entry(t, k, max_order, tol):
    """Best SISO realisation (a, b, c) of the sampled kernel k(t)."""
    scale = np.max(np.abs(k))
    if scale == 0:
        raise ValueError("cannot fit an identically zero retardation function")
    y = k / scale
    dt = t[1] - t[0]
    best = None
    for n in sorted({*range(2, max_order + 1, 2), max_order}):
        poles = _era_poles(y, n, dt)
        if poles.size == 0:
            continue
        a, b, c, fit = _residues(t, y, poles)
        err = np.linalg.norm(fit - y) / np.linalg.norm(y)
        if best is None or err < best[3] * 0.98:
            best = (a, b, c * scale, err, fit * scale)
        if err <= tol:
            break
    if best is None:
        raise RuntimeError("radiation fit found no stable poles; try a smaller dt or larger t_max")
    return best[0], best[1], best[2], float(best[3]), best[4]


def _era_poles(y, n, dt):
    """Continuous-time poles of an order-n eigensystem realisation of samples y."""
    r = min(len(y) // 2, 150)
    hank = np.lib.stride_tricks.sliding_window_view(y, r)[: r + 1]
    h0, h1 = hank[:-1], hank[1:]
    u, sv, vt = np.linalg.svd(h0)
    n = min(n, int(np.sum(sv > sv[0] * 1e-12)))
    if n < 1:
        return np.zeros(0, complex)
    sq = 1.0 / np.sqrt(sv[:n])
    ad = (sq[:, None] * (u[:, :n].T @ h1 @ vt[:n].T)) * sq[None, :]
    lam = np.linalg.eigvals(ad)
    keep = ~((np.abs(lam.imag) < 1e-12) & (lam.real <= 0))  # Nyquist-aliased or zero
    lam = lam[keep]
    s = np.log(lam.astype(complex)) / dt
    s = -np.abs(s.real) - 1e-6 + 1j * s.imag  # reflect unstable poles
    # one member of each conjugate pair (and the real poles)
    real = s[np.abs(s.imag) < 1e-9].real + 0j
    cplx = s[s.imag >= 1e-9]
    return np.concatenate([real, cplx])


def _residues(t, y, poles):
    """Least-squares residues for fixed poles; real block-diagonal (a, b, c)."""
    cols, blocks = [], []
    for p in poles:
        e = np.exp(p.real * t)
        if p.imag == 0:
            cols.append(e)
            blocks.append(("r", p.real))
        else:
            cols += [e * np.cos(p.imag * t), e * np.sin(p.imag * t)]
            blocks.append(("c", p))
    phi = np.stack(cols, axis=1)
    coef, *_ = np.linalg.lstsq(phi, y, rcond=None)
    n = phi.shape[1]
    a, b, c = np.zeros((n, n)), np.zeros(n), np.zeros(n)
    k = 0
    for kind, p in blocks:
        if kind == "r":
            a[k, k], b[k], c[k] = p, 1.0, coef[k]
            k += 1
        else:
            sig, w = p.real, p.imag
            # e^{At} [1, 0]ᵀ = e^{σt} [cos ωt, −sin ωt]ᵀ  →  c = [p_cos, −p_sin]
            a[k:k + 2, k:k + 2] = [[sig, w], [-w, sig]]
            b[k] = 1.0
            c[k], c[k + 1] = coef[k], -coef[k + 1]
            k += 2
    return a, b, c, phi @ coef
