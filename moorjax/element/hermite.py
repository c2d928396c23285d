"""Wu et al.'s mixed element: Hermite-cubic position, quadratic tension field.

The line's position r(s) over unstretched arc length s is C¹ piecewise cubic:
each node k carries its position r_k and slope r'_k = dr/ds (|r'| = 1 + ε), and
element e (length h = h_e, L/n unless ``HermiteElement.mesh`` grades them; ξ = (s − s_e)/h) interpolates

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
its inverse ε(λ) (exact for a linear EA, Newton iterations otherwise).

Slack: a cable carries no compression (the unilateral laws of
:mod:`moorjax.model.axial`), but ε(λ) has no inverse at λ = 0 (every ε < 0 gives
T = 0). The element regularises it: for λ < 0, ε = λ/(c·EA) with the slack
ratio c = ``HermiteElement.slack_ratio`` (default 1e-4), a line that shortens
by 1 % pushes with 1e-6·EA. A :class:`~moorjax.model.axial.Bilateral` law keeps
its full EA in compression. Measured on the reference case A (10 elements,
Newmark reference, 60 s): with the earlier bilateral field (c = 1) the lower line
carried up to −170 kN of compression in the troughs, holding the fairlead
tension at 12 kN where MoorDyn has 115 kN (RMS error 10 % of the std); with
c = 1e-2, 1e-3, 1e-4: 2.5 %, 1.3 %, 1.25 %. Ends are pinned (the end slopes are
unknowns with zero end moment) unless clamped
(:class:`~moorjax.model.ends.AbstractClampedEnd`): a clamp fixes the direction
of the end slope, its length 1 + ε stays free (:func:`clamped_slopes`).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.lax as lax
import jax.numpy as jnp
import numpy as np

from .._numerics import safe_norm
from ..model.axial import Bilateral, LinearEA
from . import morison
from .base import AbstractElement

# the element's constants are NumPy arrays (no XLA op at import; constants in a trace)
_GX, _GW = np.polynomial.legendre.leggauss(5)
XI = 0.5 * (_GX + 1.0)  # quadrature points on [0, 1]
WQ = 0.5 * _GW  # and weights (sum 1)


def _hermite(xi):
    """Shape functions (4, Q) and their first and second ξ-derivatives."""
    x2, x3 = xi * xi, xi * xi * xi
    h = np.stack([1 - 3 * x2 + 2 * x3, xi - 2 * x2 + x3, 3 * x2 - 2 * x3, x3 - x2])
    d = np.stack([-6 * xi + 6 * x2, 1 - 4 * xi + 3 * x2, 6 * xi - 6 * x2, 3 * x2 - 2 * xi])
    dd = np.stack([-6 + 12 * xi, -4 + 6 * xi, 6 - 12 * xi, 6 * xi - 2])
    return h, d, dd


def _lagrange(xi):
    """Quadratic Lagrange functions on ξ = 0, ½, 1: (3, Q)."""
    return np.stack([(1 - xi) * (1 - 2 * xi), 4 * xi * (1 - xi), xi * (2 * xi - 1)])


H, DH, DDH = _hermite(XI)
P = _lagrange(XI)


class HermiteDofs(eqx.Module):
    """Unknowns of a Hermite line: node positions (n+1, 3) [m], node slopes
    dr/ds (n+1, 3) [-] and the tension field at nodes and midpoints (2n+1,) [N]."""

    r: jax.Array
    dr: jax.Array
    lam: jax.Array


def strain_of_tension(law, lam, slack_ratio=1.0, slack_width=0.0):
    """Strain ε [-] at effective tension λ [N]: the inverse of the axial law.

    Exact for a linear EA; otherwise Newton iterations on ``tension_positive``
    from λ/EA, the last step taken on a stopped-gradient iterate so that the
    derivative is the implicit one, 1/T'(ε). Compression (λ < 0): ε =
    λ/(c·EA) with c = ``slack_ratio`` [-] for a unilateral law (the slack
    regularisation, see the module notes), λ/EA for a :class:`Bilateral` one.

    ``slack_width`` δ [N] > 0 rounds the unilateral law's kink at λ = 0: ε =
    ε_law(λ₊) + λ₋/(c·EA) with λ₋ = −δ·softplus(−λ/δ) (→ min(λ, 0) as δ → 0)
    and λ₊ = λ − λ₋ (→ max(λ, 0)), smooth in λ; it differs from the kinked
    law only where |λ| is a few δ (by at most δ·ln 2/(c·EA) in strain, at
    λ = 0). 0 (the default) keeps the kink.
    """
    ea = law.nominal_ea()
    inner = law.law if isinstance(law, Bilateral) else law
    ea_c = ea if isinstance(law, Bilateral) else ea * slack_ratio
    if not isinstance(law, Bilateral) and not (isinstance(slack_width, (int, float)) and slack_width == 0.0):
        width = jnp.asarray(slack_width, float)
        wide = width > 0.0
        safe = jnp.where(wide, width, 1.0)
        neg = jnp.where(wide, -safe * jax.nn.softplus(-lam / safe), jnp.minimum(lam, 0.0))
        return strain_of_tension(law, lam - neg, 1.0) + neg / ea_c
    if isinstance(inner, LinearEA):
        return jnp.where(lam >= 0.0, lam, 0.0) / ea + jnp.where(lam < 0.0, lam, 0.0) / ea_c
    pos = jnp.maximum(lam, 0.0)

    def newton(e):
        t, dt = jax.jvp(inner.tension_positive, (e,), (jnp.ones_like(e),))
        return jnp.maximum(e - (t - pos) / dt, 0.0)

    e = lax.fori_loop(0, 40, lambda _, e: newton(e), pos / ea)
    e = newton(lax.stop_gradient(e))
    return jnp.where(lam >= 0.0, e, jnp.where(lam < 0.0, lam, 0.0) / ea_c)


def element_strain(line, lam):
    """:func:`strain_of_tension` of a Hermite line's axial law with its
    element's slack regularisation (``slack_ratio``, ``slack_width``)."""
    el = line.element
    return strain_of_tension(line.line_type.axial, lam, el.slack_ratio, el.slack_width)


def element_lengths(line):
    """The unstretched element lengths h_e (n,) [m]: L/n each, or the line's
    length split by ``HermiteElement.mesh`` (relative lengths, normalised)."""
    mesh = getattr(line.element, "mesh", None)
    n = line.n_segments
    if mesh is None:
        return jnp.full((n,), 1.0, dtype=jnp.result_type(line.length, float)) * (line.length / n)
    if mesh.shape != (n,):
        raise ValueError(f"line {line.label!r}: HermiteElement mesh has shape {mesh.shape}, "
                         f"the line has {n} elements")
    return line.length * mesh / jnp.sum(mesh)


def _element_coefficients(line, r, dr):
    """Each element's Hermite unknowns (n, 4, 3): r_e, h_e·r'_e, r_e+1, h_e·r'_e+1,
    and h_e (n, 1, 1)."""
    h = element_lengths(line)[:, None, None]
    return jnp.stack([r[:-1], h[:, 0] * dr[:-1], r[1:], h[:, 0] * dr[1:]], axis=1), h


def element_fields(line, dofs: HermiteDofs):
    """Per element and quadrature point (n, Q, ·): r, r', r'' and λ."""
    u, h = _element_coefficients(line, dofs.r, dofs.dr)  # (n,4,3)
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


def _distributed_load(line, env, r, d1, t, v=None):
    """External load per unstretched length (n, Q, 3) [N/m]: weight and buoyancy,
    seabed contact (:meth:`~moorjax.model.environment.Seabed.contact`: spring,
    and ramped damper and friction when moving; flat or a bathymetry), the water's
    acceleration under waves (Froude–Krylov and added mass, as the linear
    element's), Morison drag on the velocity ``v`` relative to the current and
    the waves' velocity (``None``: at rest, no waves' loads). A Hermite line is
    buoyant everywhere: it must stay under the free surface (the linear element
    models partial wetting)."""
    lt = line.line_type
    weight = lt.wet_weight(env.rho, env.g)
    q = jnp.zeros_like(r).at[..., 2].add(-weight)
    if env.seabed is not None:
        q = q + env.seabed.contact(r, v, lt.diameter, weight, env.depth)[0]
    stretch = safe_norm(d1)[..., None]
    tangent = d1 / jnp.maximum(stretch, 1e-300)
    r_current, wave_u = r, None
    if env.waves is not None and v is not None:
        eta, wave_u, wave_a = env.waves.kinematics(r, t)
        r_current = r.at[..., 2].set(env.waves.current_height(r, eta))
        q = q + stretch * morison.fluid_inertia(lt, env, wave_a, tangent)
    if lt.drag is not None and (env.current is not None or v is not None):
        u = jnp.zeros_like(r) if v is None else v
        if env.current is not None:
            u = u - env.current.velocity_at(r_current, t)
        if wave_u is not None:
            u = u - wave_u
        q = q + stretch * morison.drag(lt, env, u, tangent)
    return q


def _interpolate(line, r_nodes, dr_nodes):
    """Values (n, Q, 3) at the quadrature points of a nodal Hermite field."""
    u, _ = _element_coefficients(line, r_nodes, dr_nodes)
    return jnp.einsum("aq,nai->nqi", H, u)


def quadrature_weights(line):
    """∫ ds weights (n, Q) [m] of the quadrature points."""
    return element_lengths(line)[:, None] * WQ


def _to_dofs(line, f, g, b):
    """Generalised forces on (positions, slopes) (n+1, 3) each from quadrature-point
    densities: Q_a = ∫ [ H_a f − H_a'/h g − H_a''/h² b ] ds."""
    h = element_lengths(line)[:, None]  # (n, 1)
    w = WQ * h
    qa = jnp.einsum("aq,nq,nqi->nai", H, w, f) - jnp.einsum("aq,nq,nqi->nai", DH, w / h, g)
    if b is not None:
        qa = qa - jnp.einsum("aq,nq,nqi->nai", DDH, w / h**2, b)
    zero = jnp.zeros((1, 3))
    force = jnp.concatenate([qa[:, 0], zero]) + jnp.concatenate([zero, qa[:, 2]])
    moment = jnp.concatenate([h * qa[:, 1], zero]) + jnp.concatenate([zero, h * qa[:, 3]])
    return force, moment


def generalized_forces(line, env, dofs: HermiteDofs, vel: HermiteDofs | None = None, t=0.0,
                       tension=None):
    """All non-inertial generalised forces (n+1, 3) on the node positions [N] and
    (n+1, 3) on the slopes [N·m]: tension λ/(1 + ε)·r' and internal damping
    BA·dε/dt along the tangent, bending, and the distributed loads. ``vel`` holds
    the node velocities and slope rates (``lam`` unused); ``None`` is at rest.
    ``tension``: (λ [N], ε [-]) at the quadrature points (n, Q) in place of the
    field ``dofs.lam`` and its strain."""
    lt = line.line_type
    r, d1, d2, lam = element_fields(line, dofs)
    if tension is None:
        eps = element_strain(line, lam)
    else:
        lam, eps = tension
    g = (lam / (1.0 + eps))[..., None] * d1  # ∂(internal work)/∂r'
    v = None
    if vel is not None:
        u, h = _element_coefficients(line, vel.r, vel.dr)
        v = jnp.einsum("aq,nai->nqi", H, u)
        dv = jnp.einsum("aq,nai->nqi", DH, u) / h  # rate of r'
        stretch = safe_norm(d1)
        tangent = d1 / jnp.maximum(stretch, 1e-300)[..., None]
        strain_rate = jnp.sum(tangent * dv, axis=-1)
        g = g + (lt.damping * strain_rate)[..., None] * tangent
    b = None
    if lt.ei is not None:
        gb, b = jax.grad(lambda a, c: jnp.sum(_bending_density(lt.ei, a, c)), argnums=(0, 1))(d1, d2)
        g = g + gb
    q = _distributed_load(line, env, r, d1, t, v)
    return _to_dofs(line, q, g, b)


def inertia_forces(line, env, dofs: HermiteDofs, acc: HermiteDofs):
    """Generalised inertia forces ∫ H_a μ r̈ ds of the accelerations ``acc`` (node
    accelerations and slope accelerations): the consistent mass m per unstretched
    length and, with added mass, ρA·(Ca_n(I − ttᵀ) + Ca_ax·ttᵀ) per stretched length."""
    lt = line.line_type
    _, d1, _, _ = element_fields(line, dofs)
    a = _interpolate(line, acc.r, acc.dr)
    f = lt.mass_per_length * a
    if lt.added_mass is not None:
        stretch = safe_norm(d1)
        tangent = d1 / jnp.maximum(stretch, 1e-300)[..., None]
        at = jnp.sum(a * tangent, axis=-1, keepdims=True) * tangent
        am = lt.added_mass
        f = f + env.rho * lt.area * stretch[..., None] * (am.ca_normal * (a - at) + am.ca_axial * at)
    return _to_dofs(line, f, jnp.zeros_like(f), None)


def extensibility(line, dofs: HermiteDofs):
    """The P_m-weighted extensibility integrals (2n+1,) [m] (Eq. 16/27)."""
    lt = line.line_type
    n = line.n_segments
    _, d1, _, lam = element_fields(line, dofs)
    eps = element_strain(line, lam)
    c = jnp.sum(d1 * d1, axis=-1) / (1.0 + eps) - (1.0 + eps)  # (n, Q)
    ce = jnp.einsum("mq,nq,nq->nm", P, quadrature_weights(line), c)  # (n, 3)
    out = jnp.zeros(2 * n + 1)
    return out.at[0:-1:2].add(ce[:, 0]).at[1::2].add(ce[:, 1]).at[2::2].add(ce[:, 2])


def extensibility_jacobian(line, dofs: HermiteDofs):
    """∂(extensibility)/∂λ (2n+1, 2n+1) [m/N]: ∫ P_m P_k ∂c/∂λ ds, banded (an
    element couples its three values), assembled from the pointwise derivative."""
    lt = line.line_type
    n = line.n_segments
    _, d1, _, lam = element_fields(line, dofs)
    s2 = jnp.sum(d1 * d1, axis=-1)

    def c(l):
        eps = element_strain(line, l)
        return s2 / (1.0 + eps) - (1.0 + eps)

    _, dc = jax.jvp(c, (lam,), (jnp.ones_like(lam),))  # elementwise in λ
    ke = jnp.einsum("mq,kq,nq,nq->nmk", P, P, quadrature_weights(line), dc)  # (n, 3, 3)
    idx = 2 * np.arange(n)[:, None] + np.arange(3)[None, :]
    out = jnp.zeros((2 * n + 1, 2 * n + 1))
    return out.at[idx[:, :, None], idx[:, None, :]].add(ke)


def static_residual(line, env, dofs: HermiteDofs, t=0.0):
    """Generalised forces of the line at rest and the extensibility residuals.

    Returns ``(force_r (n+1, 3) [N], moment_dr (n+1, 3) [N·m], constraint (2n+1,) [m])``:
    the generalised forces on the node positions and slopes (the line's pull on
    the end nodes included; zero at equilibrium on free unknowns), and the
    P_m-weighted extensibility integrals.
    """
    force, moment = generalized_forces(line, env, dofs, None, t)
    return force, moment, extensibility(line, dofs)


class HermiteElement(AbstractElement):
    """Wu et al.'s mixed Hermite-cubic element (see the module docstring).

    Its unknowns are not node positions alone (:class:`HermiteDofs`), so its
    statics has its own solve (:func:`moorjax.statics.hermite.hermite_statics_core`,
    called by :func:`moorjax.statics.fem.solve_line_statics`) and its dynamic
    state carries the slopes (:class:`~moorjax.element.hermite_motion.HermiteState`,
    see :mod:`moorjax.element.hermite_motion`): the dynamics driver uses its
    ``state_*`` methods; the node-only methods of the linear element raise.

    Args:
        slack_ratio: compression stiffness of a unilateral line as a fraction of
            its EA [-] (the slack regularisation of the module notes; 1e-4).
        slack_width: δ [N], the tension over which the unilateral law's kink
            at λ = 0 is rounded in the tension field's strain
            (:func:`strain_of_tension`; 0, the default: kinked). It acts where
            the field λ is solved: the statics and ``MixedTension``.
        tension: how the tension follows from the slopes in the dynamics:
            :class:`~moorjax.element.hermite_motion.ProjectedTension` (the
            default: Wu's continuous quadratic field, the law on the strain
            projected onto it), ``StrainTension`` (the unilateral law at each quadrature
            point) or ``MixedTension`` (Wu's continuous field eliminated per
            evaluation); see that module for the measurements that chose the
            default. Statics always solve Wu's field.
        mesh: the elements' relative lengths (n,) [-] from end A (normalised to
            the line's length; ``None``: equal elements). A node placed at the
            touchdown, where the line's curvature jumps, is what a cubic needs
            on a grounded line: :func:`moorjax.statics.hermite.touchdown_mesh`
            finds one from the statics.
    """

    slack_ratio: float = 1e-4
    tension: "AbstractTension" = None  # noqa: F821
    mesh: jax.Array | None = None
    slack_width: float = 0.0

    def __init__(self, slack_ratio=1e-4, tension=None, mesh=None, slack_width=0.0):
        from .._numerics import as_float
        from .hermite_motion import ProjectedTension

        if isinstance(slack_ratio, (int, float)) and not (0.0 < slack_ratio <= 1.0):
            raise ValueError(f"HermiteElement: slack_ratio = {slack_ratio} must be in (0, 1] "
                             "(compression stiffness over EA; 1e-4 is the default)")
        if isinstance(slack_width, (int, float)) and not (0.0 <= slack_width < np.inf):
            raise ValueError(f"HermiteElement: slack_width = {slack_width} N must be finite and >= 0 "
                             "(the tension over which the slack kink is rounded; 0: kinked)")
        self.slack_ratio = slack_ratio
        self.slack_width = slack_width
        self.tension = ProjectedTension() if tension is None else tension
        if mesh is not None and not isinstance(mesh, jax.core.Tracer):
            m = np.asarray(mesh, dtype=float)
            if m.ndim != 1 or m.size < 1 or not np.all(np.isfinite(m)) or np.any(m <= 0.0):
                raise ValueError("HermiteElement: mesh must be a 1-d array of positive relative "
                                 f"element lengths; got {mesh!r}")
            mesh = as_float(m)
        self.mesh = mesh

    @property
    def banded_jacobian(self) -> bool:
        return False

    # -- the dynamics driver's packed state ------------------------------------
    def provides_stage_factor(self, line) -> bool:
        from .hermite_stage import provides_stage_factor

        return provides_stage_factor(line)

    def stage_factor(self, line, env, t, q, c):
        from .hermite_stage import stage_factor

        return stage_factor(line, env, t, q, c)

    def state_rate(self, line, env, t, q):
        from .hermite_motion import state_rate

        return state_rate(line, env, t, q)

    def state_end_forces(self, line, env, t, q):
        from .hermite_motion import end_forces

        return end_forces(line, env, t, q)

    @property
    def carries_end_inertia(self) -> bool:
        return True

    def state_end_response(self, line, env, t, q):
        from .hermite_motion import end_response

        return end_response(line, env, t, q)

    def state_outputs(self, line, env, t, q):
        from .hermite_motion import outputs

        return outputs(line, env, t, q)

    def state_rows(self, line) -> int:
        """[r, v] rows of the free nodes, then [d, dv] rows of every node (2n)."""
        return 2 * line.n_segments

    def unpack_state(self, line, q):
        from .hermite_motion import unpack_hermite

        return unpack_hermite(line, q)

    # -- node-only interface: not available ------------------------------------
    def _node_only(self):
        raise NotImplementedError(
            "HermiteElement: its state carries node slopes, so the node-only methods "
            "(nodal_forces, accelerations, segment_tensions, end_forces) do not apply; "
            "the dynamics driver uses state_rate/state_end_forces/state_outputs"
        )

    def nodal_forces(self, line, env, r, v, t=0.0):
        self._node_only()

    def accelerations(self, line, env, t, r, v):
        self._node_only()

    def segment_tensions(self, line, r, v):
        self._node_only()

    def end_forces(self, line, env, r, v, t=0.0):
        self._node_only()


def clamped_slopes(line, t=0.0):
    """The clamped end slopes: ``[(node, direction), ...]`` with the node index (0
    or n) and the unit vector (3,) the slope dr/ds must keep there (from end A the
    clamp's direction, from end B its reverse). Only the length of such a slope
    (1 + ε) is an unknown; the two components of the generalised force across it
    are the clamp's end moment. Structure: empty for pinned ends."""
    from ..model.ends import clamp_directions

    d_a, d_b = clamp_directions(line.end_a, line.end_b, t)
    return [(node, d) for node, d in ((0, d_a), (line.n_segments, d_b)) if d is not None]
