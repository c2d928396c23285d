"""A linearly implicit (Rosenbrock-W) time stepper: one matrix per step, no Newton iteration.

ROS34PW2 (Rang & Angermann 2005, *New Rosenbrock W-methods of order 3 for
partial differential algebraic equations of index 1*, BIT 45, 761–787): 4
stages, order 3 with an embedded order-2 solution, L-stable and stiffly
accurate, and a W-method (its order conditions hold, to order 2, for any
matrix W in place of the Jacobian ∂f/∂y). In Hairer & Wanner's transformed
variables (Solving ODEs II, IV.7, Eq. 7.25), u = Γk:

    (1/(γh) − W) uᵢ = f(tₙ + αᵢh, yₙ + Σⱼ₍ⱼ<ᵢ₎ ãᵢⱼ uⱼ) + Σⱼ₍ⱼ<ᵢ₎ (c̃ᵢⱼ/h) uⱼ + γᵢ h ∂f/∂t
    yₙ₊₁ = yₙ + Σ mⱼ uⱼ,   error estimate Σ (mⱼ − m̂ⱼ) uⱼ

with ã = AΓ⁻¹, c̃ = diag(1/γ) − Γ⁻¹, m = bΓ⁻¹ (m̂ from the embedded weights).

Every stage is one linear solve with the same matrix and no Newton iteration,
so a step cannot fail to converge: at the kinks of touchdown and slack, where
the Kvaerno methods' Newton stalls and their steps are rejected, this method
only loses accuracy. The embedded estimate alone does not see that loss: a
force that switches on within a step (a node landing on the seabed) is
treated explicitly by both solutions alike. On a 410 m chain settling on a
soft seabed in waves (``wavekin_3.txt`` of MoorDyn's tests, MoorDyn's seabed
damping step) 47 steps of about 1 s were all accepted while the fairlead
tension grew into an oscillation of 1.6 MN (93× the reference's std). So each
step also measures its linearisation error: the residual of f(t₁, y₁) against
the step's linear model, as the state correction a Newton iteration would
make (:meth:`RosenbrockW._with_linearisation_error`), O(h³) where f is smooth.
With it the same run takes 71 steps (5 rejected) and stays within 0.29 std
(6.4 % at rtol 3e-6), and reference case A reaches Kvaerno5's error at the same
tolerances (N = 40, rtol 1e-5: 0.82 % against 0.84 %; without the check
1.09 %). For lines of the linear element W comes in mass form
(:class:`~moorjax.linalg.mass_form.MassFormW`: nodal masses and 3×3
block-tridiagonal force derivatives, each differentiated on its own small
function), and I − γhW is solved through one 3×3 block-tridiagonal system in
the velocities; otherwise W is the block-tridiagonal band of the Jacobian (18
coloured JVPs of the vector field), factored by the reduced 3×3 block solve of
:class:`~moorjax.linalg.banded_solver.SecondOrderBandSolver`. ∂f/∂t (the
prescribed motions) is one forward difference per step
(:meth:`RosenbrockW._time_derivative`): without it the method drops to order 1
on a line whose end is driven (measured on a forced stiff scalar problem,
``tests/test_rosenbrock.py``). Where W's band comes with a time column (lines
of the linear element in steady water, whose equations depend on time through
their ends alone: :func:`~moorjax.element.linear.stiff_band`), that column is
∂f/∂t instead, as a W-method allows (its order-2 conditions hold for any W, and
in the autonomous form the time column is one more column of W), and the
step saves that evaluation (``benchmarks/README.md``, "Session 31").

W is the Jacobian at the step's start by default. ``jacobian_age`` > 1 keeps it
for that many accepted steps (rebuilding it also after a step cut below
``shrink``·(previous step), usually a rejection), which the W-method's order
tolerates but its accuracy on mooring lines does not: on reference case A
(chain catenary with seabed contact, N = 40, rtol 1e-5) a Jacobian kept for 2
steps raised the fairlead-tension error from 1.1 % to 5.6 %, since the contact
stiffness of the nodes that touch down or lift off is stale in W (at a fixed
40 ms step a kept W diverged). Measured costs are in ``benchmarks/README.md``.

First same as last: f(tₙ₊₁, yₙ₊₁) is evaluated at the end of each step and is
the next step's f(tₙ, yₙ); a step costs
five vector-field evaluations (one for the time derivative, none where W has
a time column), the band, one
factorisation and five solves (one for the linearisation check).

Outputs between steps are a dense output of order 3 built from the stages
(:func:`_dense_weights`, :class:`StagePolynomialInterpolation`), not diffrax's
cubic Hermite interpolation through h·f(t₁, y₁): on 100 drawn stiff lines
that go slack and snap within a step (``tests/test_error_control.py``, N = 60,
rtol/atol 4e-4/4e-3, 22,508 steps either way) the RMS fairlead tension error
fell from median 0.0184 / max 3.72 of the tension's std to 0.0026 / 0.49; on
reference cases A and B, whose errors are the mesh's, it is unchanged.

W is not differentiated (``stop_gradient``): gradients are those of the
W-method with its matrix held fixed, a consistent discretisation of the
sensitivities (the order conditions of a W-method do not involve W).
"""

from __future__ import annotations

from typing import Any, ClassVar

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import jax.tree_util as jtu
import numpy as np
from jax import lax
from jax.flatten_util import ravel_pytree

from ..linalg import block_tridiagonal as btd
from ..linalg.banded_solver import SecondOrderBandSolver, _flatten, _unflatten, band_of
from ..linalg.mass_form import MassFormFactor, MassFormW


class Tableau(eqx.Module):
    """A Rosenbrock(-W) method in Hairer & Wanner's form (A strictly lower, Γ lower
    triangular with the diagonal γ, weights b and embedded weights b̂), stored in the
    transformed variables the step uses."""

    gamma: float = eqx.field(static=True)
    a_t: tuple = eqx.field(static=True)  # AΓ⁻¹ (rows of the strictly lower part)
    c_t: tuple = eqx.field(static=True)  # diag(1/γ) − Γ⁻¹, off-diagonal part
    alpha: tuple = eqx.field(static=True)  # stage times Σⱼ aᵢⱼ
    gamma_sum: tuple = eqx.field(static=True)  # Σⱼ₍ⱼ≤ᵢ₎ γᵢⱼ (∂f/∂t weights)
    m: tuple = eqx.field(static=True)  # bΓ⁻¹
    m_err: tuple = eqx.field(static=True)  # (b − b̂)Γ⁻¹
    order: int = eqx.field(static=True)
    #: the dense output: rows of θ¹, θ², θ³ coefficients on the stages u (y(t₀+θh)
    #: = y₀ + Σₚ θᵖ Σⱼ dₚⱼ uⱼ), or ``()`` (then the cubic Hermite interpolation)
    dense: tuple = eqx.field(static=True, default=())

    @classmethod
    def from_hairer_wanner(cls, gamma, a, g, b, b_hat, order):
        a, g = np.asarray(a, float), np.asarray(g, float)
        s = a.shape[0]
        big_g = g + gamma * np.eye(s)
        g_inv = np.linalg.inv(big_g)
        # entries that are zero in exact arithmetic come out of the inverse as
        # ~1e-16: drop them (the step skips zero coefficients)
        clean = lambda x: 0.0 if abs(x) < 1e-13 else float(x)  # noqa: E731
        rows = lambda m: tuple(tuple(clean(x) for x in r) for r in m)  # noqa: E731
        return cls(
            dense=rows(_dense_weights(gamma, a, g, b) @ g_inv) if order == 3 and s == 4 else (),
            gamma=float(gamma),
            a_t=rows(a @ g_inv),
            c_t=rows(np.diag(np.full(s, 1.0 / gamma)) - g_inv),
            alpha=tuple(clean(x) for x in a.sum(axis=1)),
            gamma_sum=tuple(clean(x) for x in big_g.sum(axis=1)),
            m=tuple(clean(x) for x in np.asarray(b) @ g_inv),
            m_err=tuple(clean(x) for x in (np.asarray(b) - np.asarray(b_hat)) @ g_inv),
            order=int(order),
        )


def _dense_weights(gamma, a, g, b):
    """Weights bⱼ(θ) = Σₚ θᵖ Bₚⱼ (p = 1, 2, 3) of a dense output of order 3 for a
    4-stage Rosenbrock method: the order conditions of Hairer & Wanner (Solving
    ODEs II, Table IV.7.1) for the solution at t₀ + θh instead of t₀ + h,

        Σ bⱼ(θ) = θ,   Σ bⱼ(θ) βⱼ = θ²/2 − γθ,   Σ bⱼ(θ) αⱼ² = θ³/3,
        Σ bⱼ(θ) βⱼₖ βₖ = θ³/6 − γθ² + γ²θ,

    with βⱼₖ = αⱼₖ + γⱼₖ (k < j), βⱼ = Σₖ βⱼₖ, αⱼ = Σₖ αⱼₖ (the θ-forms follow
    from θ^ρ/t! for each tree, the diagonal γ moved to the right as in the
    table). Four conditions fix the four weights; at θ = 1 they are the
    method's own weights b (checked), so the output is continuous at both ends
    of every step. Unlike the cubic Hermite interpolation through h·f(t₁, y₁)
    it never multiplies a stiff component's error by hλ: the stages are the
    solutions of (I − γhJ)-systems.
    """
    beta_jk = a + g
    beta, alpha = beta_jk.sum(axis=1), a.sum(axis=1)
    conditions = np.array([np.ones(4), beta, alpha ** 2, beta_jk @ beta])
    powers = np.array([[1.0, 0.0, 0.0],  # right-hand sides as polynomials in θ
                       [-gamma, 0.5, 0.0],
                       [0.0, 0.0, 1.0 / 3.0],
                       [gamma ** 2, -gamma, 1.0 / 6.0]])
    weights = np.linalg.solve(conditions, powers).T  # rows: θ, θ², θ³
    if not np.allclose(weights.sum(axis=0), b, atol=1e-12):
        raise ValueError("dense output weights do not reproduce b at θ = 1")
    return weights


class StagePolynomialInterpolation(diffrax.AbstractLocalInterpolation):
    """The dense output y₀ + θc₁ + θ²c₂ + θ³c₃ of a Rosenbrock step (θ the
    fraction of the step; cₚ from the stages, :func:`_dense_weights`)."""

    t0: Any
    t1: Any
    coeffs: Any  # per leaf, stacked [c₃, c₂, c₁, y₀]

    def __init__(self, *, t0, t1, y0, c1, c2, c3):
        self.t0, self.t1 = t0, t1
        self.coeffs = jtu.tree_map(lambda *x: jnp.stack(x), c3, c2, c1, y0)

    def evaluate(self, t0, t1=None, left=True):
        del left
        if t1 is not None:
            return jtu.tree_map(lambda a, b: b - a, self.evaluate(t0), self.evaluate(t1))
        theta = (t0 - self.t0) / jnp.where(self.t1 == self.t0, 1.0, self.t1 - self.t0)
        return jtu.tree_map(lambda c: jnp.polyval(c, theta), self.coeffs)


#: Rang & Angermann (2005), ROS34PW2
ROS34PW2 = Tableau.from_hairer_wanner(
    gamma=4.3586652150845900e-1,
    a=[[0, 0, 0, 0],
       [8.7173304301691801e-1, 0, 0, 0],
       [8.4457060015369423e-1, -1.1299064236484185e-1, 0, 0],
       [0, 0, 1, 0]],
    g=[[0, 0, 0, 0],
       [-8.7173304301691801e-1, 0, 0, 0],
       [-9.0338057013044082e-1, 5.4180672388095326e-2, 0, 0],
       [2.4212380706095346e-1, -1.2232505839045147, 5.4526025533510214e-1, 0]],
    b=[2.4212380706095346e-1, -1.2232505839045147, 1.5452602553351020, 4.3586652150845900e-1],
    b_hat=[3.7810903145819369e-1, -9.6042292212423178e-2, 0.5, 2.1793326075422950e-1],
    order=3,
)


class _State(eqx.Module):
    f0: Any  # f(t_n, y_n) (FSAL)
    jac: Any  # the Jacobian W: bands (lower, diag, upper) or a dense matrix
    age: Any  # accepted steps since W was built
    h_prev: Any  # the last accepted step [s]


def _on_rows(fn, v):
    """``fn`` on the lines' (rows, 6) leaves of v stacked along the row axis,
    split back into v's pytree."""
    leaves, treedef = jtu.tree_flatten(v)
    sizes = tuple(int(x.shape[0]) for x in leaves)
    return _unflatten(fn(_flatten(v, sizes)), treedef, sizes)


def _combine(terms_):
    """Σ cᵢ·xᵢ over pytrees, skipping zero coefficients (static)."""
    terms_ = [(c, x) for c, x in terms_ if not (isinstance(c, float) and c == 0.0)]
    return jtu.tree_map(lambda *xs: sum(c * x for (c, _), x in zip(terms_, xs)),
                        *[x for _, x in terms_])


class RosenbrockW(diffrax.AbstractAdaptiveSolver):
    """A Rosenbrock-W method (see the module): ``"ros34pw2"`` by name.

    Args:
        tableau: the method (default :data:`ROS34PW2`).
        jacobian_age: accepted steps between Jacobian rebuilds (default 1: every
            step; see the module for why more is not the default).
        shrink: a step shorter than this fraction of the last accepted one (a
            rejection, usually at a kink) rebuilds the Jacobian.
        structured: ``True`` (default): the Jacobian's block-tridiagonal band from
            18 coloured JVPs and the reduced 3×3 block solve (line states of
            (n, 6) [r, v] rows only); ``False``: a dense Jacobian (``jacfwd``)
            and LU, for any state (bodies, consistent-mass elements).
    """

    term_structure: ClassVar = diffrax.AbstractTerm
    interpolation_cls: ClassVar = StagePolynomialInterpolation
    tableau: Tableau = ROS34PW2
    jacobian_age: int = eqx.field(static=True, default=1)
    shrink: float = eqx.field(static=True, default=0.7)
    structured: bool = eqx.field(static=True, default=True)
    #: ``band(t, y, args)``: (W's block-tridiagonal band or ``None``, W's time
    #: column ≈ ∂f/∂t as a pytree like y or ``None``); without a band, the band
    #: of the exact Jacobian from 18 coloured JVPs, and without a time column
    #: a forward difference in t (:meth:`_time_derivative`)
    band: Any = eqx.field(static=True, default=None)
    #: ``factors(t, y, args, c)``: each line's factored I − c·J (objects with
    #: ``solve``, :func:`~moorjax.dynamics.vector_field.stage_factors`), used
    #: instead of a W where given (the exact Jacobian, rebuilt every step)
    factors: Any = eqx.field(static=True, default=None)
    #: add the linearisation error of the step to its error estimate (see
    #: :meth:`_with_linearisation_error`)
    linearisation_check: bool = eqx.field(static=True, default=True)

    def order(self, terms):
        del terms
        return self.tableau.order

    def error_order(self, terms):
        del terms
        return self.tableau.order  # the embedded solution's local error is O(h^order)

    # -- the Jacobian and the stage matrix ------------------------------------
    def __check_init__(self):
        if not self.tableau.dense:
            raise ValueError("RosenbrockW: the tableau has no dense output weights")
        if self.factors is not None and self.jacobian_age != 1:
            raise ValueError("RosenbrockW: factors are rebuilt every step (jacobian_age = 1)")

    def _jacobian(self, terms, t, y, args):
        return self._linearise(terms, t, y, args)[0]

    def _linearise(self, terms, t, y, args):
        """(W at (t, y), W's time column ≈ ∂f/∂t or ``None``: then
        :meth:`_time_derivative` differences the vector field)."""
        y = lax.stop_gradient(y)
        if self.factors is not None:  # no W: the factors hold the exact stage matrix
            return jnp.zeros(()), None

        def f(z):
            return terms.vf(t, z, args)

        if self.structured:
            band, time = (None, None) if self.band is None else self.band(t, y, args)
            if band is not None:
                return lax.stop_gradient(band), (None if time is None else lax.stop_gradient(time))
            lower, diag, upper, _, _ = band_of(lambda v: jax.jvp(f, (y,), (v,))[1], y)
            return lax.stop_gradient((lower, diag, upper)), None
        flat, unravel = ravel_pytree(y)
        jac = jax.jacfwd(lambda z: ravel_pytree(f(unravel(z)))[0])(flat)
        return lax.stop_gradient(jac), None

    def _factor(self, jac, c, y):
        """The factorisation of I − c·W."""
        if isinstance(jac, MassFormW):
            return jac.factor(c)
        if self.structured:
            lower, diag, upper = jac
            eye = jnp.eye(diag.shape[-1], dtype=diag.dtype)
            leaves, treedef = jtu.tree_flatten(y)
            sizes = tuple(int(x.shape[0]) for x in leaves)
            return SecondOrderBandSolver().factor_bands(
                -c * lower, eye - c * diag, -c * upper, treedef, sizes)
        n = jac.shape[0]
        return jax.scipy.linalg.lu_factor(jnp.eye(n, dtype=jac.dtype) - c * jac)

    def _apply(self, jac, v):
        """W·v (same pytree as v)."""
        if isinstance(jac, _Tangent):
            return jac(v)
        if isinstance(jac, MassFormW):
            return _on_rows(jac.matvec, v)
        if self.structured:
            return _on_rows(lambda x: btd.matvec(*jac, x), v)
        flat, unravel = ravel_pytree(v)
        return unravel(jac @ flat)

    def _with_linearisation_error(self, y_error, jac, lu, c, h, y0, y1, f0, f_t, f_end):
        """The error estimate, raised where the step's linearisation was poor.

        The residual of the vector field at the step's end against its linear
        model, r = f(t₁, y₁) − [f₀ + W(y₁ − y₀) + h ∂f/∂t], mapped to the state
        change one Newton correction of the implicit step would make,
        (I − γhW)⁻¹ γh r: O(h³) where f is smooth (the embedded estimate's
        order), large where a force switched on or off within the step (a node
        landing on the seabed, a slack segment going taut) or where W misses a
        stiff term. Combined with the embedded estimate as √(e² + d²).
        """
        dy = jtu.tree_map(lambda a, b: a - b, y1, y0)
        lin = _combine([(1.0, f0), (1.0, self._apply(jac, dy)), (h, f_t)])
        residual = jtu.tree_map(lambda a, b: c * (a - b), f_end, lin)
        correction = self._solve(lu, residual)
        return jtu.tree_map(lambda e, d: jnp.sqrt(e * e + d * d), y_error, correction)

    def _time_derivative(self, terms, t0, y0, args, f0):
        """∂f/∂t at (t₀, y₀) by a forward difference from f₀ (one evaluation).

        Only the prescribed motions depend on t, but a forward-mode derivative
        in t carries tangents through the whole vector field (the end nodes are
        concatenated with the free ones, so XLA cannot drop the zero tangents):
        it cost 2–3 evaluations, 15–20 % of a step (measured: case B, N = 10,
        60 → 50 µs; case A, N = 40, 187 → 151 µs). The difference step
        δ = √(ε·max(|t₀|, 1e-5)) (as Hairer & Wanner's RODAS) leaves a relative
        error of about √ε in a term the method multiplies by γᵢh; step counts
        and errors of cases A and B are unchanged within the run-to-run spread.
        """
        eps = jnp.finfo(jnp.result_type(t0, float)).eps
        delta = jnp.sqrt(eps * jnp.maximum(jnp.abs(t0), 1e-5))
        delta = (t0 + delta) - t0  # exactly representable
        return jtu.tree_map(lambda a, b: (a - b) / delta, terms.vf(t0 + delta, y0, args), f0)

    def _solve(self, lu, rhs):
        if self.factors is not None:
            return tuple(f.solve(r) for f, r in zip(lu, rhs))
        if isinstance(lu, MassFormFactor):
            return _on_rows(lu.solve, rhs)
        if self.structured:
            return SecondOrderBandSolver()._compute_band(lu, rhs)
        flat, unravel = ravel_pytree(rhs)
        return unravel(jax.scipy.linalg.lu_solve(lu, flat))

    # -- the diffrax solver interface -------------------------------------------
    def init(self, terms, t0, t1, y0, args):
        f0 = terms.vf(t0, y0, args)
        if self.jacobian_age <= 1:  # every step builds its own W: keep only its layout
            like = jax.eval_shape(lambda: self._jacobian(terms, t0, y0, args))
            jac = jtu.tree_map(lambda x: jnp.zeros(x.shape, x.dtype), like)
        else:
            jac = self._jacobian(terms, t0, y0, args)
        return _State(f0, jac, jnp.asarray(0), jnp.asarray(t1 - t0, dtype=float))

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        tab, st = self.tableau, solver_state
        h = t1 - t0
        # plain jnp/lax only (no equinox-internal primitives): the integration
        # must stay exportable (moorjax._cache.StoredProgram)
        if isinstance(made_jump, bool):  # diffrax passes a static False without jumps
            f0 = terms.vf(t0, y0, args) if made_jump else st.f0
        else:
            f0 = jtu.tree_map(lambda a, b: jnp.where(made_jump, a, b), terms.vf(t0, y0, args), st.f0)
        time = None  # W's time column: only with a W of this step
        if self.jacobian_age <= 1:
            (jac, time), age = self._linearise(terms, t0, y0, args), st.age
        else:
            stale = (st.age >= self.jacobian_age) | (h < self.shrink * st.h_prev) | made_jump
            jac = lax.cond(stale, lambda: self._jacobian(terms, t0, y0, args), lambda: st.jac)
            age = jnp.where(stale, 0, st.age)
        c = tab.gamma * h
        if self.factors is None:
            lu = self._factor(jac, c, y0)
        else:
            lu = lax.stop_gradient(self.factors(t0, lax.stop_gradient(y0), args, c))
            jac = _Tangent(terms, t0, y0, args)
        # ∂f/∂t (the prescribed motions): W's time column where the band gives one
        f_t = self._time_derivative(terms, t0, y0, args, f0) if time is None else time
        u = self._stages(terms, t0, h, c, y0, args, f0, f_t, lu)
        y1 = _combine([(1.0, y0)] + list(zip(tab.m, u)))
        y_error = _combine(list(zip(tab.m_err, u)))
        f_end = terms.vf(t1, y1, args)
        if self.linearisation_check:
            y_error = self._with_linearisation_error(y_error, jac, lu, c, h, y0, y1, f0, f_t, f_end)
        dense_info = dict(y0=y0, **{f"c{p + 1}": _combine(list(zip(row, u)))
                                    for p, row in enumerate(tab.dense)})
        if self.factors is not None:
            jac = st.jac
        new_state = _State(f_end, jac, age + 1, jnp.asarray(h, dtype=float))
        return y1, y_error, dense_info, new_state, diffrax.RESULTS.successful

    def _stages(self, terms, t0, h, c, y0, args, f0, f_t, lu):
        """The stages u₁ … u_s (a list of pytrees like y0).

        The first stage takes f₀ and the others evaluate the vector field; the
        others are one loop (``lax.fori_loop``) over the stage index with the
        tableau's rows as arrays, so that the program holds one copy of the
        vector field and of the stage solve for all of them instead of one per
        stage: XLA compiles the step in less time (``benchmarks/README.md``,
        session 35)."""
        tab = self.tableau
        s = len(tab.alpha)
        dtype = jnp.result_type(h)
        a_t = jnp.asarray(tab.a_t, dtype)
        c_t = jnp.asarray(tab.c_t, dtype)
        alpha = jnp.asarray(tab.alpha, dtype)
        gamma_sum = jnp.asarray(tab.gamma_sum, dtype)

        def weighted(row, us):  # Σⱼ rowⱼ·uⱼ (rows of the strictly lower part: zeros from i on)
            return jtu.tree_map(lambda x: jnp.sum(row.reshape((s,) + (1,) * (x.ndim - 1)) * x, axis=0), us)

        def solved(i, f_i, us):  # uᵢ into its row of us, from f at the stage
            rhs = jtu.tree_map(lambda f, ft, cu: c * (f + gamma_sum[i] * h * ft + cu / h),
                               f_i, f_t, weighted(c_t[i], us))
            return jtu.tree_map(lambda x, v: x.at[i].set(v), us, self._solve(lu, rhs))

        def stage(i, us):
            y_i = jtu.tree_map(jnp.add, y0, weighted(a_t[i], us))
            return solved(i, terms.vf(t0 + alpha[i] * h, y_i, args), us)

        stacked = solved(0, f0, jtu.tree_map(lambda x: jnp.zeros((s,) + x.shape, x.dtype), y0))
        stacked = lax.fori_loop(1, s, stage, stacked)
        return [jtu.tree_map(lambda x: x[i], stacked) for i in range(s)]

    def func(self, terms, t0, y0, args):
        return terms.vf(t0, y0, args)


class _Tangent:
    """J·v by forward differentiation of the vector field at (t, y): the
    linearisation check's W where the lines factor their own stage matrix."""

    def __init__(self, terms, t, y, args):
        self.f = lambda z: terms.vf(t, z, args)
        self.y = lax.stop_gradient(y)

    def __call__(self, v):
        return jax.jvp(self.f, (self.y,), (v,))[1]
