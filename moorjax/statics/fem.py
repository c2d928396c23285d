"""Static equilibrium of a finite-element line (energy descent, Newton polish).

The unknowns are the free-node positions; the residual is the element's nodal
force at rest (elastic, weight/buoyancy, seabed contact and — when the scene has
one — the drag of the current). The iteration starts from the analytic catenary
profile (touchdown only where the lower end rests on the seabed; nodes under the
bed lifted to their resting penetration; the chord when no catenary exists).
Without a current these forces are minus the gradient of a convex energy, so a
regularised Newton iteration with a line search on that energy converges from
any start, through touchdown and slack kinks (``_descent``). Its Jacobian is
assembled from 9 coloured JVPs and solved block-tridiagonally (O(n)). Near the
root its steps are Newton's, and it ends with one of them past the tolerance
(the polish: quadratic convergence); gradients are attached to the answer by
the implicit function theorem (``_implicit``, a minimum-norm solve where the
shape is undetermined), never through unrolled iterations.

Seabed friction does not act in statics (the node velocities are zero), as in
MoorDyn; the analytic catenary does model it (``moorjax.statics.catenary``).
"""

from __future__ import annotations

import functools
from typing import Any

import equinox as eqx
import jax
import jax.lax as lax
import jax.numpy as jnp
import lineax as lx
import numpy as np
from jaxtyping import Array

from .._cache import StoredProgram
from .._numerics import as_float, safe_norm
from ..linalg import block_tridiagonal as btd
from ..linalg.banded_solver import band_of
from ..linalg.undetermined import MinimumNorm
from ..model.ends import FixedEnd
from ..model.line import Line, LineState


class LineStatics(eqx.Module):
    """A line's static solution.

    Attributes:
        positions: (n+1, 3) node positions [m], ends included.
        tensions: (n,) segment tensions [N].
        force_a, force_b: (3,) forces the line exerts on its end A / B points [N].
        tension_a, tension_b: magnitudes of those forces [N].
        grounded_length: unstretched length resting on the seabed [m].
        converged: whether Newton met its tolerance.
        iterations: Newton iterations used.
        max_residual: largest free-node force imbalance [N].
        rest_state: the state at rest of an element whose state is more than node
            positions (a Hermite line's :class:`~moorjax.element.hermite_motion.HermiteState`,
            with its slopes), else ``None``.
        dofs: the static unknowns themselves where they are more than the state
            holds (a Hermite line's :class:`~moorjax.element.hermite.HermiteDofs`:
            positions, slopes and tension field of Wu's equilibrium, which its
            ``rest_state``, the strain closure's equilibrium, does not keep),
            else ``None``.
    """

    positions: Array
    tensions: Array
    force_a: Array
    force_b: Array
    tension_a: Array
    tension_b: Array
    grounded_length: Array
    converged: Array
    iterations: Array
    max_residual: Array
    rest_state: Any = None
    dofs: Any = None

    def warm_start(self):
        """What a static solve of the same line nearby starts from (``init``):
        the unknowns where they are kept (:attr:`dofs`), else :meth:`state`.
        A Hermite line started again from its ``rest_state`` (slopes and the
        tension field rebuilt from the closure's shape) failed on 8 of the 199
        drawn lines of ``tests/test_hermite_statics_property.py`` that converge
        cold, and body scenes on such lines could not start."""
        return self.dofs if self.dofs is not None else self.state()

    def state(self):
        """The equilibrium as a dynamic state (free nodes at rest; ``rest_state``
        where the element has one)."""
        if self.rest_state is not None:
            return self.rest_state
        r = self.positions[1:-1]
        return LineState(r=r, v=jnp.zeros_like(r))


def _catenary_guess(line: Line, env, t):
    """Free-node positions from the analytic elastic catenary (no friction)."""
    from .catenary import _frame, nodes_in_frame, solve_catenary

    lt = line.line_type
    ra, rb = line.end_a.position(t), line.end_b.position(t)
    w = lt.wet_weight(env.rho, env.g)
    ea = lt.axial.nominal_ea()
    # the analytic touchdown model needs the lower end on the seabed; a line whose
    # ends are both above it starts from the free catenary, lifted onto the bed
    touchdown = env.seabed is not None and jnp.minimum(ra[2], rb[2]) <= -env.depth * (1.0 - 1e-6)
    lo, e, xf, zf, swap = _frame(ra, rb)  # once: a program compiled without XLA's passes
    sol = solve_catenary(xf, zf, line.length, ea, w, 0.0, seabed=touchdown)  # keeps both copies
    s = line.segment_length * jnp.arange(1, line.n_segments)
    nodes = nodes_in_frame(sol, lo, e, swap, s)
    ok = sol.converged & jnp.all(jnp.isfinite(nodes))
    nodes = jnp.where(ok, nodes, line.straight_state(t).r)
    if env.seabed is not None:
        # nodes on (or under) the bed start at the static penetration of a resting node
        sink = jnp.maximum(w, 0.0) / (env.seabed.stiffness * lt.diameter)
        z = nodes[:, 2]
        nodes = nodes.at[:, 2].set(jnp.where(z < -env.depth + sink, -env.depth - sink, z))
    return nodes


def initial_guess(line: Line, env, t=0.0) -> LineState:
    """A starting state for statics: the catenary profile, else the chord."""
    r = _catenary_guess(line, env, t)
    return LineState(r=r, v=jnp.zeros_like(r))


def _residual(line, env, t):
    # Forces are divided by the element's axial stiffness EA/l, so the residual is
    # a displacement [m] and one tolerance in metres serves steps and residuals.
    k = line.line_type.axial.nominal_ea() / line.segment_length

    def fn(r_free, args):
        del args
        r, _ = line.nodes(t, LineState(r=r_free, v=jnp.zeros_like(r_free)))
        force = line.element.nodal_forces(line, env, r, jnp.zeros_like(r))
        return force[1:-1] / k

    return fn


def _force_scale(line, env, t):
    """The force scale [N] of an iterate: its largest tension, at least one node's weight."""
    weight = jnp.abs(line.line_type.wet_weight(env.rho, env.g)) * line.segment_length

    def scale(r_free):
        r, _ = line.nodes(t, LineState(r=r_free, v=jnp.zeros_like(r_free)))
        tension = line.element.segment_tensions(line, r, jnp.zeros_like(r))
        return jnp.maximum(jnp.max(jnp.abs(tension)), weight)

    return scale


_ALPHAS = 2.0 ** -np.arange(16.0)  # NumPy: no XLA op at import


def _band_step(fn, y, fy, mu):
    """Solve (μI − J)·Δy = f with J's block-tridiagonal band (coloured JVPs, O(n))."""
    _, lin = jax.linearize(lambda z: fn(z, None), y)
    lower, diag, upper, _, _ = band_of(lin, jax.ShapeDtypeStruct(y.shape, y.dtype))
    return btd.solve(btd.factor(-lower, mu * jnp.eye(3) - diag, -upper), fy)


def _dense_step(fn, y, fy, mu):
    """Solve (μI − J)·Δy = f with the dense Jacobian (lines coupling nodes further:
    bending stiffness)."""
    m = y.size
    jac = jax.jacfwd(lambda z: fn(z, None).reshape(-1))(y).reshape(m, m)
    return jnp.linalg.solve(mu * jnp.eye(m) - jac, fy.reshape(-1)).reshape(y.shape)


#: steps of the descent from a warm start before it restarts from the catenary
#: guess (at most half the limit): half the old limit of 500. A warm start that
#: crawls is left early (MoorDyn's ``seafloor.txt`` pendulum, below, fails to
#: balance its point when the restart waits for 1000 of 2000 steps)
RESTART_STEPS = 250


def _descent(fn, y0, tol, max_steps, soft_length, step=_band_step, restart=None, small=None):
    """Regularised Newton with an exact line search on the static energy.

    Without a current the static forces are the negative gradient of a convex
    energy (a tension-only axial law with nondecreasing tension, gravity, the
    one-sided seabed spring), so every step is a descent step of that energy:
    the direction solves (μI − J)·Δy = f with the block-tridiagonal band of J
    (coloured JVPs, O(n); ``step``), μ = max|f|/soft_length keeps it defined where J is
    singular (slack or unloaded directions move at most ~soft_length per step),
    and the step length is where the energy stops decreasing along Δy: the sign
    change of g(α) = −f(y + αΔy)·Δy, bracketed on α = 1, ½, … (vmapped) and
    interpolated. Touchdown and slack kinks only make g piecewise smooth, so the
    iteration cannot stall on them. Returns (y, iterations).

    Stops when max|f| ≤ tol(y). With ``small`` (a test of a step Δy and the
    iterate it led to) it stops there only if the step that got there was
    small, else takes one more step, the polish: near the root μ → 0 and the
    step is Newton's, taken in full (quadratic convergence) where that does not
    raise the imbalance, and kept only if it stays within tol. A separate
    Newton solve would add the same; a step in a direction the forces do not
    determine (a singular J: a slack weightless line piled on the bed) is not
    repeated for ever.

    ``restart`` (a start like ``y0``, or None): where ``y0`` has not converged in
    :data:`RESTART_STEPS` steps (or half the steps), the rest start from it. A
    warm start (a neighbouring solution: the system statics' previous pose) can
    sit where the descent crawls; the catenary guess then converges (MoorDyn's
    ``seafloor.txt`` pendulum: a weightless slack line of EA = 1e9 N, taut at 1e-10 strain below a
    kink, failed from its last shape at most trial poses and converged from the
    guess).
    """
    def cond(c):
        it, done = c[3], c[4]
        return (it < max_steps) & jnp.invert(done)

    if restart is not None:
        # once, not per step (a cond on a vmapped count runs both sides)
        f_restart, tol_restart = fn(restart, None), tol(restart)
        # a start that is the restart itself (a body iteration's first trial
        # starts from the catenary guess) keeps all its steps: a slack line
        # piled on the bed crawls, and restarting it from where it began halved
        # them (its solve failed at a point scene's deck pose, where it
        # converges from no start)
        differs = jnp.any(restart != y0)

    def body(c):
        # tol(y) is carried: the force scale it needs is computed once per iterate
        y, fy, tol_y, it, _, within_before = c
        if restart is not None:
            now = (it == min(max_steps // 2, RESTART_STEPS)) & differs
            y, fy = jnp.where(now, restart, y), jnp.where(now, f_restart, fy)
            tol_y = jnp.where(now, tol_restart, tol_y)
            within_before = within_before & jnp.invert(now)
        mu = jnp.max(jnp.abs(fy)) / soft_length
        dy = step(fn, y, fy, mu)
        dy = jnp.where(jnp.all(jnp.isfinite(dy)), dy, fy)  # a failed solve: relax along f
        alphas = jnp.asarray(_ALPHAS)
        f_trial = jax.vmap(lambda a: fn(y + a * dy, None))(alphas)
        g = -jnp.sum(f_trial * dy, axis=tuple(range(1, f_trial.ndim)))
        g = jnp.where(jnp.isfinite(g), g, jnp.inf)
        down = g <= 0.0  # the energy still decreases at α
        k = jnp.argmax(down)  # the largest such α (α decreases with k)
        k = jnp.where(jnp.any(down), k, _ALPHAS.shape[0] - 1)
        a_lo = alphas[k]
        a_hi = alphas[jnp.maximum(k - 1, 0)]
        g_lo, g_hi = g[k], g[jnp.maximum(k - 1, 0)]
        # k = 0: the full step still descends, take it; otherwise interpolate the
        # sign change of g between a_lo (g <= 0) and a_hi (g > 0)
        frac = jnp.where(jnp.isfinite(g_hi) & (g_hi > g_lo), -g_lo / (g_hi - g_lo), 0.0)
        alpha = jnp.where(k == 0, a_lo, a_lo + (a_hi - a_lo) * jnp.clip(frac, 0.0, 0.9))
        # The polish (y within tol): the full step, Newton's, wherever it does not
        # raise the imbalance. At the root g(1) is rounding, and an interpolated
        # α ≈ 0.95 would converge linearly.
        res_full = jnp.max(jnp.abs(f_trial[0]))
        full = within_before & (res_full <= jnp.maximum(jnp.max(jnp.abs(fy)), tol_y))
        alpha = jnp.where(full, 1.0, alpha)
        y_new = y + alpha * dy
        f_new = fn(y_new, None)
        ok = jnp.all(jnp.isfinite(f_new))  # else the bracket's lower end, evaluated above
        y_new, f_new = jnp.where(ok, y_new, y + a_lo * dy), jnp.where(ok, f_new, f_trial[k])
        tol_new = tol(y_new)
        within = jnp.max(jnp.abs(f_new)) <= tol_new
        if small is None:
            return y_new, f_new, tol_new, it + 1, within, within
        # the polish step, from an iterate within tol, is the last: kept where it
        # stays within tol (else that iterate is the answer)
        done = within_before | (within & small(y_new - y, y_new))
        keep = within_before & jnp.invert(within)
        y_new, f_new = jnp.where(keep, y, y_new), jnp.where(keep, fy, f_new)
        return y_new, f_new, jnp.where(keep, tol_y, tol_new), it + 1, done, within | keep

    f0, tol0 = fn(y0, None), tol(y0)
    within0 = jnp.max(jnp.abs(f0)) <= tol0
    c0 = (y0, f0, tol0, jnp.array(0), within0 if small is None else jnp.array(False), within0)
    y, _, _, it, _, _ = lax.while_loop(cond, body, c0)
    return lax.stop_gradient(y), it


def _grounded_length(line, env, r):
    if env.seabed is None:
        return jnp.zeros(())
    lt = line.line_type
    w = lt.wet_weight(env.rho, env.g)
    l = line.segment_length
    pen = -env.depth - r[:, 2]
    contact = jnp.where(pen > 0, env.seabed.stiffness * pen * lt.diameter * l, 0.0)
    interior = jnp.sum(contact[1:-1]) / jnp.where(w > 0, w, jnp.inf)
    tol = 1e-6 * env.depth
    ends_on_bed = (jnp.abs(pen[0]) < tol) & (pen[1] > 0), (jnp.abs(pen[-1]) < tol) & (pen[-2] > 0)
    ends = 0.5 * l * (ends_on_bed[0].astype(float) + ends_on_bed[1].astype(float))
    return jnp.where(w > 0, interior + ends, 0.0)


#: Largest strain a static solve accepts: a line whose ends are farther apart than
#: (1 + MAX_STRAIN)·L cannot reach them at any plausible tension.
MAX_STRAIN = 0.5


@eqx.filter_jit
def _end_positions(line, t):
    # one small program per line structure: a tabulated motion's lookup run
    # eagerly would be some twenty XLA operations, each compiled on its own
    return line.end_a.position(t), line.end_b.position(t)


def concrete_geometry(line, env, t):
    """The line's end positions ra, rb (3,) [m] at time t, its unstretched length
    [m] and the water depth [m] as NumPy values, or None where any of them is
    traced (under ``jit``/``vmap``: the host-level checks are then skipped)."""
    try:
        ends = _end_positions(line, t if isinstance(t, jax.core.Tracer) else np.float64(t))
        ra, rb = (np.asarray(r, dtype=float) for r in ends)
        return ra, rb, float(line.length), float(env.depth)
    except (jax.errors.ConcretizationTypeError, jax.errors.TracerArrayConversionError, TypeError):
        return None


def check_geometry(line, env, t):
    """Python-level checks on concrete end positions (skipped under tracing)."""
    geometry = concrete_geometry(line, env, t)
    if geometry is None:
        return
    ra, rb, length, depth = geometry
    for name, r in (("A", ra), ("B", rb)):
        if r[2] < -depth * (1 + 1e-6):
            raise ValueError(
                f"line {line.label}: end {name} at z = {r[2]:.6g} m is below the seabed "
                f"(z = {-depth:.6g} m); expected z >= -depth"
            )
    chord = float(np.linalg.norm(rb - ra))
    if chord > (1 + MAX_STRAIN) * length:
        raise ValueError(
            f"line {line.label}: impossible geometry: its ends are {chord:.6g} m apart but its "
            f"unstretched length is {length:.6g} m (strain {chord / length - 1:.3g} > "
            f"{MAX_STRAIN}); lengthen the line or move its ends"
        )


#: Default tolerances of the static solve (see :func:`solve_line_statics`).
RTOL, ATOL = 1e-10, 1e-8
#: The linear element's default step limit of the descent (``max_steps=None``;
#: other elements have their own: the Hermite statics' Newton takes 500). A
#: line longer than its anchor's L-shaped path to the fairlead piles on the bed
#: and its slack segments move a little per step: drawn point scenes' lines at 80
#: segments took 438–656 steps (500 before session 40: their body starts failed).
MAX_STEPS = 2000


def solve_line_statics(
    line: Line,
    env,
    t=0.0,
    init: LineState | None = None,
    *,
    rtol: float = RTOL,
    atol: float = ATOL,
    max_steps: int | None = None,
    throw: bool = True,
    method: str = "fem",
) -> LineStatics:
    """Static equilibrium of one line with its ends where they are at time t.

    Two answers exist for a line of n segments, and ``method`` chooses:

    * ``"fem"`` (default): the equilibrium of the discrete (lumped-mass) model,
      the state dynamics start from (:meth:`LineStatics.state`). Its end tensions
      carry the discretisation error, largest where the touchdown kink is sharper
      than a segment (H/w below a few tens of segment lengths).
    * ``"catenary"``: the exact elastic catenary of the continuous line sampled at
      the nodes (:mod:`moorjax.statics.exact`); only for lines it describes
      exactly (Hooke's law, no current, flat seabed; a bending length √(EI/H)
      under 1e-4 of the length) and geometries where it has a solution, else
      ``ValueError`` / not converged.
    * ``"auto"``: ``"catenary"`` where it applies, else ``"fem"`` — the line's
      statics to the solver's precision whatever the segment count; what
      ``moorjax statics`` reports.

    Args:
        line, env: the line and its environment.
        t: time at which the end positions are taken [s].
        init: starting state (default: :func:`initial_guess`).
        rtol, atol: the last step's tolerance, relative to the positions and
            absolute [m] (or the step after the first iterate within the force
            tolerance is the last); ``atol`` also caps the descent's
            residual (forces / (EA/l), in m). The result is ``converged`` when
            the largest free-node force imbalance is below 1e-6 of the largest
            tension (or of one segment's weight), or at float64 resolution.
        max_steps: iteration limit of the descent (None: the element's own,
            :data:`MAX_STEPS` for the linear element).
        throw: raise ``RuntimeError`` if Newton fails (otherwise inspect
            ``converged``).

    A grounded line of equal Hermite elements solved outside ``jit`` is checked
    against the linear element at :data:`~moorjax.statics.hermite.FINE_SEGMENTS`
    segments per element (:func:`~moorjax.statics.hermite.check_resolution`):
    where their end tensions differ by more than
    :data:`~moorjax.statics.hermite.RESOLUTION_TOL` the touchdown bends
    more sharply than the elements resolve, and it warns
    (``UnresolvedTouchdownWarning``; ``converged`` says only that the discrete
    equations are solved). A Hermite line longer than its path along the seabed
    warns before the solve (``PiledLineWarning``,
    :func:`~moorjax.statics.hermite.check_piled`), and is then not checked
    for its touchdown (grading does not mend it).
    """
    from .hermite import check_piled, check_resolution

    piled = check_piled(line, env, t)  # before a solve that may fail on such a line
    out = line_statics(line, env, t, init, rtol=rtol, atol=atol, max_steps=max_steps, throw=throw,
                       method=method)
    if not piled:  # grading the touchdown does not mend a piled line
        check_resolution(line, env, out, t)
    return out


def line_statics(line, env, t=0.0, init=None, *, rtol=RTOL, atol=ATOL, max_steps=None,
                 throw=True, method="fem") -> LineStatics:
    """:func:`solve_line_statics` without its check of a Hermite line's
    resolution (what :func:`moorjax.statics.hermite.touchdown_mesh` calls
    while it grades the mesh)."""
    check_geometry(line, env, t)
    from .exact import catenary_eligible

    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    eligible = catenary_eligible(line, env)
    if method == "catenary" and not eligible:
        raise ValueError(
            f"line {line.label}: method='catenary' needs a linear element with Hooke's law "
            "(LinearEA), no current and a flat seabed; use method='fem' or 'auto'")
    t = as_float(t)
    if method == "fem" or not eligible:
        out = element_core(line)(line, env, t, init, rtol, atol, max_steps)
    else:
        out = _exact_core(line, env, t, init, rtol, atol, max_steps, method == "auto")
    if throw:
        out = eqx.error_if(
            out,
            jnp.invert(out.converged),
            "static solve of a line did not converge (Newton failed or left a force "
            "imbalance); check the geometry (can the line reach its ends?), or give "
            "`init`, more `max_steps` or looser tolerances",
        )
    return out


def element_core(line):
    """The jitted finite-element static solve for the line's element:
    ``_solve_core`` (node elements) or the Hermite element's, whose unknowns carry
    slopes and a tension field (``statics.hermite.hermite_statics_core``); both
    are called as ``core(line, env, t, init, rtol, atol, max_steps)``."""
    from ..element.hermite import HermiteElement

    if isinstance(line.element, HermiteElement):
        from .hermite import hermite_statics_core

        return hermite_statics_core
    return _solve_core


#: The choices of :func:`solve_line_statics`'s ``method``.
METHODS = ("fem", "catenary", "auto")


# eqx.filter_jit, its program also stored on disk (moorjax._cache) and compiled
# for one run (moorjax._xla_flags.PRESETS)
@functools.partial(StoredProgram, compile_for="once")
def _exact_core(line, env, t, init, rtol, atol, max_steps, fallback):
    """The catenary statics; with ``fallback``, the finite-element solve where it fails."""
    from .exact import catenary_statics

    out, ok = catenary_statics(line, env, t)
    if not fallback:
        return out

    def fem():
        return _solve_core(line, env, t, init, rtol, atol, max_steps)

    like = jax.eval_shape(fem)
    out = jax.tree.map(lambda a, b: jnp.asarray(a, b.dtype), out, like)
    return lax.cond(ok, lambda: out, fem)


def _values(tree):
    """``tree`` with every array's derivative stopped (the search for a root)."""
    return jax.tree.map(lambda x: lax.stop_gradient(x) if eqx.is_array(x) else x, tree)


@eqx.filter_custom_jvp
def implicit_root(y, residual, params):
    """``y``, a root of ``residual(*params)`` (a function ``(y, args) -> F``, as
    optimistix and lineax call it), with the implicit-function derivative
    ẏ = −J⁻¹·∂F/∂θ·θ̇ attached, however ``y`` was found (never the derivative of
    the iterations). J⁻¹ is the solve of
    :class:`~moorjax.linalg.undetermined.MinimumNorm`: LU, or where J is
    singular (the undetermined shape of a slack weightless line) the
    minimum-norm solution, or zero where J or ``y`` is not finite (a failed
    solve); it never raises. It replaces optimistix's own implicit derivative
    in the Hermite statics, which is taken at optimistix's Newton value: where
    that Newton fails, as the strain closure's does on a 1500 m chain with
    1.1 km on the bed (a singular Jacobian; the start falls back to Wu's
    equilibrium), lineax raised on its NaN under ``jax.jacfwd`` and
    ``jax.linearize``, and a body scene with such a line could not start."""
    return y


@implicit_root.def_jvp
def _implicit_root_jvp(primals, tangents):
    y, residual, params = primals
    _, _, t_params = tangents
    f, b_dot = eqx.filter_jvp(lambda p: residual(*p)(y, None), (params,), (t_params,))
    # an output the tangents do not reach comes back as None (a symbolic zero)
    if b_dot is None:
        b_dot = jax.tree.map(jnp.zeros_like, f)
    b_dot = jax.tree.map(lambda fi, bi: jnp.zeros_like(fi) if bi is None else bi, f, b_dot,
                         is_leaf=lambda x: x is None)
    op = lx.JacobianLinearOperator(residual(*params), y)
    y_dot = lx.linear_solve(op, b_dot, MinimumNorm(), throw=False).value
    return y, jax.tree.map(jnp.negative, y_dot)


def _implicit(r_free, line, env, t):
    """``r_free``, an equilibrium of ``_residual(line, env, t)``, with its
    implicit-function derivative (:func:`implicit_root`)."""
    return implicit_root(r_free, _residual, (line, env, t))


@functools.partial(StoredProgram, compile_for="once")  # as _exact_core
def _solve_core(line, env, t, init, rtol, atol, max_steps):
    """The jitted static solve: compiled once per line structure, reused for any values."""
    max_steps = MAX_STEPS if max_steps is None else max_steps
    env = env.without_waves()  # statics: the mean state, waves ignored (as MoorDyn's IC)
    r0 = initial_guess(line, env, t).r if init is None else init.r
    # A regularised Newton descent on the static energy (``_descent``) finds the
    # equilibrium from the catenary guess with the true (tension-only) law: it
    # cannot stall on the touchdown or slack kinks. It stops 100× below the force
    # imbalance that counts as converged (never below what float64 resolves:
    # positions carry eps·|r| of rounding) once a step is below rtol·|r| + atol,
    # or one (Newton) step after it first got there: its own polish, no second
    # root finder in the program. It searches on values only; the answer gets its
    # derivative from the implicit function theorem once, however it was found
    # (``_implicit``: never the derivative of the iterations).
    fn = _residual(*_values((line, env, t)))
    k = line.line_type.axial.nominal_ea() / line.segment_length
    scale = _force_scale(line, env, t)

    def floor(y):
        return 16.0 * jnp.finfo(y.dtype).eps * jnp.maximum(jnp.max(jnp.abs(y)), line.length)

    def tol(y):
        return jnp.maximum(jnp.minimum(atol, 1e-8 * scale(y) / k), floor(y))

    def small(dy, y):
        return jnp.all(jnp.abs(dy) <= atol + rtol * jnp.abs(y))

    banded = line.banded_jacobian
    # from ``init``, the catenary guess once RESTART_STEPS did not converge
    restart = None if init is None else lax.stop_gradient(initial_guess(line, env, t).r)
    r_found, steps = _descent(fn, lax.stop_gradient(r0), tol, max_steps, line.segment_length,
                              _band_step if banded else _dense_step, restart, small)
    r_free = _implicit(r_found, line, env, t)
    r, _ = line.nodes(t, LineState(r=r_free, v=jnp.zeros_like(r_free)))
    v0 = jnp.zeros_like(r)
    element = line.element
    force = element.nodal_forces(line, env, r, v0)
    max_res = jnp.max(jnp.abs(force[1:-1]))
    tensions = element.segment_tensions(line, r, v0)
    converged = jnp.all(jnp.isfinite(r)) & (
        max_res < jnp.maximum(1e-6 * scale(r_free), 100.0 * k * floor(r_free))
    )
    fa, fb = force[0], force[-1]
    out = LineStatics(
        positions=r,
        tensions=tensions,
        force_a=fa,
        force_b=fb,
        tension_a=safe_norm(fa),
        tension_b=safe_norm(fb),
        grounded_length=_grounded_length(line, env, r),
        converged=converged,
        iterations=steps,
        max_residual=max_res,
    )
    return out


def solve_statics(scene, t=0.0, **kwargs) -> tuple[LineStatics, ...]:
    """Static equilibrium of every line of a scene (lines between fixed/held points)."""
    return tuple(solve_line_statics(line, scene.env, t, **kwargs) for line in scene.lines)


def fairlead_stiffness(line: Line, env, end: str = "b", t=0.0, **kwargs) -> Array:
    """Stiffness matrix K = −dF/dx (3×3) [N/m] of a line at its end A or B.

    F is the force the line exerts on that end point and x the end position; the
    derivative is exact (forward-mode AD through the implicit-function gradient of
    the static solve).
    """
    if end not in ("a", "b"):
        raise ValueError(f"end must be 'a' or 'b', got {end!r}")
    pos = (line.end_a if end == "a" else line.end_b).position(t)

    def force_at(x):
        moved = eqx.tree_at(
            (lambda ln: ln.end_a) if end == "a" else (lambda ln: ln.end_b), line, FixedEnd(x)
        )
        st = solve_line_statics(moved, env, t, **kwargs)
        return st.force_a if end == "a" else st.force_b

    return -jax.jacfwd(force_at)(pos)
