"""Static equilibrium of a finite-element line (Newton with optimistix).

The unknowns are the free-node positions; the residual is the element's nodal
force at rest (elastic, weight/buoyancy, seabed contact and — when the scene has
one — the drag of the current). Newton starts from the analytic catenary profile
(or the chord when no catenary exists), and its Jacobian is assembled from 9
coloured JVPs and solved block-tridiagonally (O(n)). Gradients of the solution
use the implicit function theorem (optimistix's ImplicitAdjoint), never unrolled
iterations.

Seabed friction does not act in statics (the node velocities are zero), as in
MoorDyn; the analytic catenary does model it (``moorjax.statics.catenary``).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.lax as lax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array

from ..linalg import block_tridiagonal as btd
from ..linalg.banded_solver import BlockTridiagonalSolver, band_of
from ..model.axial import Bilateral
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

    def state(self) -> LineState:
        """The equilibrium as a dynamic state (free nodes at rest)."""
        r = self.positions[1:-1]
        return LineState(r=r, v=jnp.zeros_like(r))


def _catenary_guess(line: Line, env, t):
    """Free-node positions from the analytic elastic catenary (no friction)."""
    from .catenary import catenary_line_forces, catenary_nodes

    lt = line.line_type
    ra, rb = line.end_a.position(t), line.end_b.position(t)
    w = lt.wet_weight(env.rho, env.g)
    ea = lt.axial.nominal_ea()
    on_seabed = env.seabed is not None
    sol, _, _ = catenary_line_forces(ra, rb, line.length, ea, w, 0.0, seabed=on_seabed)
    s = line.segment_length * jnp.arange(1, line.n_segments)
    nodes = catenary_nodes(sol, ra, rb, s)
    ok = sol.converged & jnp.all(jnp.isfinite(nodes))
    chord = line.straight_state(t).r
    return jnp.where(ok, nodes, chord)


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


_BACKTRACK = 2.0 ** -jnp.arange(12)


def _damped_newton(fn, y0, atol, rtol, max_steps):
    """Newton with backtracking line search on the max-norm of the residual.

    The Jacobian band comes from coloured JVPs (O(n)); trial step lengths 1, ½, …
    are evaluated together (vmap) and the first that reduces the residual wins.
    Stops when the step is below ``atol + rtol·|y|``. Returns (y, iterations).
    """
    def norm(f):
        return jnp.max(jnp.abs(f))

    def cond(c):
        _, it, _, done = c
        return (it < max_steps) & jnp.invert(done)

    def body(c):
        y, it, fy, _ = c
        _, lin = jax.linearize(lambda z: fn(z, None), y)
        lower, diag, upper, _, _ = band_of(lin, jax.ShapeDtypeStruct(y.shape, y.dtype))
        dx = btd.solve(btd.factor(lower, diag, upper), fy)
        trial = jax.vmap(lambda a: fn(y - a * dx, None))(_BACKTRACK)
        tn = jax.vmap(norm)(trial)
        good = jnp.isfinite(tn) & (tn < (1 - 1e-4 * _BACKTRACK) * norm(fy))
        k = jnp.where(jnp.any(good), jnp.argmax(good), _BACKTRACK.shape[0] - 1)
        step = _BACKTRACK[k] * dx
        y_new = y - step
        small = jnp.all(jnp.abs(step) <= atol + rtol * jnp.abs(y_new))
        stuck = jnp.invert(jnp.any(good))
        return y_new, it + 1, trial[k], small | stuck | jnp.invert(jnp.all(jnp.isfinite(y_new)))

    f0 = fn(y0, None)
    y, it, _, _ = lax.while_loop(cond, body, (y0, jnp.array(0), f0, jnp.array(False)))
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


def _check_geometry(line, env, t):
    """Python-level checks on concrete end positions (skipped under tracing)."""
    try:
        ra = np.asarray(line.end_a.position(t), dtype=float)
        rb = np.asarray(line.end_b.position(t), dtype=float)
        length = float(line.length)
        depth = float(env.depth)
    except (jax.errors.ConcretizationTypeError, jax.errors.TracerArrayConversionError, TypeError):
        return
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


def solve_line_statics(
    line: Line,
    env,
    t=0.0,
    init: LineState | None = None,
    *,
    rtol: float = 1e-10,
    atol: float = 1e-8,
    max_steps: int = 100,
    throw: bool = True,
) -> LineStatics:
    """Static equilibrium of one line with its ends where they are at time t.

    Args:
        line, env: the line and its environment.
        t: time at which the end positions are taken [s].
        init: starting state (default: :func:`initial_guess`).
        rtol, atol: Newton step tolerances, relative to the positions and absolute
            [m]; the default resolves 100 m positions to ~1e-8 m.
        max_steps: Newton iteration limit.
        throw: raise ``RuntimeError`` if Newton fails (otherwise inspect
            ``converged``).
    """
    _check_geometry(line, env, t)
    out = _solve_core(line, env, jnp.asarray(t, dtype=float), init, rtol, atol, max_steps)
    if throw:
        out = eqx.error_if(
            out,
            jnp.invert(out.converged),
            "static solve of a line did not converge (Newton failed or left a force "
            "imbalance); check the geometry (can the line reach its ends?), or give "
            "`init`, more `max_steps` or looser tolerances",
        )
    return out


@eqx.filter_jit
def _solve_core(line, env, t, init, rtol, atol, max_steps):
    """The jitted static solve: compiled once per line structure, reused for any values."""
    r0 = initial_guess(line, env, t).r if init is None else init.r
    fn = _residual(line, env, t)
    # 1) a damped Newton (backtracking on the residual) finds the equilibrium
    #    robustly from the catenary guess. It uses a bilateral axial law: on coarse
    #    meshes the catenary guess has chords shorter than the unstretched element
    #    (slack, zero stiffness, a singular Jacobian); letting those segments push
    #    keeps Newton well-posed, and where the equilibrium is taut (the usual case)
    #    both laws have the same solution. 2) optimistix's Newton with the true law,
    #    started there, polishes it and attaches implicit-function gradients.
    axial = line.line_type.axial
    bilateral = axial if isinstance(axial, Bilateral) else Bilateral(axial)
    line_bi = eqx.tree_at(lambda ln: ln.line_type.axial, line, bilateral)
    fn_bi = _residual(line_bi, env, t)
    r_start, damped_steps = _damped_newton(fn_bi, lax.stop_gradient(r0), atol, rtol, max_steps)
    solver = optx.Newton(rtol=rtol, atol=atol, linear_solver=BlockTridiagonalSolver())
    sol = optx.root_find(fn, solver, r_start, max_steps=max_steps, throw=False)
    # a diverged polish must not hand back NaN: keep the last finite iterate (the
    # result is then flagged not converged by its force imbalance)
    r_free = jnp.where(jnp.all(jnp.isfinite(sol.value)), sol.value, r_start)
    r, _ = line.nodes(t, LineState(r=r_free, v=jnp.zeros_like(r_free)))
    v0 = jnp.zeros_like(r)
    element = line.element
    force = element.nodal_forces(line, env, r, v0)
    max_res = jnp.max(jnp.abs(force[1:-1]))
    tensions = element.segment_tensions(line, r, v0)
    scale = jnp.maximum(jnp.max(jnp.abs(tensions)), 1.0)
    converged = (sol.result == optx.RESULTS.successful) & jnp.all(jnp.isfinite(r)) & (
        max_res < 1e-6 * scale
    )
    fa, fb = force[0], force[-1]
    out = LineStatics(
        positions=r,
        tensions=tensions,
        force_a=fa,
        force_b=fb,
        tension_a=jnp.linalg.norm(fa),
        tension_b=jnp.linalg.norm(fb),
        grounded_length=_grounded_length(line, env, r),
        converged=converged,
        iterations=damped_steps + sol.stats["num_steps"],
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
