"""Wu et al.'s mixed element: Hermite-cubic position, quadratic tension field.

The line's position r(s) over unstretched arc length s is C¹ piecewise cubic:
each node k carries its position r_k and slope r'_k = dr/ds (|r'| = 1 + ε), and
element e (length h = L/n, ξ = (s − s_e)/h) interpolates

    r(ξ) = H₁ r_e + h H₂ r'_e + H₃ r_{e+1} + h H₄ r'_{e+1},
    H₁ = 1 − 3ξ² + 2ξ³, H₂ = ξ − 2ξ² + ξ³, H₃ = 3ξ² − 2ξ³, H₄ = ξ³ − ξ².

The effective tension λ(s) is continuous and piecewise quadratic, with values at
the nodes and at the element midpoints (2n + 1 unknowns; Lagrange P₁, P₂, P₃ on
ξ = 0, ½, 1). The two equations (Wu et al. Eq. 17–18/19, 27, written with the
axial law's exact strain ε(λ) instead of its second-order series):

- equilibrium, for every virtual Hermite δr:
  ∫ [ λ/(1 + ε(λ)) · r'·δr' + ∂e_b/∂r'·δr' + ∂e_b/∂r''·δr'' − q·δr ] ds = end forces·δr,
  with q the weight/buoyancy, seabed contact and (static) current drag per
  unstretched length and e_b = ½·EI·κ² the bending energy density (κ² =
  |r'×r''|²/|r'|⁶, natural here: the slopes are unknowns);
- extensibility (Eq. 16), weighted by each P_m: ∫ P_m [ r'·r'/(1 + ε) − (1 + ε) ] ds = 0.

Integrals use 5-point Gauss–Legendre per element. The axial law enters through
its inverse ε(λ) (exact for a linear EA, Newton iterations otherwise); the
element is bilateral in compression (ε = λ/EA for λ < 0): a slack stretch is not
modelled. Ends are pinned (the end slopes are unknowns with zero end moment).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.lax as lax
import jax.numpy as jnp
import numpy as np

from .._numerics import abs_times, safe_norm
from ..model.axial import Bilateral, LinearEA
from .base import AbstractElement

_GX, _GW = np.polynomial.legendre.leggauss(5)
XI = jnp.asarray(0.5 * (_GX + 1.0))  # quadrature points on [0, 1]
WQ = jnp.asarray(0.5 * _GW)  # and weights (sum 1)


def _hermite(xi):
    """Shape functions (4, Q) and their first and second ξ-derivatives."""
    x2, x3 = xi * xi, xi * xi * xi
    h = jnp.stack([1 - 3 * x2 + 2 * x3, xi - 2 * x2 + x3, 3 * x2 - 2 * x3, x3 - x2])
    d = jnp.stack([-6 * xi + 6 * x2, 1 - 4 * xi + 3 * x2, 6 * xi - 6 * x2, 3 * x2 - 2 * xi])
    dd = jnp.stack([-6 + 12 * xi, -4 + 6 * xi, 6 - 12 * xi, 6 * xi - 2])
    return h, d, dd


def _lagrange(xi):
    """Quadratic Lagrange functions on ξ = 0, ½, 1: (3, Q)."""
    return jnp.stack([(1 - xi) * (1 - 2 * xi), 4 * xi * (1 - xi), xi * (2 * xi - 1)])


H, DH, DDH = _hermite(XI)
P = _lagrange(XI)


class HermiteDofs(eqx.Module):
    """Unknowns of a Hermite line: node positions (n+1, 3) [m], node slopes
    dr/ds (n+1, 3) [-] and the tension field at nodes and midpoints (2n+1,) [N]."""

    r: jax.Array
    dr: jax.Array
    lam: jax.Array


def strain_of_tension(law, lam):
    """Strain ε [-] at effective tension λ [N]: the inverse of the axial law.

    Exact for a linear EA; otherwise Newton iterations on ``tension_positive``
    from λ/EA, the last step taken on a stopped-gradient iterate so that the
    derivative is the implicit one, 1/T'(ε). Compression: ε = λ/EA (bilateral).
    """
    ea = law.nominal_ea()
    inner = law.law if isinstance(law, Bilateral) else law
    if isinstance(inner, LinearEA):
        return lam / ea
    pos = jnp.maximum(lam, 0.0)

    def newton(e):
        t, dt = jax.jvp(inner.tension_positive, (e,), (jnp.ones_like(e),))
        return jnp.maximum(e - (t - pos) / dt, 0.0)

    e = lax.fori_loop(0, 40, lambda _, e: newton(e), pos / ea)
    e = newton(lax.stop_gradient(e))
    return jnp.where(lam >= 0.0, e, lam / ea)


def element_fields(line, dofs: HermiteDofs):
    """Per element and quadrature point (n, Q, ·): r, r', r'' and λ."""
    h = line.segment_length
    u = jnp.stack([dofs.r[:-1], h * dofs.dr[:-1], dofs.r[1:], h * dofs.dr[1:]], axis=1)  # (n,4,3)
    r = jnp.einsum("aq,nai->nqi", H, u)
    d1 = jnp.einsum("aq,nai->nqi", DH, u) / h
    d2 = jnp.einsum("aq,nai->nqi", DDH, u) / h**2
    lam_e = jnp.stack([dofs.lam[0:-1:2], dofs.lam[1::2], dofs.lam[2::2]], axis=1)  # (n,3)
    lam = jnp.einsum("mq,nm->nq", P, lam_e)
    return r, d1, d2, lam


def _bending_density(ei, d1, d2):
    """½·EI·κ² [N] with κ² = |r'×r''|²/|r'|⁶ (exact curvature of an extensible curve)."""
    c = jnp.cross(d1, d2)
    s2 = jnp.sum(d1 * d1, axis=-1)
    return 0.5 * ei * jnp.sum(c * c, axis=-1) / s2**3


def _distributed_load(line, env, r, d1, t):
    """External load per unstretched length (n, Q, 3) [N/m] at rest: weight and
    buoyancy, seabed contact, drag of the current."""
    lt = line.line_type
    q = jnp.zeros_like(r).at[..., 2].add(-lt.wet_weight(env.rho, env.g))
    if env.seabed is not None:
        if env.seabed.bathymetry is not None:
            raise ValueError("HermiteElement: a bathymetry grid (SeafloorFile) is not supported yet; "
                             "use LinearElement for lines over a 3-D seabed")
        pen = jnp.maximum(-env.depth - r[..., 2], 0.0)
        q = q.at[..., 2].add(env.seabed.stiffness * lt.diameter * pen)
    if lt.drag is not None and env.current is not None:
        u = -env.current.velocity(r[..., 2].reshape(-1), t).reshape(r.shape)
        stretch = safe_norm(d1)[..., None]
        tangent = d1 / jnp.maximum(stretch, 1e-300)
        ut = jnp.sum(u * tangent, axis=-1, keepdims=True) * tangent
        un = u - ut
        cn = 0.5 * env.rho * lt.drag.cd_normal * lt.diameter
        ca = 0.5 * env.rho * lt.drag.cd_axial * jnp.pi * lt.diameter
        q = q - stretch * (cn * abs_times(un) + ca * abs_times(ut))
    return q


def static_residual(line, env, dofs: HermiteDofs, t=0.0):
    """Generalised forces of the line at rest and the extensibility residuals.

    Returns ``(force_r (n+1, 3) [N], moment_dr (n+1, 3) [N·m], constraint (2n+1,) [m])``:
    the generalised forces on the node positions and slopes (the line's pull on
    the end nodes included; zero at equilibrium on free unknowns), and the
    P_m-weighted extensibility integrals.
    """
    lt = line.line_type
    h = line.segment_length
    r, d1, d2, lam = element_fields(line, dofs)
    eps = strain_of_tension(lt.axial, lam)
    g = (lam / (1.0 + eps))[..., None] * d1  # ∂(internal work)/∂r'
    b = jnp.zeros_like(d2)
    if lt.ei is not None:
        gb, b = jax.grad(lambda a, c: jnp.sum(_bending_density(lt.ei, a, c)), argnums=(0, 1))(d1, d2)
        g = g + gb
    q = _distributed_load(line, env, r, d1, t)
    # Q_a = ∫ [ H_a q − H_a'/h g − H_a''/h² b ] ds, ds = h dξ
    w = WQ * h
    qa = (jnp.einsum("aq,q,nqi->nai", H, w, q) - jnp.einsum("aq,q,nqi->nai", DH, w / h, g)
          - jnp.einsum("aq,q,nqi->nai", DDH, w / h**2, b))
    n = line.n_segments
    zero = jnp.zeros((1, 3))
    force = jnp.concatenate([qa[:, 0], zero]) + jnp.concatenate([zero, qa[:, 2]])
    moment = h * (jnp.concatenate([qa[:, 1], zero]) + jnp.concatenate([zero, qa[:, 3]]))
    c = jnp.sum(d1 * d1, axis=-1) / (1.0 + eps) - (1.0 + eps)  # (n, Q)
    ce = jnp.einsum("mq,q,nq->nm", P, w, c)  # (n, 3)
    constraint = jnp.zeros(2 * n + 1)
    constraint = constraint.at[0:-1:2].add(ce[:, 0]).at[1::2].add(ce[:, 1]).at[2::2].add(ce[:, 2])
    return force, moment, constraint


class HermiteElement(AbstractElement):
    """Wu et al.'s mixed Hermite-cubic element (statics; see the module docstring).

    Its unknowns are not node positions alone (:class:`HermiteDofs`), so its
    statics has its own solve (:func:`moorjax.statics.hermite.solve_hermite_statics`,
    called by :func:`moorjax.statics.fem.solve_line_statics`). The node-position
    interface of the dynamics driver is not available for it yet.
    """

    @property
    def banded_jacobian(self) -> bool:
        return False

    def _no_dynamics(self):
        raise NotImplementedError(
            "HermiteElement: dynamics are not implemented yet (its state carries slopes and a "
            "tension field); use LinearElement for simulate/fit/ensembles"
        )

    def nodal_forces(self, line, env, r, v, t=0.0):
        self._no_dynamics()

    def accelerations(self, line, env, t, r, v):
        self._no_dynamics()

    def segment_tensions(self, line, r, v):
        self._no_dynamics()

    def end_forces(self, line, env, r, v, t=0.0):
        self._no_dynamics()
