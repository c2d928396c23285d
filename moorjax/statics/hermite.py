"""Static equilibrium of a line of Hermite elements (:class:`HermiteElement`).

The unknowns are the free node positions, every node's slope and the tension
field (:class:`moorjax.element.hermite.HermiteDofs`); the residual is the
element's generalised force on them and its extensibility equation
(:func:`moorjax.element.hermite.static_residual`). Newton's method (optimistix,
a dense LU: the slopes and tensions couple an element's two nodes fully) starts
from the analytic elastic catenary — its positions, slopes dr/ds and the tension
the axial law gives at its stretch — and attaches gradients by the implicit
function theorem. With a seabed it starts instead from the linear element's
equilibrium at twice the segments (eight on a graded mesh), whose globalised
descent finds the bed and the touchdown (:func:`_linear_guess`), and Newton's
steps are damped (:func:`_damped_newton`) before optimistix's Newton polishes
the answer (kept only where it does not raise the imbalance); where that does
not converge it is solved again from the linear equilibrium at the other
resolution (:data:`GUESS_SEGMENTS`). Scaled as the linear element's statics:
forces divided by the element stiffness EA/h, so each residual reads in metres.
"""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.flatten_util
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._cache import StoredProgram
from .._numerics import safe_norm
from ..element.hermite import (HermiteDofs, clamped_slopes, element_fields, element_lengths,
                               extensibility, generalized_forces, quadrature_weights, static_residual)
from ..element.hermite_motion import HermiteState, static_state
from ..linalg.ordering import after
from ..model.line import Line


def _linear_guess(line: Line, env, t, per_element=2) -> HermiteDofs:
    """Unknowns from the linear element's equilibrium at ``per_element``·n equal
    segments, interpolated at the Hermite nodes and element midpoints: positions,
    slopes by central differences (second-order one-sided at the ends), the
    tension field from the mean of the adjacent segments' tensions. At two per
    element (equal elements) its nodes are the Hermite nodes and midpoints."""
    from ..element.linear import LinearElement
    from .fem import ATOL, RTOL, _solve_core

    n = line.n_segments
    m = per_element * n
    fine = Line(line.line_type, line.length, m, line.end_a, line.end_b,
                element=LinearElement(), label=line.label)
    st = _solve_core(fine, env, t, None, RTOL, ATOL, None)
    p, tens = st.positions, st.tensions
    step = 2.0 * fine.segment_length
    inner = (p[2:] - p[:-2]) / step
    first = (-3.0 * p[0] + 4.0 * p[1] - p[2]) / step
    last = (3.0 * p[-1] - 4.0 * p[-2] + p[-3]) / step
    slope = jnp.concatenate([first[None], inner, last[None]])  # at the fine nodes
    tension = jnp.concatenate([tens[:1], 0.5 * (tens[:-1] + tens[1:]), tens[-1:]])
    # the fine nodes are the Hermite nodes and midpoints of equal elements;
    # graded ones take the values interpolated at theirs
    s_fine = jnp.linspace(0.0, 1.0, m + 1) * line.length
    s = _field_points(line)
    at = lambda v: jax.vmap(lambda c: jnp.interp(s, s_fine, c), in_axes=1, out_axes=1)(v)  # noqa: E731
    r = at(p)[::2].at[0].set(p[0]).at[-1].set(p[-1])
    dr = at(slope)[::2]
    lam = jnp.interp(s, s_fine, tension)
    for node, d in clamped_slopes(line, t):
        dr = dr.at[node].set(safe_norm(dr[node]) * d)
    return HermiteDofs(r=r, dr=dr, lam=lam)


def _field_points(line):
    """Arc lengths (2n+1,) [m] of the nodes and element midpoints, in order."""
    he = element_lengths(line)
    nodes = jnp.concatenate([jnp.zeros(1, he.dtype), jnp.cumsum(he)])
    mids = nodes[:-1] + 0.5 * he
    return jnp.zeros(2 * line.n_segments + 1, he.dtype).at[0::2].set(nodes).at[1::2].set(mids)


def hermite_guess(line: Line, env, t=0.0) -> HermiteDofs:
    """Unknowns from the analytic elastic catenary (the chord where it fails)."""
    from .catenary import catenary_line_forces, catenary_nodes

    lt = line.line_type
    n = line.n_segments
    ra, rb = line.end_a.position(t), line.end_b.position(t)
    w = lt.wet_weight(env.rho, env.g)
    touchdown = env.seabed is not None and jnp.minimum(ra[2], rb[2]) <= -env.depth * (1.0 - 1e-6)
    sol, _, _ = catenary_line_forces(ra, rb, line.length, lt.axial.nominal_ea(), w, 0.0, seabed=touchdown)
    s = _field_points(line)  # nodes and element midpoints
    point = lambda si: catenary_nodes(sol, ra, rb, si[None])[0]  # noqa: E731
    r = catenary_nodes(sol, ra, rb, s[::2])
    dr = jax.vmap(jax.jacfwd(point))(s)
    lam = lt.axial.tension(safe_norm(dr) - 1.0)
    ok = sol.converged & jnp.all(jnp.isfinite(r)) & jnp.all(jnp.isfinite(dr))
    chord = line.straight_state(t).r
    r = jnp.where(ok, r.at[0].set(ra).at[-1].set(rb), jnp.concatenate([ra[None], chord, rb[None]]))
    slope = (rb - ra) / line.length
    dr = jnp.where(ok, dr[::2], jnp.broadcast_to(slope, (n + 1, 3)))
    lam = jnp.where(ok, lam, jnp.abs(w) * line.length)
    for node, d in clamped_slopes(line, t):  # a clamp's slope along its direction
        dr = dr.at[node].set(safe_norm(dr[node]) * d)
    return HermiteDofs(r=r, dr=dr, lam=lam)


def _clamp(line, t, moment, dr):
    """The slope residuals (n+1, 3) [m] with each clamped slope's row replaced by
    its moment along the clamp's direction (the one free component, the stretch)
    and h times the slope's part across it (zero when the clamp holds)."""
    h = line.segment_length
    for node, d in clamped_slopes(line, t):
        across = dr[node] - jnp.dot(dr[node], d) * d
        moment = moment.at[node].set(jnp.dot(moment[node], d) * d + h * across)
    return moment


def _unbalanced(line, t, moment):
    """The generalised forces (n+1, 3) [N·m] on the slopes less the clamps' end
    moments (the components across a clamped slope are reactions)."""
    for node, d in clamped_slopes(line, t):
        moment = moment.at[node].set(jnp.dot(moment[node], d) * d)
    return moment


def _assemble(line, ra, rb, y):
    r_free, dr, lam = y
    return HermiteDofs(r=jnp.concatenate([ra[None], r_free, rb[None]]), dr=dr, lam=lam)


def _start(line, env, t, init, ra, rb) -> HermiteDofs:
    """A start from ``init``, with its ends at ``ra``, ``rb``: from
    :class:`HermiteDofs` (a neighbouring static solution's unknowns,
    ``LineStatics.warm_start``, e.g. a body iteration's previous pose) or from a
    :class:`HermiteState` (a dynamic state: the field λ of its stretch), the one
    of it and the catenary guess whose residual is smaller: an end moved by
    metres kinks the end element of the old shape (measured: a free point's 5 m
    step on a taut 4-element line, started from the old state, diverged or
    reached a folded equilibrium)."""
    if isinstance(init, HermiteState):
        mine = _from_state(line, init, ra, rb)
    else:
        mine = HermiteDofs(r=init.r.at[0].set(ra).at[-1].set(rb), dr=init.dr, lam=init.lam)
    guess = hermite_guess(line, env, t)
    k = line.line_type.axial.nominal_ea() / line.segment_length

    def size(dofs):
        force, moment, constraint = static_residual(line, env, dofs, t)
        return jnp.maximum(jnp.max(jnp.abs(force[1:-1])) / k,
                           jnp.maximum(jnp.max(jnp.abs(moment)) / (k * line.segment_length),
                                       jnp.max(jnp.abs(constraint))))

    better = size(mine) < size(guess)  # a NaN residual picks the guess
    return jax.tree_util.tree_map(lambda a, b: jnp.where(better, a, b), mine, guess)


def _from_state(line, init, ra, rb) -> HermiteDofs:
    r = jnp.concatenate([ra[None], init.r, rb[None]])
    dr = init.d / line.segment_length  # the state's slopes are scaled by L/n
    he = element_lengths(line)[:, None]
    mid = 1.5 * (r[1:] - r[:-1]) / he - 0.25 * (dr[:-1] + dr[1:])  # r'(½) of the cubic
    pts = jnp.zeros((2 * line.n_segments + 1, 3)).at[0::2].set(dr).at[1::2].set(mid)
    strain = safe_norm(pts) - 1.0
    axial = line.line_type.axial
    lam = jnp.where(strain >= 0.0, axial.tension(strain),
                    line.element.slack_ratio * axial.nominal_ea() * strain)
    return HermiteDofs(r=r, dr=dr, lam=lam)


#: segments per element of the linear equilibria that start a grounded line's
#: solve (:func:`_linear_guess`): the first for equal elements, the second where
#: the first fails; a graded mesh (``HermiteElement.mesh``) takes them in the
#: other order. On the drawn lines of ``tests/test_hermite_statics_property.py``
#: (10 elements): equal elements from 2 per element failed on draws 47, 108, 188
#: (from 8: 1, 44, 47); graded from 2 per element the two sharpest touchdowns
#: (H/w 0.016 and 0.022 element lengths: the guess's segments are 3-6 times the
#: graded mesh's first element there) converged or diverged with the rounding of
#: the linear solve, from 8 both converge (errors 2.9e-5, 2.5e-4 of MoorPy's
#: largest tension, against 1.1e-3, 2.1e-3 from 2).
GUESS_SEGMENTS = (2, 8)


#: the Hermite statics' default Newton step limit (``max_steps=None``)
NEWTON_STEPS = 500


def hermite_equilibrium(line: Line, env, t=0.0, init: HermiteDofs | None = None, *,
                        rtol=1e-10, atol=1e-8, max_steps=NEWTON_STEPS):
    """The static unknowns (:class:`HermiteDofs`) and Newton's step count.

    Without ``init``: from the catenary guess (:func:`hermite_guess`), or with a
    seabed from the linear element's equilibrium (:func:`_linear_guess`; from
    the flat catenary Hermite Newton failed on 16 of 200 drawn lines at 10
    elements, 14 of them grounded, and the catenary does not know a
    bathymetry), solved again from the second of :data:`GUESS_SEGMENTS` where
    the first start does not converge (:func:`_balance`).
    """
    dofs, steps, _ = _equilibrium(line, env, t, init, rtol, atol, max_steps)
    return dofs, steps


def _equilibrium(line, env, t, init, rtol, atol, max_steps):
    """:func:`hermite_equilibrium`'s unknowns and step count, and
    :func:`_balance` of the unknowns."""
    lt = line.line_type
    ra, rb = line.end_a.position(t), line.end_b.position(t)
    from .fem import _values, implicit_root

    solver = optx.Newton(rtol=rtol, atol=atol)
    # the search runs on values only; the root kept gets its derivative from the
    # implicit function theorem (implicit_root: at the root kept, never raising)
    values = _scaled_residual(*_values((line, env, t)))

    def solve(y0):
        y0 = jax.lax.stop_gradient((y0.r[1:-1], y0.dr, y0.lam))
        if lt.ei is not None and init is None:
            y0 = _bending_continuation(line, env, t, y0, rtol, atol, max_steps)
        if env.seabed is None:
            sol = optx.root_find(values, solver, y0, max_steps=max_steps, throw=False)
            y = implicit_root(sol.value, _scaled_residual, (line, env, t))
            return _assemble(line, ra, rb, y), sol.stats["num_steps"]
        # the contact's kinks: where plain Newton cycles or diverges
        y0, size0 = _damped_newton(lambda y: values(y, None), y0, atol, max_steps)
        sol = optx.root_find(values, solver, y0, max_steps=max_steps, throw=False)
        # Newton unguarded after a damped search that stopped short of a root can
        # run off (to 1e17 m): the damped iterate stands where Newton's is worse
        # and outside the tolerance (at a root the two differ by rounding)
        worse = _size(values(sol.value, None)) > jnp.maximum(size0, atol)
        y = jax.tree.map(lambda a, b: jnp.where(worse, a, b), y0, sol.value)
        y = implicit_root(y, _scaled_residual, (line, env, t))
        return _assemble(line, ra, rb, y), sol.stats["num_steps"]

    def balanced(dofs, steps):
        return dofs, steps, _balance(line, env, t, dofs)

    if init is not None:
        return balanced(*solve(_start(line, env, t, init, ra, rb)))
    if env.seabed is None:
        return balanced(*solve(hermite_guess(line, env, t)))
    # a grounded line: from the linear equilibrium at the first of
    # GUESS_SEGMENTS, again from the second where that does not converge. One
    # copy of the Hermite solve, in a scan of two attempts (a lax.cond of two
    # solves compiled both: 8.5 s against 5.9 s for case A at 10 elements)
    order = GUESS_SEGMENTS if line.element.mesh is None else GUESS_SEGMENTS[::-1]
    first = _linear_guess(line, env, t, order[0])

    def attempt(carry, second):
        dofs, steps, balance, done = carry

        def run():
            start = jax.lax.cond(second, lambda: _linear_guess(line, env, t, order[1]), lambda: dofs)
            more, more_steps = solve(start)
            balance = _balance(line, env, t, more)
            return more, steps + jnp.asarray(more_steps, steps.dtype), balance, balance[3]

        return jax.lax.cond(done, lambda: carry, run), None

    nothing = (jnp.zeros_like(first.r), jnp.zeros_like(first.dr), jnp.zeros_like(first.lam[0]),
               jnp.array(False))
    carry = (first, jnp.array(0, jnp.int32), nothing, jnp.array(False))
    (dofs, steps, balance, _), _ = jax.lax.scan(attempt, carry, jnp.array([False, True]))
    return dofs, steps, balance


def _size(f):
    """The largest entry of a residual pytree (inf where one is not finite)."""
    m = jax.tree.reduce(jnp.maximum, jax.tree.map(lambda x: jnp.max(jnp.abs(x)), f))
    return jnp.where(jnp.isfinite(m), m, jnp.inf)


def _balance(line, env, t, dofs):
    """The generalised forces (force, moment) of ``dofs``, the largest free
    imbalance [N] and whether it is an equilibrium: imbalance below 1e-6 of the
    largest tension (at least an element's weight) and extensibility below
    1e-9 of the length."""
    lt = line.line_type
    h = line.segment_length
    force, moment, _ = static_residual(line, env, dofs, t)
    weight = jnp.abs(lt.wet_weight(env.rho, env.g)) * h
    scale = jnp.maximum(jnp.max(jnp.abs(dofs.lam)), weight)
    res = jnp.maximum(jnp.max(jnp.abs(force[1:-1])), jnp.max(jnp.abs(_unbalanced(line, t, moment))) / h)
    cres = extensibility(line, dofs)
    converged = (
        jnp.all(jnp.isfinite(dofs.r)) & (res < 1e-6 * scale) & (jnp.max(jnp.abs(cres)) < 1e-9 * line.length)
    )
    return force, moment, res, converged


def _scaled_residual(line, env, t):
    """The static residual of the free unknowns (free positions, slopes, tension
    field) as optimistix calls it, forces over the element stiffness EA/h."""
    h = line.segment_length
    k = line.line_type.axial.nominal_ea() / h
    ra, rb = line.end_a.position(t), line.end_b.position(t)

    def fn(y, args):
        del args
        force, moment, constraint = static_residual(line, env, _assemble(line, ra, rb, y), t)
        return force[1:-1] / k, _clamp(line, t, moment / (k * h), y[1]), constraint

    return fn


#: trial step lengths of :func:`_damped_newton`, largest first
_ALPHAS = 2.0 ** -np.arange(12.0)
#: and the damping of its Levenberg–Marquardt directions (times the mean of diag JᵀJ)
_MUS = 10.0 ** np.arange(-8.0, 1.0, 2.0)


def _damped_newton(fn, y0, atol, max_steps):
    """Newton's method with a backtracking search on |f|² (all trial steps at
    once): the step taken is the longest of 1, ½, … 2⁻¹¹ that reduces the
    residual, else the one of those and of Levenberg–Marquardt steps (damping
    1e-8 … 1 of the mean of diag JᵀJ) that reduces it most. Stops when |f|∞ < atol/100 or
    no trial step reduces it. Values only (the root finder that follows attaches
    the implicit gradient). Plain Newton cycles where a quadrature point crosses
    the seabed (the contact force has a kink there) and diverges where the
    touchdown is much sharper than an element. Returns the iterate and its
    largest residual (inf where not finite)."""
    flat0, unravel = jax.flatten_util.ravel_pytree(y0)

    def f(x):
        return jax.flatten_util.ravel_pytree(fn(unravel(x)))[0]

    alphas = jnp.asarray(_ALPHAS)
    mus = jnp.asarray(_MUS)

    def cond(c):
        x, fx, it, stuck = c
        return (it < max_steps) & jnp.invert(stuck) & (jnp.max(jnp.abs(fx)) >= 0.01 * atol)

    def body(c):
        x, fx, it, _ = c
        jac = jax.jacfwd(f)(x)
        dx = -jnp.linalg.solve(jac, fx)
        dx = jnp.where(jnp.all(jnp.isfinite(dx)), dx, 0.0)
        # Levenberg–Marquardt directions (descent directions of |f|² where the
        # Newton step is not one: across a kink of the contact law)
        jtj, jtf = after(jac.T @ jac, dx), jac.T @ fx  # one batched LU at a time (linalg.ordering)
        scale = jnp.mean(jnp.diag(jtj))
        lm = jax.vmap(lambda m: -jnp.linalg.solve(jtj + m * scale * jnp.eye(x.size), jtf))(mus)
        steps = jnp.concatenate([alphas[:, None] * dx, jnp.where(jnp.isfinite(lm), lm, 0.0)])
        trial = jax.vmap(lambda d: f(x + d))(steps)
        size = jnp.sum(trial * trial, axis=1)
        size = jnp.where(jnp.isfinite(size), size, jnp.inf)
        now = jnp.sum(fx * fx)
        better = size < now
        k = jnp.where(jnp.any(better[:alphas.size]), jnp.argmax(better), jnp.argmin(size))
        stuck = size[k] >= now
        x_new = jnp.where(stuck, x, x + steps[k])
        return x_new, jnp.where(stuck, fx, trial[k]), it + 1, stuck

    x, fx, *_ = jax.lax.while_loop(cond, body, (flat0, f(flat0), 0, False))
    size = jnp.max(jnp.abs(fx))
    return unravel(x), jnp.where(jnp.isfinite(size), size, jnp.inf)


#: Fractions of EI solved in turn from the catenary guess (then EI itself).
EI_STAGES = (1e-3, 1e-2, 1e-1)


def _bending_continuation(line, env, t, y0, rtol, atol, max_steps):
    """The start for a line with bending stiffness: the equilibria at EI_STAGES
    of its EI, each from the last, from the catenary guess (the shape at EI = 0).

    Newton's full steps from the catenary diverge when the bending length
    √(EI/T) is a sizable fraction of the line: measured on a 20 m line of
    902 N/m hung between points 17 m apart with EI = 3.4e4 N·m² (bending length
    ≈ 10 % of L), which 8 and 16 elements failed from the catenary and solve in
    4 steps per stage by these stages. Gradients: the stages start the final
    solve only (no gradient flows through them; they run on values, so no
    derivative of a failed stage is ever formed).
    """
    from .fem import _values

    line, env, t = _values((line, env, t))
    lt = line.line_type
    h = line.segment_length
    k = lt.axial.nominal_ea() / h
    ra, rb = line.end_a.position(t), line.end_b.position(t)

    def stage(y, frac):
        staged = eqx.tree_at(lambda ln: ln.line_type.ei, line, lt.ei * frac)

        def fn(y, args):
            del args
            force, moment, constraint = static_residual(staged, env, _assemble(staged, ra, rb, y), t)
            return force[1:-1] / k, _clamp(staged, t, moment / (k * h), y[1]), constraint

        sol = optx.root_find(fn, optx.Newton(rtol=rtol, atol=atol), y, max_steps=max_steps, throw=False)
        ok = jax.tree.reduce(lambda a, b: a & b, jax.tree.map(lambda v: jnp.all(jnp.isfinite(v)), sol.value))
        return jax.tree.map(lambda a, b: jnp.where(ok, a, b), sol.value, y), None

    y, _ = jax.lax.scan(stage, y0, jnp.asarray(EI_STAGES))
    return y


def closure_equilibrium(line: Line, env, dofs: HermiteDofs, t=0.0, *, rtol=1e-10, atol=1e-8,
                        max_steps=100) -> HermiteDofs:
    """The equilibrium of the dynamics' tension closure, from Wu's static ``dofs``.

    With :class:`~moorjax.element.hermite_motion.MixedTension` that is ``dofs``
    itself; with ``ProjectedTension`` or ``StrainTension`` (λ from the slopes) the positions and
    slopes move slightly (the two closures differ by their discretisation
    error), so that a run starts at rest in its own equilibrium.
    """
    from ..element.hermite_motion import MixedTension
    from .fem import _values, implicit_root

    if isinstance(line.element.tension, MixedTension):
        return dofs
    ra, rb = line.end_a.position(t), line.end_b.position(t)
    y0 = jax.lax.stop_gradient((dofs.r[1:-1], dofs.dr))
    values = _closure_residual(*_values((line, env, t, dofs.lam)))
    sol = optx.root_find(values, optx.Newton(rtol=rtol, atol=atol), y0, max_steps=max_steps,
                         throw=False)
    # where the closure's Newton fails (its Jacobian is singular where a whole
    # element is slack: the unilateral law has no compression stiffness), the
    # run starts from Wu's equilibrium itself rather than from NaN
    ok = (sol.result == optx.RESULTS.successful) & jnp.all(jnp.isfinite(sol.value[0])) & jnp.all(
        jnp.isfinite(sol.value[1]))
    y = implicit_root(sol.value, _closure_residual, (line, env, t, dofs.lam))
    r, dr = (jnp.where(ok, a, b) for a, b in zip(y, (dofs.r[1:-1], dofs.dr)))
    return _assemble(line, ra, rb, (r, dr, dofs.lam))


def _closure_residual(line, env, t, lam):
    """The dynamics' tension closure's static residual of the free positions and
    slopes with Wu's tension field ``lam`` held (:func:`closure_equilibrium`),
    forces over the element stiffness EA/h."""
    closure = line.element.tension
    h = line.segment_length
    k = line.line_type.axial.nominal_ea() / h
    ra, rb = line.end_a.position(t), line.end_b.position(t)

    def fn(y, args):
        del args
        full = _assemble(line, ra, rb, (y[0], y[1], lam))
        full, tension = closure.resolve(line, full)
        force, moment = generalized_forces(line, env, full, None, t, tension)
        return force[1:-1] / k, _clamp(line, t, moment / (k * h), y[1])

    return fn


# eqx.filter_jit, its program also stored on disk (moorjax._cache) and compiled
# for one run (moorjax._xla_flags.PRESETS), as the linear element's solve
@functools.partial(StoredProgram, compile_for="once")
def hermite_statics_core(line: Line, env, t, init, rtol, atol, max_steps):
    """The jitted static solve of a Hermite line; returns a ``LineStatics``."""
    max_steps = NEWTON_STEPS if max_steps is None else max_steps
    env = env.without_waves()  # statics: the mean state, waves ignored (as MoorDyn's IC)
    from .fem import LineStatics

    dofs, steps, (force, _, res, converged) = _equilibrium(line, env, t, init, rtol, atol, max_steps)
    fa, fb, push = _bed_support(line, env, dofs, force[0], force[-1])
    return LineStatics(
        positions=dofs.r,
        tensions=dofs.lam[1::2],
        force_a=fa,
        force_b=fb,
        tension_a=jnp.linalg.norm(fa),
        tension_b=jnp.linalg.norm(fb),
        grounded_length=_grounded_length(line, env, dofs, push),
        converged=converged,
        iterations=steps,
        max_residual=res,
        rest_state=static_state(line, closure_equilibrium(line, env, dofs, t)),
        dofs=dofs,
    )


def _bed_support(line, env, dofs, fa, fb):
    """End forces with the seabed carrying the push of an end held on it.

    An end on the bed (an anchor) cannot be pushed into it: the bed takes the
    part of the end's force into the bed along its normal (the share of the
    first element's weight that the coarse cubic does not lay on the bed), so
    the anchor feels the grounded tension, as in the analytic catenary and the
    linear element. An end the line lifts off is unchanged.
    """
    if env.seabed is None:
        return fa, fb, jnp.zeros(())
    tol = 1e-6 * env.depth
    ends = dofs.r[jnp.array([0, -1])]
    _, height, normal = env.seabed.contact(ends, None, line.line_type.diameter,
                                           line.line_type.wet_weight(env.rho, env.g), env.depth)

    def support(f, k):
        push = jnp.minimum(jnp.dot(f, normal[k]), 0.0)
        held = jnp.abs(height[k]) < tol
        return jnp.where(held, f - push * normal[k], f), jnp.where(held, -push, 0.0)

    (fa, pa), (fb, pb) = support(fa, 0), support(fb, 1)
    return fa, fb, pa + pb


def _grounded_length(line, env, dofs, push=0.0):
    """Unstretched length carried by the seabed [m]: the contact force, and the
    ``push`` [N] of an end held on the bed into it (the weight the end element's
    cubic does not lay on the bed), over the wet weight."""
    if env.seabed is None:
        return jnp.zeros(())
    lt = line.line_type
    w = lt.wet_weight(env.rho, env.g)
    r, _, _, _ = element_fields(line, dofs)
    load = env.seabed.contact(r, None, lt.diameter, w, env.depth)[0]  # along the bed's normal
    contact = jnp.sum(quadrature_weights(line) * safe_norm(load)) + push
    return jnp.where(w > 0, contact / jnp.where(w > 0, w, 1.0), 0.0)


#: segments per Hermite element of the linear equilibrium that places the first
#: touchdown where equal Hermite elements do not (:func:`touchdown_mesh`). On the
#: grounded lines of ``tests/test_hermite_statics_property.py`` (10 elements):
#: equal elements failed on two (draws 47 and 188) and, where the touchdown bends
#: within a few hundredths of an element, converged on a horizontal pull 2–50×
#: too small (draws 90, 108: H = 46 N for MoorPy's 2.3 kN), so the mesh graded
#: from it started at a millimetre and its statics failed or landed 3e-3 off;
#: the linear element at 8 segments per element gave H within 1e-3 and all four
#: a graded mesh that converges (end tensions 1.6e-4 … 1.1e-3 of MoorPy's)
FINE_SEGMENTS = 8
#: a first horizontal pull H with H/w below this fraction of a mean element is
#: not trusted (:data:`FINE_SEGMENTS`)
SHARP = 0.05


def _horizontal_pull(st, on_a, on_b):
    """The smallest horizontal pull H [N] of a solution's suspended ends (those
    not held on the bed), ``None`` if both are."""
    pulls = [float(np.hypot(*np.asarray(f, float)[:2])) for f, held in
             ((st.force_a, on_a), (st.force_b, on_b)) if not held]
    return min(pulls) if pulls else None


def _sharp(st, on_a, on_b, w, mean):
    """Whether a converged equal-element solution bends at its touchdown within
    :data:`SHARP` of an element (H/w from its suspended end's horizontal pull)."""
    pull = _horizontal_pull(st, on_a, on_b)
    return pull is not None and pull / w < SHARP * mean


def _fine_linear(line: Line) -> Line:
    """The line with :data:`FINE_SEGMENTS` linear segments per Hermite element."""
    from ..element.linear import LinearElement

    return Line(line.line_type, line.length, FINE_SEGMENTS * line.n_segments, line.end_a,
                line.end_b, element=LinearElement(), label=line.label)


@eqx.filter_jit
def _end_heights(line: Line, env, t):
    """Heights [m] of the line's ends above the seabed (along its normal)."""
    ends = jnp.stack([line.end_a.position(t), line.end_b.position(t)])
    lt = line.line_type
    _, height, _ = env.seabed.contact(ends, None, lt.diameter, lt.wet_weight(env.rho, env.g), env.depth)
    return height


#: the largest ratio of neighbouring elements' lengths in :func:`graded_mesh`
MAX_GROWTH = 3.0


def _graded(length, k, first, at_start, at_end):
    """k element lengths over ``length`` [m], growing geometrically from
    ``first`` at the graded end(s) (ratio at most MAX_GROWTH; equal where k
    elements of ``first`` already cover it)."""
    if k * first >= length or not (at_start or at_end):
        return np.full(k, length / k)
    i = np.arange(k)
    dist = np.minimum(i if at_start else k, (k - 1 - i) if at_end else k).astype(float)

    def total(q):
        return float(np.sum(q ** dist))

    if total(MAX_GROWTH) * first < length:  # the growth capped: a larger first element
        return length * MAX_GROWTH ** dist / total(MAX_GROWTH)
    lo, hi = 1.0, MAX_GROWTH
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if total(mid) * first < length else (lo, mid)
    sizes = first * lo ** dist
    return sizes * length / sizes.sum()


def graded_mesh(length: float, n: int, start: float, end: float, first: float,
                grounded_share: float = 0.5) -> np.ndarray:
    """Relative element lengths (n,) for a line grounded over [start, end] [m]
    of its ``length``: element boundaries at the touchdowns (those inside the
    line), elements growing geometrically away from them from ``first`` [m]
    (the catenary's length scale H/w), the grounded stretch taking
    ``grounded_share`` of its proportional share of the elements (it lies
    straight in statics; at least one), the suspended ones the rest in
    proportion to their lengths (at least one each)."""
    knots = [k for k in (start, end) if 0.0 < k < length]
    edges = [0.0] + knots + [length]
    gaps = np.diff(edges)
    ground = [(a + b) / 2 > start and (a + b) / 2 < end for a, b in zip(edges[:-1], edges[1:])]
    if len(gaps) > n:
        return np.full(n, 1.0 / n)
    weight = np.where(ground, grounded_share, 1.0) * gaps
    share = weight / weight.sum() * n
    count = np.maximum(np.floor(share).astype(int), 1)
    while count.sum() > n:
        count[np.argmax(np.where(count > 1, count - share, -np.inf))] -= 1
    while count.sum() < n:
        count[np.argmax(share - count)] += 1
    sizes = [_graded(g, k, first, a > 0.0, b < length)
             for g, k, a, b in zip(gaps, count, edges[:-1], edges[1:])]
    return np.concatenate(sizes) / length


class UnresolvedTouchdownWarning(UserWarning):
    """A Hermite line's touchdown bends within a small part of an element
    (:func:`touchdown_mesh`, :func:`check_resolution`): its static end tensions
    are unreliable."""


def _warn_unresolved(line: Line, scale):
    """Warn that ``line``'s touchdown, bending over ``scale`` = H/w [m], is
    sharper than its elements resolve (:data:`SHARP` of a mean element)."""
    import warnings

    n, mean = line.n_segments, float(line.length) / line.n_segments
    needed = int(np.ceil(SHARP * float(line.length) / scale))
    warnings.warn(
        f"line {line.label}: its touchdown bends within H/w = {scale:.3g} m, {scale / mean:.3f} of "
        f"a mean element ({mean:.3g} m); {n} Hermite elements do not resolve it (below {SHARP} of an "
        f"element), and its static end tensions, the grounded end's most, are unreliable (drawn lines: "
        f"up to 1.3 % off the analytic catenary). Use about {needed} elements or more.",
        UnresolvedTouchdownWarning, stacklevel=3)


#: the relative difference of end tensions (each over its own value, at least
#: 1e-3 of the larger) between a grounded line of equal Hermite elements and the
#: linear element at :data:`FINE_SEGMENTS` segments per element above which
#: :func:`check_resolution` warns. On the 98 grounded drawn lines of
#: ``tests/test_hermite_statics_property.py`` at 10 elements the difference
#: follows the Hermite error against MoorPy (own value; within 10 % of it but
#: for draw 122, 90 against 56): the 26 lines it exceeds 5e-2 on are 4.8e-2 … 56 off,
#: the others at most 4.9e-2.
RESOLUTION_TOL = 5e-2


#: what :func:`check_resolution`'s warning (and an ensemble's) tells the user to do
RESOLUTION_ADVICE = ("Grade the elements at the touchdown (moorjax.statics.hermite.touchdown_mesh; CLI: "
                     "--hermite-mesh touchdown) or use more elements.")


def resolution_checked(line: Line, env) -> bool:
    """Whether :func:`check_resolution` applies to ``line`` by its structure: a
    Hermite line of equal elements (``element.mesh`` None; a mesh graded by
    :func:`touchdown_mesh` has its own check) in an environment with a seabed."""
    from ..element.hermite import HermiteElement

    return env.seabed is not None and isinstance(line.element, HermiteElement) and line.element.mesh is None


def resolution_offsets(line: Line, env, st, t=0.0):
    """``(off, ref)``: ``ref`` the (2,) end tensions (A, B) [N] of the linear
    element at :data:`FINE_SEGMENTS` segments per element, ``off`` the relative
    differences of ``st``'s from them, each over the fine line's own value (at
    least 1e-3 of its larger end tension); ``off`` NaN where the comparison
    does not apply (``st`` not converged or not on the bed, or the
    fine solve not converged). Traceable: what :func:`check_resolution`
    measures, and what ensembles run for all members at once (vmapped)."""
    from .fem import line_statics

    fine = line_statics(_fine_linear(line), env, t, throw=False)
    return _relative_offsets(st.tension_a, st.tension_b, st.converged & (st.grounded_length > 0.0),
                             fine.tension_a, fine.tension_b, fine.converged)


@jax.jit
def _relative_offsets(ta, tb, ok, fine_a, fine_b, fine_ok):
    """:func:`resolution_offsets`' arithmetic (one small program outside jit)."""
    ours, ref = jnp.stack([ta, tb]), jnp.stack([fine_a, fine_b])
    off = jnp.abs(ours - ref) / jnp.maximum(ref, 1e-3 * jnp.max(ref))
    return jnp.where(ok & fine_ok, off, jnp.nan), ref


class PiledLineWarning(UserWarning):
    """A Hermite line longer than its path along the seabed (:func:`check_piled`)."""


def check_piled(line: Line, env, t=0.0) -> bool:
    """Warn where a Hermite line is longer than its path along a flat seabed
    (the horizontal distance of its ends plus each end's height above the
    bed); returns whether it warned.

    Such a line lies partly slack on the bed, piled, with no horizontal
    tension: the part that hangs is vertical and meets the bed at a corner,
    which C¹ cubics cannot represent. Measured on case A's chain from
    (−1100, 0, −320) to (0, 0, −70) m (a 1350 m path; the hanging 250 m weigh
    174.5 kN), 10 equal elements: 1400 m converges to 155 kN at the fairlead
    (the linear element at 100 segments: 171 kN), 1500 m does not converge.
    An element boundary at the corner and a slack ratio of 1e-6–1e-8 give
    174.2 kN with the corner on the node, but with the fairlead 1–20 m higher
    or lower (the corner off the node) the solve "converges" 0.2–10 % off, or
    fails: the slack part on the bed admits spurious equilibria (arches of
    cubics), so no mesh or regularisation was found that mends it (session
    43). Bodies on such lines settle at poses that rest on these forces: a
    point on three piled chains came out 92 m off its symmetric pose, with
    ``converged`` true; :func:`check_lines` warns there too. The linear
    element's lumped nodes follow the corner. Values only (skipped under
    ``jit``/``vmap``), flat seabeds only."""
    import warnings

    found = piled_path(line, env, t)
    if found is None:
        return False
    length, path = found
    warnings.warn(
        f"line {line.label}: its unstretched length {length:.6g} m exceeds its path along the seabed "
        f"({path:.6g} m: the horizontal distance of its ends plus their heights above the bed), so "
        f"{PILED_ADVICE}", PiledLineWarning, stacklevel=3)
    return True


#: what a piled Hermite line's warning says after its numbers
PILED_ADVICE = ("part of it lies piled on the bed with no horizontal tension and hangs to it at a "
                "corner, which Hermite elements (C¹ cubics) cannot represent: its end tensions are "
                "unreliable and its statics may not converge. Use the linear element for this line "
                "(--element linear).")


def piled_path(line: Line, env, t=0.0):
    """``(length, path)`` [m] where a Hermite line's unstretched length exceeds its
    path along a flat seabed (:func:`check_piled`), else ``None``; values only
    (``None`` under ``jit``/``vmap``)."""
    from ..element.hermite import HermiteElement
    from .fem import concrete_geometry

    if (env.seabed is None or getattr(env.seabed, "bathymetry", None) is not None
            or not isinstance(line.element, HermiteElement)):
        return None
    geometry = concrete_geometry(line, env, t)
    if geometry is None:
        return None
    ra, rb, length, depth = geometry
    path = float(np.linalg.norm(rb[:2] - ra[:2]) + (ra[2] + depth) + (rb[2] + depth))
    return (float(length), path) if length > path else None


def check_resolution(line: Line, env, st, t=0.0) -> float | None:
    """Warn where a grounded line of equal Hermite elements does not resolve
    its touchdown; returns the relative end-tension difference it measured
    (None where it does not apply).

    ``st`` is the line's :class:`~moorjax.statics.fem.LineStatics`. Newton's
    ``converged`` says that the discrete equations are solved, not that 10
    cubics follow a catenary that bends within a small part of an element at
    its touchdown: on drawn lines such solutions are up to 56 times off at the
    grounded end, and some of them (draws 122, 132 of the property test) even
    come with a larger horizontal pull than the true one, so a check of H/w
    against the element length misses them. This solves the same line with the
    linear element at :data:`FINE_SEGMENTS` segments per element (lumped nodes
    follow a kink; one more static solve, compiled once per segment count) and
    warns (:class:`UnresolvedTouchdownWarning`) where an end tension differs by
    more than :data:`RESOLUTION_TOL` of its own value (at least 1e-3 of the
    larger end tension): :func:`resolution_offsets`.

    Applies only to values (not under ``jit``/``vmap``; ensembles run
    :func:`resolution_offsets` batched and warn once per line, naming the
    members), to the lines of :func:`resolution_checked`, where their solution
    converged and rests on the bed.
    """
    import warnings

    from .._checks import _concrete

    if not resolution_checked(line, env) or any(
            _concrete(x) is None for x in (st.converged, st.grounded_length, st.tension_a)):
        return None
    if not bool(st.converged) or not float(st.grounded_length) > 0.0:
        return None
    off, ref = (np.asarray(x) for x in resolution_offsets(line, env, st, t))
    if not np.all(np.isfinite(off)):  # the fine solve did not converge
        return None
    worst = int(np.argmax(off))
    if off[worst] > RESOLUTION_TOL:
        n = line.n_segments
        ours = float((st.tension_a, st.tension_b)[worst])
        warnings.warn(
            f"line {line.label}: {n} equal Hermite elements do not resolve its touchdown: end "
            f"{'AB'[worst]}'s static tension {ours:.6g} N differs by {100 * off[worst]:.3g} % from "
            f"the linear element's at {FINE_SEGMENTS * n} segments ({ref[worst]:.6g} N). {RESOLUTION_ADVICE}",
            UnresolvedTouchdownWarning, stacklevel=3)
    return float(off[worst])


def check_lines(lines, env, statics, t=0.0) -> None:
    """:func:`check_piled` and :func:`check_resolution` for lines solved
    together (``statics``: their :class:`~moorjax.statics.fem.LineStatics`,
    ``None`` for a line not solved by finite elements): what
    :func:`~moorjax.statics.fem.solve_line_statics` runs on one line, for the
    lines of a body scene at the poses its statics found (their ends are then
    where the bodies put them, which the lines themselves do not know). Values
    only (nothing under ``jit``/``vmap``). A piled line is not checked for its
    touchdown's resolution: grading does not mend it (:func:`check_piled`)."""
    for line, st in zip(lines, statics):
        if st is not None and not check_piled(line, env, t):
            check_resolution(line, env, st, t)


def touchdown_mesh(line: Line, env, t=0.0, *, iterations: int = 6, tol: float = 1e-3,
                   min_element: float = 0.05) -> Line:
    """The line with its Hermite elements graded about its static touchdown.

    Where a line meets the seabed its curvature jumps (the bed takes the weight)
    and the suspended catenary bends over its length scale a = H/w, which can
    be a small part of an element: a cubic inside one element follows neither.
    At 10 equal elements the grounded lines of
    ``tests/test_hermite_statics_property.py`` miss MoorPy's end tensions by a
    median 4.6e-3 of the largest tension (lines off the bed: 1e-6).

    This solves the statics, takes the touchdown from the suspended end's
    vertical pull (the suspended stretch's unstretched length is V/w: exact for
    a flat frictionless bed without current, a smooth functional of the
    solution), puts an element boundary there and grades the elements away from
    it (:func:`graded_mesh`, first element a = H/w from the suspended end's
    horizontal pull), and repeats until the touchdown moves less than ``tol`` of
    a mean element (at most ``iterations`` times). The first touchdown and pull
    come from equal elements, or, where those fail or bend within
    :data:`SHARP` of an element (their pull is then unreliable), from the linear
    element's equilibrium at :data:`FINE_SEGMENTS` segments per element. A line with one end on the
    bed (an anchor's line) gets one such boundary; a line whose ends are both
    above the bed but which sags onto it gets two (the touchdowns from each
    end's vertical pull). Lines without a seabed, off it, with both ends on it,
    with a touchdown within ``min_element`` of a mean element of an end, or not
    of Hermite elements are returned unchanged, and a mesh whose statics fail
    is not kept (the last one that converged is returned).
    On a bathymetry or with a current the touchdown estimate is approximate
    (the mesh is still a valid one, only less well placed).

    Where even the graded mesh does not resolve the touchdown (the catenary's
    H/w below :data:`SHARP` of a mean element) it warns
    (``UnresolvedTouchdownWarning``), naming the line and the element count
    that would: the end tensions are then unreliable, the grounded end's most
    (on drawn lines of ``tests/test_hermite_statics_property.py`` at 10
    elements, H/w of 0.016–0.046 of an element: up to 1.3e-2 of their own value
    off MoorPy's, against 1.1e-3 for the lines it does not warn for; until
    the second start of :data:`GUESS_SEGMENTS`, up to 26 %).

    Host-level (a few static solves, one compiled program for all): call it
    once when building a scene, before ``solve_line_statics`` and ``simulate``;
    the mesh is a value of the line (changing it does not recompile).
    """
    from ..element.hermite import HermiteElement
    from .fem import line_statics

    if env.seabed is None or not isinstance(line.element, HermiteElement):
        return line
    n, length = line.n_segments, float(line.length)
    mean = length / n
    w = abs(float(line.line_type.wet_weight(env.rho, env.g)))
    env_static = env.without_waves()
    mesh = np.full(n, 1.0 / n) if line.element.mesh is None else np.asarray(line.element.mesh, float)
    current = eqx.tree_at(lambda ln: ln.element.mesh, line, jnp.asarray(mesh / mesh.sum()),
                          is_leaf=lambda x: x is None)
    height_a, height_b = (float(x) for x in _end_heights(line, env_static, jnp.asarray(t, float)))
    tol_z = 1e-6 * max(float(env.depth), 1.0)
    on_a, on_b = height_a <= tol_z, height_b <= tol_z  # the ends on the bed (the mesh moves no end)
    if (on_a and on_b) or w <= 0.0:
        return line  # both ends on the bed (not graded), or a buoyant line
    history, best, here = [], line, None  # best: the last mesh whose statics converged
    last = None  # the last converged statics: best's, or the fine linear element's first

    def finish():
        """``best``, with the warning where its touchdown stays unresolved."""
        if last is not None and float(last.grounded_length) > 0.0 and _sharp(last, on_a, on_b, w, mean):
            _warn_unresolved(line, _horizontal_pull(last, on_a, on_b) / w)
        return best

    for _ in range(iterations + 1):
        st = line_statics(current, env_static, t, throw=False)
        ok = bool(st.converged) and bool(jnp.all(jnp.isfinite(st.rest_state.r)))
        if here is None and (not ok or _sharp(st, on_a, on_b, w, mean)):
            # the first touchdown from the linear element's equilibrium (see
            # FINE_SEGMENTS), where equal Hermite elements fail or bend too sharply
            st = line_statics(_fine_linear(line), env_static, t, throw=False)
            ok = bool(st.converged)
        if not ok:
            return finish()
        last = st
        if here is not None:
            best = current
        if float(st.grounded_length) < min_element * mean:
            return finish()  # off the bed (not graded)
        # a suspended stretch's unstretched length is its end's vertical pull
        # over the weight (the bed carries the rest): exact for a flat,
        # frictionless bed without current, and a smooth functional of the
        # solution (a sampled touchdown is off by the cubic's wiggle on the bed).
        # The touchdowns: from end A's pull unless A is on the bed, and from end
        # B's unless B is (both for a line sagging onto the bed in its middle)
        fa, fb = np.asarray(st.force_a, float), np.asarray(st.force_b, float)
        start = 0.0 if on_a else abs(fa[2]) / w
        end = length if on_b else length - abs(fb[2]) / w
        if not end - start > min_element * mean:
            return finish()
        knots = np.array([start, end])
        inner = np.array([not on_a, not on_b])  # the knots inside the line
        if here is not None:
            if np.all(np.abs(knots - here)[inner] < tol * mean):
                return finish()
            history.append((here, knots - here))  # the mesh's knots, and estimates − knots
        if len(history) >= 2:  # secant steps on estimate − knot (the plain iteration oscillates)
            (x0, f0), (x1, f1) = history[-2:]
            ok = inner & (np.abs(f1 - f0) > 1e-12 * length)
            knots = np.where(ok, x1 - f1 * (x1 - x0) / np.where(ok, f1 - f0, 1.0), knots)
        knots = np.where(inner, np.clip(knots, min_element * mean, length - min_element * mean), knots)
        first = _horizontal_pull(st, on_a, on_b) / w  # the catenary's length scale H/w
        graded = eqx.tree_at(lambda ln: ln.element.mesh, current,
                             jnp.asarray(graded_mesh(length, n, knots[0], knots[1], first)))
        current, here = graded, knots
    return finish()
