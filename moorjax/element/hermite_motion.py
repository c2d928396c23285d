"""Dynamics of a Hermite line: its state, consistent mass and tension closure.

The state of a line of :class:`~moorjax.element.hermite.HermiteElement` s is
second order in the node positions and slopes; the tension field λ is not a
state. :class:`HermiteState` packs, for the dynamics driver, the free nodes'
[r, ṙ] (n−1 rows) and every node's slope scaled by the element length,
d = h·r' [m], with its rate ḋ [m/s] (n+1 rows): one (2n, 6) array whose
columns are all metres and metres per second, so the driver's error norm
weighs slopes like positions (h = L/n, the mean element length, also where
``HermiteElement.mesh`` grades the elements).

The accelerations solve the consistent mass matrix M (the Hermite shape
functions' ∫ H_a μ H_b ds, μ = m·I plus the added mass ρA·|r'|·(Ca_n(I − ttᵀ) +
Ca_ax ttᵀ); dense, 6(n+1) square) with the prescribed end accelerations on the
right-hand side. A clamped end's slope (:class:`~moorjax.model.ends.ClampedEnd`,
fixed) accelerates along the clamp's direction only: the solve is restricted
to that direction for its row (:func:`_clamped_solve`).

How the extensibility condition (Wu et al. Eq. 27) enters — the tension closure:

- :class:`MixedTension`: Wu's quadratic field λ (2n+1 values) eliminated at
  every evaluation of the equations of motion, by Newton's method on Eq. 27
  (banded Jacobian :func:`~moorjax.element.hermite.extensibility_jacobian`)
  for the current slopes, from λ = T(|r'| − 1) at the nodes and midpoints.
  Its derivative with respect to the state is the implicit one (the last
  Newton step is taken on a stopped-gradient iterate with a frozen Jacobian),
  so the implicit solvers' Jacobians and ``jax.grad`` see the exact
  constrained dynamics: an ODE on (U, U̇), no DAE.
- :class:`ProjectedTension` (the default): Wu's continuous quadratic field,
  λ = Π T(Π ε) with ε = |r'| − 1 and Π the L2 projection onto that field (Eq.
  27 for small strains: the field's strain is the projection of the stretch);
  ``continuous=False`` projects within each element. The law acts on the
  projected strain, so the slack kink needs no inverse and no inner solve;
  the forces are the gradient of ∫ ψ(Π ε) ds; the stages' Newton matrix is the
  per-element field's (block-tridiagonal).
- :class:`StrainTension`: λ = T(|r'| − 1) at every quadrature
  point, the axial law's unilateral tension directly (a displacement-only
  Hermite element: no regularisation of the slack law, no inner solve).

A DAE through a mass matrix is not an option with diffrax's solvers (no
singular mass matrices) and a stiff penalty on Eq. 27 adds an axial time
scale faster than EA's own. Measured on case A (10 elements, Kvaerno5,
rtol 1e-5, atol 1e-4 m): both closures follow MoorDyn through the first
surge; in the first trough the mixed closure's step size collapsed at
t ≈ 7.25 s (where the lower line re-tensions: the field crosses the slack
regularisation's kink, c·EA to EA, inside the inner Newton; with 8 inner
iterations the run was still stepping slowly after 10 min and was stopped);
with a softer kink (``slack_ratio`` 1e-3) it runs through case A's trough
(RMS/std 1.36 % over 0–9 s against the strain closure's 2.30 %) but fails
the same way in case B's first snap (t ≈ 4.85 s), while the strain closure, whose kink is the law's own (as
the linear element's), runs through. So the strain closure is the default;
the Newmark reference keeps Wu's mixed field, and ``MixedTension`` is there
for runs without slack. Strain closure at 10 elements, 60 s (RMS/std of the
fairlead force against MoorDyn): case A 1.51 % (0.99 % at 13 elements),
case B 0.74 %. Session 43: with the slack kink rounded
(``HermiteElement(slack_ratio=1e-3, slack_width=2000.0)``, δ = 2 kN) and
``MixedTension(iterations=8)`` the mixed closure runs through both cases:
A 0.83 %, B 0.78 % at 10 elements over 60 s (the snap's error 2.5 times
smaller), at the cost of its dense solves. But δ and c were found on these
two cases: on other amplitudes it is worse than the strain closure (A at
2.5 m 0.95 against 0.78 %, B at 1 m 1.09 against 0.66 %) or fails (B at 3 m),
so it is not the default (``benchmarks/README.md``, session 43).

Session 44: the strain closure over-constrains a sagging cubic (its stretch
|r'| − 1 is no polynomial: membrane locking); projected onto Wu's quadratic
field it does not. At 10 elements over 60 s against MoorDyn: case A 0.92 %
(strain closure 1.53 %, the per-element projection 1.13 %), case B 0.72 %
(0.74 %). Over 6 drawn surges of each case's line and 2 other amplitudes of
each (20 s, against moorjax's own N = 160) it is better than the strain
closure on 8 of 16, within 0.025 % on 4 and worse on 4 (by up to 0.20 %:
A draw 0.97 → 1.16 %, A at 2.5 m 0.78 → 0.96 %); the geometric mean of the
ratio of errors is 0.80 on case A's line, 0.92 on B's
(``benchmarks/README.md``, session 44).
Run time about 1.3 times the strain closure's (A, 20 s: 0.75 against 0.59 s).
A per-element projection onto linears gives 0.94–1.0 % on case A but leaves
a zero-energy mode on a straight line (the slopes' lengths scaled together)
and doubles the error of taut surges (A at 2.5 m 1.67 %).
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax
import jax.lax as lax
import jax.numpy as jnp
import jax.scipy.linalg
import numpy as np
from jaxtyping import Array

from .._numerics import safe_norm
from ..linalg.ordering import after
from ..linalg import block_tridiagonal as btd
from .hermite import (H, P, WQ, HermiteDofs, clamped_slopes, element_fields, element_lengths,
                      extensibility, extensibility_jacobian, generalized_forces,
                      quadrature_weights)


class HermiteState(eqx.Module):
    """Dynamic state of a Hermite line.

    Attributes:
        r: (n−1, 3) free node positions [m].
        v: (n−1, 3) their velocities [m/s].
        d: (n+1, 3) node slopes times the element length, h·dr/ds [m].
        dv: (n+1, 3) their rates [m/s].
    """

    r: Array
    v: Array
    d: Array
    dv: Array

    def packed(self):
        """The (2n, 6) solver array: [r, v] rows, then [d, dv] rows (with leading
        member axes where the state has them, as an ensemble's start)."""
        return jnp.concatenate([jnp.concatenate([self.r, self.v], axis=-1),
                                jnp.concatenate([self.d, self.dv], axis=-1)], axis=-2)


def unpack_hermite(line, q) -> HermiteState:
    n = line.n_segments
    return HermiteState(r=q[:n - 1, :3], v=q[:n - 1, 3:], d=q[n - 1:, :3], dv=q[n - 1:, 3:])


# -- tension closures ------------------------------------------------------------

class AbstractTension(eqx.Module):
    """How a Hermite line's tension follows from its slopes."""

    def stage_closure(self):
        """The element-local closure whose block-tridiagonal matrix the implicit
        stages' Newton iteration uses for this one (:mod:`.hermite_stage`): itself
        where its tension depends on each element's own unknowns (the matrix is
        then exact), ``None`` for the dense Jacobian."""
        return None

    @abc.abstractmethod
    def resolve(self, line, dofs: HermiteDofs):
        """``(dofs with lam set, tension)``: ``tension`` is ``None`` when the field
        ``dofs.lam`` is used, else (λ [N], ε [-]) at the quadrature points (n, Q)."""


class MixedTension(AbstractTension):
    """Wu's quadratic tension field, eliminated by Newton on Eq. 27 (``iterations``
    steps from the strain's tension, then one implicit-derivative step)."""

    iterations: int = eqx.field(static=True, default=3)

    def resolve(self, line, dofs):
        lt = line.line_type
        n = line.n_segments
        r0, d0 = lax.stop_gradient(dofs.r), lax.stop_gradient(dofs.dr)
        # start: the tension of the stretch at the nodes and midpoints
        half = jnp.stack([d0[:-1], d0[1:]], axis=1)  # (n, 2, 3)
        h = element_lengths(line)[:, None]
        mid = 1.5 * (r0[1:] - r0[:-1]) / h - 0.25 * (half[:, 0] + half[:, 1])  # r'(½)
        pts = jnp.zeros((2 * n + 1, 3)).at[0::2].set(d0).at[1::2].set(mid)
        strain = safe_norm(pts) - 1.0
        ea = lt.axial.nominal_ea()
        # the exact inverse of strain_of_tension for a linear EA (slack regularised)
        lam = jnp.where(strain >= 0.0, lt.axial.tension(strain),
                        line.element.slack_ratio * ea * strain)

        def g(lam, r, dr):
            return extensibility(line, HermiteDofs(r=r, dr=dr, lam=lam))

        def jac_of(lam):
            return extensibility_jacobian(line, HermiteDofs(r=r0, dr=d0, lam=lam))

        def newton(_, lam):
            return lam - jnp.linalg.solve(jac_of(lam), g(lam, r0, d0))

        lam = lax.fori_loop(0, self.iterations, newton, lam)
        jac = lax.stop_gradient(jac_of(lam))
        lam = lam - jnp.linalg.solve(jac, g(lam, dofs.r, dofs.dr))
        return HermiteDofs(r=dofs.r, dr=dofs.dr, lam=lam), None


class StrainTension(AbstractTension):
    """λ = T(|r'| − 1) at each quadrature point (the unilateral law itself)."""

    def stage_closure(self):
        return self

    def resolve(self, line, dofs):
        _, d1, _, _ = element_fields(line, dofs)
        strain = safe_norm(d1) - 1.0
        return dofs, (line.line_type.axial.tension(strain), strain)


def projection_matrix(degree: int) -> np.ndarray:
    """(Q, Q) L2 projection, per element, of values at the Gauss points onto the
    polynomials of degree ≤ ``degree`` in ξ (discrete, in the quadrature's own
    weights: Π = V·(Vᵀ W V)⁻¹·Vᵀ W with V the Legendre polynomials at the points)."""
    from numpy.polynomial import legendre

    from .hermite import XI

    if not 0 <= degree < len(XI):
        raise ValueError(f"ProjectedTension: degree = {degree} must be in 0..{len(XI) - 1}")
    x = 2.0 * XI - 1.0
    v = np.stack([legendre.legval(x, np.eye(degree + 1)[k]) for k in range(degree + 1)], axis=1)
    w = np.diag(WQ)
    return v @ np.linalg.solve(v.T @ w @ v, v.T @ w)


class ProjectedTension(AbstractTension):
    """Wu's quadratic tension field from the projected strain: λ = Π T(Π ε), ε = |r'| − 1.

    Π is the L2 projection onto Wu's field (``continuous``, the default: the
    continuous piecewise quadratics of his 2n + 1 values at the nodes and
    midpoints), or within each element onto polynomials of degree ``degree``
    (``continuous=False``; 2: the quadratics, discontinuous between elements).
    For small strains Eq. 27, ∫ P_m [r'·r'/(1 + ε) − (1 + ε)] ds = 0, reads
    ∫ P_m (|r'| − 1 − ε(λ)) ds = 0: the field's strain is the projection of the
    cubic's stretch, which is what Π ε is. The axial law then acts on the
    projected strain at each point, so the slack kink needs no inverse (no
    inner Newton, no regularisation); the second Π makes the forces the
    gradient of the strain energy ∫ ψ(Π ε) ds (δ∫ψ(Πε) = ∫ Π[T(Πε)]·δε ds: Π is
    self-adjoint), so the stiffness stays symmetric. Internal damping stays
    pointwise (BA·dε/dt; on the projected rate it was worse: case A 1.39 →
    1.49 % with the per-element field).

    Why: the stretch |r'| − 1 of a curved cubic is no polynomial, and asking it
    to follow EA pointwise over-constrains a sagging element (membrane
    locking). On a straight line the stretch of a C¹ cubic already is a
    continuous piecewise quadratic: either projection changes nothing there and
    leaves no zero-energy mode (a per-element degree 1 leaves one, the slopes'
    lengths scaled together along the whole line).

    The continuous field couples the line (Π solves Wu's field's Gram matrix,
    block-tridiagonal, O(n), without LAPACK); the implicit stages' Newton iteration uses the
    per-element field's block-tridiagonal matrix for it (:meth:`stage_closure`),
    which is exact where the two agree (a straight taut line) and near it
    elsewhere: case A at 10 elements runs in 0.70–0.75 s (20 s simulated), against
    0.65 s with the per-element field and 2.17 s
    with the dense Jacobian.
    """

    degree: int = eqx.field(static=True, default=2)
    continuous: bool = eqx.field(static=True, default=True)

    def __check_init__(self):
        projection_matrix(self.degree)  # refuses a degree outside 0..Q−1
        if self.continuous and self.degree != 2:
            raise ValueError(f"ProjectedTension: the continuous field is Wu's quadratic one "
                             f"(degree 2), got degree = {self.degree}; use continuous=False for "
                             "a per-element projection of another degree")

    def stage_closure(self):
        return ProjectedTension(self.degree, continuous=False) if self.continuous else self

    def resolve(self, line, dofs):
        _, d1, _, _ = element_fields(line, dofs)
        strain = safe_norm(d1) - 1.0
        if self.continuous:
            gram = field_gram(line)

            def proj(f):
                return field_projection(line, gram, f)
        else:
            matrix = projection_matrix(self.degree)

            def proj(f):
                return jnp.einsum("pq,nq->np", matrix, f)
        return dofs, (proj(line.line_type.axial.tension(proj(strain))), strain)


def field_gram(line) -> btd.BlockTridiagonalLU:
    """Wu's field's Gram matrix ∫ P_m P_k ds, factored: block k holds the values at
    node k and at the midpoint of element k (the last block node n's), padded to
    3×3 with a unit placeholder so that the pivots invert by cofactors
    (:func:`~moorjax.linalg.block_tridiagonal.factor3`: no LAPACK call, which
    batched beside the stages' factorisations would break their one-at-a-time
    ordering, ``tests/test_lapack_ordering.py``)."""
    n = line.n_segments
    ge = jnp.einsum("mq,kq,nq->nmk", P, P, quadrature_weights(line))  # (n, 3, 3)
    z = jnp.zeros((n + 1, 3, 3), ge.dtype)
    diag = (z.at[:n, :2, :2].add(ge[:, :2, :2]).at[1:, 0, 0].add(ge[:, 2, 2])
            .at[:, 2, 2].set(1.0).at[n, 1, 1].set(1.0))
    upper = z.at[:n, :2, 0].set(ge[:, :2, 2])
    lower = z.at[1:, 0, :2].set(ge[:, 2, :2])
    return btd.factor3(lower, diag, upper)


def field_projection(line, gram, f):
    """The L2 projection of values f (n, Q) at the quadrature points onto Wu's
    continuous quadratic field, at the quadrature points (n, Q); ``gram`` from
    :func:`field_gram`."""
    n = line.n_segments
    be = jnp.einsum("mq,nq,nq->nm", P, quadrature_weights(line), f)  # (n, 3)
    rhs = jnp.zeros((n + 1, 3), be.dtype).at[:n, :2].add(be[:, :2]).at[1:, 0].add(be[:, 2])
    x = btd.solve(gram, rhs)
    values = jnp.concatenate([x[:n, :2], x[1:, :1]], axis=1)  # (n, 3): node, midpoint, next node
    return jnp.einsum("mq,nm->nq", P, values)


# -- mass, forces, accelerations ----------------------------------------------

def element_mass(line, env, dofs: HermiteDofs):
    """Each element's consistent mass (n, 4, 4, 3, 3) [kg] on the state's unknowns
    (r_k, d_k, r_k+1, d_k+1), d = h̄·r' with h̄ = L/n, with the added mass of its
    wet length. (Element e's shape functions act on h_e·r' = (h_e/h̄)·d.)"""
    lt = line.line_type
    he = element_lengths(line)
    rho = he / line.segment_length
    one = jnp.ones_like(rho)
    scale = jnp.stack([one, rho, one, rho], axis=1)  # (n, 4)
    _, d1, _, _ = element_fields(line, dofs)
    eye = jnp.eye(3)
    mu = lt.mass_per_length * jnp.broadcast_to(eye, d1.shape[:-1] + (3, 3))
    if lt.added_mass is not None:
        stretch = safe_norm(d1)
        t = d1 / jnp.maximum(stretch, 1e-300)[..., None]
        tt = t[..., :, None] * t[..., None, :]
        am = lt.added_mass
        mu = mu + env.rho * lt.area * stretch[..., None, None] * (
            am.ca_normal * (eye - tt) + am.ca_axial * tt)
    me = jnp.einsum("aq,bq,nq,nqij->nabij", H, H, WQ * he[:, None], mu)
    return me * (scale[:, :, None] * scale[:, None, :])[..., None, None]


def _element_unknowns(n):
    """(n, 4) indices of each element's unknowns in the interleaved 2n+2."""
    return 2 * np.arange(n)[:, None] + np.arange(4)[None, :]


def _assemble(me):
    """The dense mass matrix ((2n+2)·3, (2n+2)·3) of the element blocks."""
    n = me.shape[0]
    idx = _element_unknowns(n)
    m = jnp.zeros((2 * n + 2, 2 * n + 2, 3, 3), me.dtype)
    m = m.at[idx[:, :, None], idx[:, None, :]].add(me)
    return jnp.transpose(m, (0, 2, 1, 3)).reshape(3 * (2 * n + 2), 3 * (2 * n + 2))


def _mass_apply(me, x):
    """M·x for x ((2n+2)·3, c) from the element blocks, O(n): its derivative
    carries the blocks' tangents, not a dense matrix's (forward mode through a
    dense assembly cost a (2n+2)²·9 tangent per seed: most of a Hermite step's
    Jacobian)."""
    n = me.shape[0]
    idx = _element_unknowns(n)
    xs = x.reshape(2 * n + 2, 3, -1)
    ye = jnp.einsum("nabij,nbjc->naic", me, xs[idx])
    return jnp.zeros_like(xs).at[idx].add(ye).reshape(x.shape)


def _nodes(line, t, q):
    """All unknowns (2n+2, 3) interleaved [r_0, d_0, r_1, d_1, …] and their rates."""
    n = line.n_segments
    s = unpack_hermite(line, q)
    r = jnp.concatenate([line.end_a.position(t)[None], s.r, line.end_b.position(t)[None]])
    v = jnp.concatenate([line.end_a.velocity(t)[None], s.v, line.end_b.velocity(t)[None]])
    u = jnp.zeros((2 * n + 2, 3)).at[0::2].set(r).at[1::2].set(s.d)
    ud = jnp.zeros((2 * n + 2, 3)).at[0::2].set(v).at[1::2].set(s.dv)
    return u, ud


def _partition(n):
    """Flat indices of the free unknowns (all but the end positions) and of the
    prescribed ones (end A's position, then end B's) in the (2n+2)·3 vector."""
    free = np.ones(2 * n + 2, bool)
    free[[0, 2 * n]] = False
    fi = np.repeat(np.flatnonzero(free), 3) * 3 + np.tile(np.arange(3), 2 * n)
    pi = np.concatenate([np.arange(3), 6 * n + np.arange(3)])
    return fi, pi


def forces_and_mass(line, env, t, u, ud):
    """The generalised forces f (2n+2, 3) on all unknowns (interleaved, as
    :func:`_nodes`), the element masses (n, 4, 4, 3, 3), the resolved dofs and
    the tension closure's (λ, ε) for the unknowns u and their rates ud."""
    n, h = line.n_segments, line.segment_length
    dofs = HermiteDofs(r=u[0::2], dr=u[1::2] / h, lam=jnp.zeros(2 * n + 1))
    dofs, tension = line.element.tension.resolve(line, dofs)
    vel = HermiteDofs(r=ud[0::2], dr=ud[1::2] / h, lam=dofs.lam)
    force, moment = generalized_forces(line, env, dofs, vel, t, tension)
    f = jnp.zeros((2 * n + 2, 3)).at[0::2].set(force).at[1::2].set(moment / h)
    return f, element_mass(line, env, dofs), dofs, tension


def dynamics(line, env, t, q):
    """Accelerations (2n+2, 3) of all unknowns (interleaved; the ends' are their
    paths'), the generalised forces (2n+2, 3), the element masses (n, 4, 4, 3,
    3), the mass matrix's columns of the prescribed unknowns M[:, p] ((2n+2)·3,
    6), the field, and S = M_ff⁻¹M_fp (free unknowns × 6): how the free
    accelerations fall with the ends' (end A's, end B's) accelerations beyond
    their paths' (one factorisation serves both)."""
    n = line.n_segments
    u, ud = _nodes(line, t, q)
    f, me, dofs, tension = forces_and_mass(line, env, t, u, ud)
    size = 3 * (2 * n + 2)
    fi, pi = _partition(n)
    a_p = jnp.concatenate([line.end_a.acceleration(t), line.end_b.acceleration(t)])
    m_cp = _mass_apply(me, jnp.zeros((size, 6), me.dtype).at[pi, np.arange(6)].set(1.0))  # M[:, pi]
    m_fp = m_cp[fi]
    rhs = f.reshape(-1)[fi] - m_fp @ a_p
    # one solve for the accelerations and S = M_ff⁻¹·M_fp (how the free unknowns
    # follow the ends' accelerations); a clamped slope accelerates along its clamp only
    cols = jnp.concatenate([rhs[:, None], m_fp], axis=1)
    clamps = clamped_slopes(line, t)
    # one batched LAPACK call at a time (moorjax.linalg.ordering): the mass
    # matrix is factored after the forces (and their tension field's solve), and
    # the mass depends (by zero) on the forces, also in derivatives: a
    # derivative's solve, M⁻¹(db − dM·x), then waits for the value's x (with dM
    # exactly zero lax.custom_linear_solve would solve M⁻¹db beside it)
    me_after = after(me, cols)
    if clamps:
        sol = _clamped_solve(_assemble(me_after)[np.ix_(fi, fi)], cols, fi, clamps)
    else:
        def m_ff(x):  # M_ff·x through the element blocks
            return _mass_apply(me_after, jnp.zeros((size, x.shape[1]), x.dtype).at[fi].set(x))[fi]

        sol = _spd_solve(m_ff, _assemble(lax.stop_gradient(me_after))[np.ix_(fi, fi)], cols)
    a_f, s = sol[:, 0], sol[:, 1:]
    a = jnp.zeros(size).at[fi].set(a_f).at[pi].set(a_p).reshape(2 * n + 2, 3)
    return a, f, me, m_cp, dofs, tension, s


def _clamped_solve(m_ff, rhs, fi, clamps):
    """Accelerations of the free unknowns with each clamped slope accelerating
    along its clamp's direction only (a fixed clamp: its length, the end strain,
    is the one free component): M a = f restricted to a = B·a_r, Bᵀ M B a_r = Bᵀ f."""
    k = len(fi)
    held = {}
    for node, d in clamps:
        held[node] = (np.searchsorted(fi, 3 * (2 * node + 1) + np.arange(3)), d)
    taken = np.concatenate([pos for pos, _ in held.values()])
    keep = np.setdiff1d(np.arange(k), taken)
    basis = [jnp.asarray(np.eye(k)[:, keep])]
    for pos, d in held.values():
        basis.append(jnp.zeros((k, 1)).at[pos, 0].set(d))
    b = jnp.concatenate(basis, axis=1)
    m_r = b.T @ m_ff @ b
    a_r = _spd_solve(lambda x: m_r @ x, lax.stop_gradient(m_r), b.T @ rhs)
    return b @ a_r


def _spd_solve(matvec, m, rhs):
    """M⁻¹·rhs (k, c) for a symmetric positive definite mass matrix: ``matvec``
    applies M (differentiable), ``m`` (k, k) is M's value (not differentiated)
    for a Cholesky factorisation. No pivots: an LU solve's row permutation is
    a sequential loop of k steps on CPU. Derivatives as ``jnp.linalg.solve``'s,
    d(M⁻¹b) = M⁻¹(db − dM·M⁻¹b), through ``lax.custom_linear_solve``: the
    factorisation is never differentiated."""
    factor = jax.scipy.linalg.cho_factor(m)
    solve = lambda _, b: jax.scipy.linalg.cho_solve(factor, b)  # noqa: E731
    return lax.custom_linear_solve(matvec, rhs, solve, symmetric=True)


def state_rate(line, env, t, q):
    a, *_ = dynamics(line, env, t, q)
    return _rate_of(line, q, a)


def end_forces(line, env, t, q):
    """Forces (3,), (3,) [N] on the end points: the generalised force on each end
    node minus its consistent inertia (→ the end tension as elements shrink)."""
    a, f, me, *_ = dynamics(line, env, t, q)
    return _net_end_forces(f, me, a, line.n_segments)


def _net_end_forces(f, me, a, n):
    """End A's and end B's forces (3,) [N]: the generalised forces on their
    positions (unknowns 0 and 2n of the interleaved 2n+2) minus their consistent
    inertia M·a (``me``: the element masses)."""
    net = (f.reshape(-1) - _mass_apply(me, a.reshape(-1, 1))[:, 0]).reshape(2 * n + 2, 3)
    return net[0], net[2 * n]


def _rate_of(line, q, a):
    """dq/dt (2n, 6) from the accelerations a (2n+2, 3) of all unknowns."""
    n = line.n_segments
    s = unpack_hermite(line, q)
    return jnp.concatenate([jnp.concatenate([s.v, a[2:2 * n:2]], axis=-1),
                            jnp.concatenate([s.dv, a[1::2]], axis=-1)], axis=0)


def end_response(line, env, t, q):
    """The rate and end forces, and how they change with the ends' accelerations.

    With its ends' accelerations a_e = (a_A, a_B) (6,) [m/s²] added to their
    paths' (a body's fairlead accelerates with the body), the free unknowns
    accelerate by −S·a_e and the end forces change by −M_e·a_e, M_e = M_pp −
    M_pf·S the line's end inertia as the ends see it (Schur complement of the
    consistent mass; symmetric positive definite) [kg].

    Returns:
        rate: dq/dt (2n, 6) at the paths' end accelerations.
        forces: (2, 3) the forces on end A and end B [N] (as :func:`end_forces`).
        rate_gain: (2n, 6, 6) ∂(dq/dt)/∂a_e [s⁻¹·…: m/s² per m/s²].
        force_gain: (2, 3, 6) ∂forces/∂a_e = −M_e [kg].
    """
    n = line.n_segments
    a, f, me, m_cp, _, _, s = dynamics(line, env, t, q)
    fi, pi = _partition(n)
    forces = jnp.stack(_net_end_forces(f, me, a, n))
    da = jnp.zeros((3 * (2 * n + 2), 6)).at[fi].set(-s).at[pi].set(jnp.eye(6))
    m_e = m_cp[pi] - m_cp[fi].T @ s  # M_pp − M_pf·S (M symmetric)
    da = da.reshape(2 * n + 2, 3, 6)
    gain = jnp.concatenate([da[2:2 * n:2], da[1::2]], axis=0)  # the rate's acceleration rows
    rate_gain = jnp.concatenate([jnp.zeros_like(gain), gain], axis=1)
    return _rate_of(line, q, a), forces, rate_gain, -m_e.reshape(2, 3, 6)


def outputs(line, env, t, q):
    """Node positions (n+1, 3) [m], velocities (n+1, 3) [m/s] and the effective
    tension at element midpoints (n,) [N]."""
    n, h = line.n_segments, line.segment_length
    u, ud = _nodes(line, t, q)
    dofs = HermiteDofs(r=u[0::2], dr=u[1::2] / h, lam=jnp.zeros(2 * n + 1))
    dofs, tension = line.element.tension.resolve(line, dofs)
    if tension is None:
        return dofs.r, ud[0::2], dofs.lam[1::2]
    # midpoint of the element: the middle Gauss point (ξ = ½ for 5 points)
    return dofs.r, ud[0::2], tension[0][:, 2]


def static_state(line, dofs: HermiteDofs) -> HermiteState:
    """A static solution as a state at rest."""
    h = line.segment_length
    r = dofs.r[1:-1]
    d = h * dofs.dr
    return HermiteState(r=r, v=jnp.zeros_like(r), d=d, dv=jnp.zeros_like(d))


