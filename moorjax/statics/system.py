"""Static equilibrium of a mooring system with floating bodies, and its stiffness.

The bodies' equilibrium poses η solve ``F_body(η) + F_moor(η) = 0`` per body,
where F_body is each body's mean load (its
:meth:`~moorjax.body.base.AbstractBody.mean_load`: the hydrostatic restoring force
−Cη, a constant ``static_force`` and the mean of each external load: a wave
load's mean drift, a steady load's force), and
F_moor is the wrench of the lines, each in its own static equilibrium with its
fairleads where the poses put them. The Newton iteration on the 6·n_bodies
unknowns takes its Jacobian by forward-mode AD through the lines' static solves
(whose implicit-function gradients make it exact); one compiled function serves
every iteration.

:func:`mooring_stiffness` is the linearised 6×6 stiffness −∂F_moor/∂η of the
lines at a pose, by the same AD; the system's stiffness is that plus C.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._numerics import as_float
from ..body.coupling import attach, mooring_wrenches
from ..body.point import ConnectionPoint
from ..model.grouping import map_lines
from .exact import catenary_eligible, catenary_solves
from .fem import (ATOL, RTOL, LineStatics, _exact_core, _solve_core, check_geometry,
                  element_core, initial_guess)


class SystemStatics(eqx.Module):
    """The equilibrium of a scene with bodies.

    Attributes:
        poses: (n_bodies, 6) body displacements η [m, rad].
        lines: one :class:`LineStatics` per line.
        mooring: (n_bodies, 6) wrench of the lines on each body [N, N·m].
        residual: (n_bodies, 6) force imbalance left [N, N·m].
        iterations: Newton iterations used.
        converged: whether the imbalance met the tolerance.
        methods: each line's statics, ``"fem"`` or ``"catenary"`` (see
            :func:`solve_system_statics`'s ``method``).
    """

    poses: Array
    lines: tuple
    mooring: Array
    residual: Array
    iterations: int
    converged: bool
    methods: tuple = eqx.field(static=True, default=())

    def state(self) -> tuple:
        """Initial solver state for :func:`moorjax.simulate`: line states, then
        each body at rest at its pose (radiation memory empty)."""
        return tuple(st.state() for st in self.lines)

    def body_states(self, scene) -> tuple:
        return tuple(b.rest_state(p) for b, p in zip(scene.bodies, self.poses))


def _attached(scene, poses):
    return attach(scene.lines, scene.bodies, list(poses), [jnp.zeros(6)] * len(scene.bodies))


def line_statics_at(scene, poses, t, inits=None, methods=None):
    """Each line's static solve (``LineStatics``) with its fairleads where the
    bodies' ``poses`` (n_bodies, 6) put them, each started from ``inits`` (line
    states, or None: the element's own first guess), by ``methods``."""
    lines = _attached(scene, poses)
    inits = (None,) * len(lines) if inits is None else inits
    methods = ("fem",) * len(lines) if methods is None else methods
    t = as_float(t)
    # no end-below-the-bed check here: a free point resting on the seabed sinks to
    # its contact penetration, carried by its lines' end-node contact (as in MoorDyn);
    # a failed line solve is reported by ``converged``

    def one(ln, init, method):
        if method == "catenary":
            return _exact_core(ln, scene.env, t, init, RTOL, ATOL, None, False)
        return element_core(ln)(ln, scene.env, t, init, RTOL, ATOL, None)

    # lines of one structure (and method) solve as one vmapped call: one traced
    # copy of the solve per structure, not per line (moorjax.model.grouping)
    return map_lines(one, lines, inits, methods)


def line_starts(scene, poses, t):
    """Each line's start for a static solve with its fairleads where ``poses``
    put them: what the solve would start from without one. For node elements
    that is the catenary guess (:func:`~moorjax.statics.fem.initial_guess`), so a
    program that solves warm from here holds no second (cold) copy of the solve;
    other elements (Hermite) start from their own solve's answer."""
    t = as_float(t)

    def one(ln):
        if element_core(ln) is _solve_core:
            return initial_guess(ln, scene.env, t)
        return element_core(ln)(ln, scene.env, t, None, RTOL, ATOL, None).warm_start()

    return map_lines(one, _attached(scene, poses))


def mooring_wrench(scene, poses, t=0.0, inits=None, methods=None) -> Array:
    """(n_bodies, 6) static wrench of the lines on each body at poses (n_bodies, 6).

    ``inits``: optional line states to start each line's static solve from (a
    nearby solution: continuation is more robust than the catenary guess for
    lines resting on the seabed).
    """
    poses = jnp.asarray(poses, dtype=float).reshape(len(scene.bodies), 6)
    st = line_statics_at(scene, poses, t, inits, methods)
    ends = [(s.force_a, s.force_b) for s in st]
    return jnp.stack(mooring_wrenches(scene.lines, scene.bodies, list(poses), ends))


def body_forces(scene, poses, t=0.0, loads=True) -> Array:
    """(n_bodies, 6) static non-mooring forces at poses: each body's
    :meth:`~moorjax.body.base.AbstractBody.mean_load` (−Cη + static + mean loads)."""
    return jnp.stack([body.mean_load(pose, t, scene.env, loads=loads)
                      for body, pose in zip(scene.bodies, poses)])


@eqx.filter_jit
def _newton_parts(scene, poses, t, loads, inits, methods):
    def imbalance(p):
        return body_forces(scene, p, t, loads) + mooring_wrench(scene, p, t, inits, methods)

    g, jvp_fn = jax.linearize(imbalance, poses)
    jac = jax.vmap(jvp_fn)(jnp.eye(poses.size).reshape((poses.size,) + poses.shape))
    jac = jac.reshape(poses.size, poses.size).T
    return g, jac


#: Newton iterations the bodies' statics allow by default (here and in
#: :func:`moorjax.dynamics.initial.equilibrium_state`): where a body or point is
#: held only by a slack line, the regularised steps move it a bounded distance
#: each; MoorDyn's ``seafloor.txt`` point sliding 16 m down a frictionless slope
#: takes 15–29 iterations (105, or more than 200, before the lines' statics
#: restarted from the catenary guess: see :func:`admissible_rise`)
MAX_ITERATIONS = 200


#: an accepted Newton step that moves no body by more than this [m, rad] and
#: does not lower the largest imbalance is a stall; :data:`STALLS` in a row stop
#: the bodies' statics (a body pressed into the bed by its own fairlead's line
#: contact crept by 7e-7 m per iteration, each trying 20 halvings, for 200
#: iterations: 4 minutes)
STALL_STEP = 1e-6
STALLS = 5


def stalled(step, size_before, size_after) -> Array:
    """Whether an accepted step (n_bodies, 6) is a stall (see :data:`STALL_STEP`)."""
    return (jnp.max(jnp.abs(step)) <= STALL_STEP) & (size_after >= size_before)


#: how far [m] below the seabed under it a body's reference point may go before
#: the bodies' statics stop: bodies have no seabed contact, so a body that sinks
#: through the bed has no equilibrium (its lines' nodes resting on the bed
#: penetrate millimetres, so a point carried by them stays well within this)
SUNK_MARGIN = 1.0


def sunk_bodies(scene, poses) -> Array:
    """(n_bodies,) whether each body's reference point at ``poses`` is more than
    :data:`SUNK_MARGIN` below the seabed under it."""
    ref = jnp.stack([b.origin for b in scene.bodies]) + jnp.asarray(poses)[:, :3]
    return ref[:, 2] < scene.env.seabed_height(ref[:, 0], ref[:, 1]) - SUNK_MARGIN


def imbalance_report(scene, poses, residual, mooring) -> str:
    """Words for an unconverged equilibrium (concrete arrays): the force and
    moment left on each unbalanced body at its last pose, and where the
    vertical balance is impossible (its own loads and its lines all push the
    same way, or it sank through the seabed), why."""
    poses, residual, mooring = (np.asarray(a, dtype=float) for a in (poses, residual, mooring))
    sunk = np.asarray(sunk_bodies(scene, poses))
    worst = np.max(np.abs(residual))
    parts = []
    for i, body in enumerate(scene.bodies):
        g, m = residual[i], mooring[i]
        if np.max(np.abs(g)) < 1e-3 * worst and not sunk[i]:
            continue
        own_z, lines_z = g[2] - m[2], m[2]
        kind = "point" if isinstance(body, ConnectionPoint) else "body"
        name = f"{kind} {body.label if body.label != kind else i + 1}"
        text = (f"{name}: force ({g[0]:.4g}, {g[1]:.4g}, {g[2]:.4g}) N (vertically "
                f"{own_z:.4g} N from its own loads, {lines_z:.4g} N from its lines) and moment "
                f"({g[3]:.4g}, {g[4]:.4g}, {g[5]:.4g}) N·m left at η = "
                f"({', '.join(f'{v:.4g}' for v in poses[i])})")
        if sunk[i]:
            ref = np.asarray(body.origin) + poses[i, :3]
            floor = float(scene.env.seabed_height(ref[0], ref[1]))
            text += (f"; it sank through the seabed (reference point at z = {ref[2]:.4g} m, the bed "
                     f"at {floor:.4g} m: bodies have no seabed contact)")
        tiny = 1e-9 * max(abs(own_z), abs(lines_z), 1.0)
        if own_z < 0 and lines_z <= tiny:
            text += (f"; nothing holds it up: its own loads (weight, buoyancy, hydrostatics, mean "
                     f"loads) pull it down by {-own_z:.4g} N and its lines by {-lines_z:.4g} N")
        elif own_z > 0 and lines_z >= -tiny:
            text += (f"; nothing holds it down: its own loads push it up by {own_z:.4g} N and its "
                     f"lines by {lines_z:.4g} N")
        parts.append(text)
    return "; ".join(parts)


def solve_system_statics(scene, t=0.0, *, loads: bool = True, init=None, tol: float = 1e-6,
                         max_iterations: int = MAX_ITERATIONS, throw: bool = True,
                         method: str = "fem") -> SystemStatics:
    """Equilibrium poses of the scene's bodies and the lines' static shapes.

    Args:
        scene: a scene with at least one body.
        t: time of the line ends that are not on bodies, and of loads without a
            ``mean_force`` [s].
        loads: include the bodies' mean external loads (else hydrostatics only).
        init: (n_bodies, 6) starting poses (default zero).
        tol: relative force tolerance, on the scale of the lines' tensions and
            the bodies' loads.
        max_iterations: Newton iterations allowed (:data:`MAX_ITERATIONS`).
        throw: raise ``RuntimeError`` when it does not converge.
        method: the lines' statics (see :func:`moorjax.statics.solve_line_statics`).
            ``"fem"`` (default): finite-element lines, the state dynamics start
            from. ``"auto"``: each line the exact catenary describes (at the
            starting poses) is one, the others FEM, so points and bodies settle
            where the continuous lines put them; where that fails (no
            convergence, a line end under the seabed: a point resting on the bed
            is carried by its FEM lines' contact) the system is solved with FEM
            lines. ``methods`` on the result says which each line got.
    """
    if not scene.bodies:
        raise ValueError("solve_system_statics needs a scene with bodies; use solve_statics")
    if method not in ("fem", "auto"):
        raise ValueError(f"method must be 'fem' or 'auto', got {method!r}")
    nb = len(scene.bodies)
    poses = jnp.zeros((nb, 6)) if init is None else jnp.asarray(init, float).reshape(nb, 6)
    for line in _attached(scene, poses):
        check_geometry(line, scene.env, t)  # names a line that cannot reach its ends
    fem = ("fem",) * len(scene.lines)
    if method == "auto":
        methods = tuple("catenary" if catenary_eligible(ln, scene.env)
                        and catenary_solves(ln, scene.env, t) else "fem"
                        for ln in _attached(scene, poses))
        if methods != fem:
            out = _system_newton(scene, poses, t, loads, tol, max_iterations, methods)
            if out.converged and _ends_above_bed(scene, out):
                _check_lines(scene, out, t)
                return out
    out = _system_newton(scene, poses, t, loads, tol, max_iterations, fem)
    _check_lines(scene, out, t)
    if throw and not out.converged:
        bad = [scene.lines[i].label for i, s in enumerate(out.lines) if not bool(s.converged)]
        why = (f"the static solve of line(s) {', '.join(bad)} failed (can they reach their "
               "anchors?)" if bad else
               f"force imbalance {np.max(np.abs(np.asarray(out.residual))):.3g} N after "
               f"{out.iterations} Newton iterations: "
               + imbalance_report(scene, out.poses, out.residual, out.mooring))
        raise RuntimeError(f"system statics did not converge: {why}")
    return out


def _check_lines(scene, out: SystemStatics, t) -> None:
    """The host-level checks of :func:`~moorjax.statics.solve_line_statics` for
    the FEM lines at the poses found: a Hermite line piled on the bed or whose
    touchdown its elements miss warns (their forces, and so the poses, are then
    unreliable although the iteration converged)."""
    from .hermite import check_lines

    methods = out.methods or ("fem",) * len(out.lines)
    statics = [st if m == "fem" else None for st, m in zip(out.lines, methods)]
    check_lines(_attached(scene, out.poses), scene.env, statics, t)


#: step halvings the system Newton tries before it gives up on an iteration: enough
#: for a regularised step of 1 m to come down to the 0.5 mm a seabed contact
#: (kBot·d·l ≈ 2e5 N/m) allows for a 100 N load
HALVINGS = 20


def admissible_rise(tol, scale, lines) -> Array:
    """How much larger [N] a trial pose's largest force imbalance may be than the
    last one's for the trial to be taken: the convergence tolerance tol × scale
    plus twice the largest force imbalance left inside the trial's lines (their
    end forces are known to about that). A point sliding where nothing holds it
    (a slack line, a frictionless slope) moves along an unchanged force, which
    the lines' statics give only to within their tolerance: MoorDyn's
    ``seafloor.txt`` pendulum (a weightless line of EA = 1e9 N, whose statics
    resolve 7e-3 N) near its equilibrium, 45.5356 N, trials 1e-6…1e-3 N more:
    with no rise allowed the compiled iteration stopped 0.3 m short, the host
    loop took 105 iterations."""
    resid = jnp.max(jnp.stack([jnp.max(x.max_residual) for x in lines]))
    return tol * scale + 2.0 * resid


#: a Jacobian whose largest entry is below this fraction of the largest force
#: imbalance (per metre or radian) counts as no stiffness at all (see newton_step)
NEGLIGIBLE_STIFFNESS = 1e-3


@jax.jit
def newton_step(jac, g):
    """The damped Newton step (n_bodies, 6) on the poses from the imbalance g
    (n_bodies, 6) and its Jacobian J = ∂g/∂η: −J⁻¹g; where J is singular or
    undefined (a point on slack weightless lines has no stiffness, and such a
    line's shape, hence its implicit derivative, is undetermined: condition
    number 1e12 or more, or a non-finite step), or negligible (its largest entry
    below :data:`NEGLIGIBLE_STIFFNESS` of |g|max per metre: well conditioned
    but nearly zero, as for a point resting exactly on the seabed at a slack
    line), a regularised step (μI − J)Δη = g with μ = |g|max per 5 m
    (translations) or per 0.05 rad (rotations), which moves along the net force
    by up to those where J = 0 and becomes Newton's step as g vanishes. Scaled
    to at most 5 m and 0.05 rad (the lines' statics must stay reachable from
    their last shapes). One traced function for the host loop here and the
    compiled one of :func:`moorjax.dynamics.initial.equilibrium_state`.

    MoorDyn's ``seafloor.txt`` pendulum (a point on the seabed slope at a slack
    line) under AMD EPYC rounding (session 24): with the condition test alone,
    |J| < 5e-4 N/m (condition 1.5e7) gave a 5 m step upwards and the loop stopped
    unconverged after 27 iterations; with the negligible-J test and μ per 1 m it
    slid 1 m per iteration down the slope (41 iterations), per 5 m 16. Judging
    the Newton step by its length instead (longer than 5 m: regularised) broke
    the statics of free points and bodies far from equilibrium, whose long
    Newton steps are right. A Newton step that does negative work against
    the net load (g·Δη ≤ 0: the stiffness −J is not positive along it) is
    regularised too: under AMD EPYC rounding again (session 42) the pendulum's
    first Newton step, from a slack line's undetermined shape, went 5 m up
    against the point's weight, and the loop stopped 0.55 m above the slope
    after 10 iterations, its trials within the slack line's force noise; with
    the test it slides down and converges in 29."""
    nb = g.shape[0]
    g = jnp.ravel(g)
    step = jnp.linalg.solve(jac, -g)
    limits = jnp.tile(jnp.array([5.0] * 3 + [0.05] * 3), nb)
    scale = jnp.maximum(jnp.max(jnp.abs(g)), 1e-300)
    stiff = jnp.max(jnp.where(jnp.isfinite(jac), jnp.abs(jac), 0.0)) >= NEGLIGIBLE_STIFFNESS * scale
    # a Newton step that does negative work against the net load (g·Δη ≤ 0)
    # climbs the energy: the stiffness −J is not positive along it (a slack
    # line's undetermined shape gives such Jacobians)
    downhill = jnp.vdot(g, step) > 0.0
    regular = jnp.all(jnp.isfinite(step)) & (jnp.linalg.cond(jac) < 1e12) & stiff & downhill
    mu = scale / limits
    relaxed = jnp.linalg.solve(jnp.diag(mu) - jnp.where(jnp.isfinite(jac), jac, 0.0), g)
    step = jnp.where(regular, step, relaxed).reshape(nb, 6)
    big = jnp.maximum(jnp.maximum(jnp.max(jnp.abs(step[:, :3])) / 5.0,
                                  jnp.max(jnp.abs(step[:, 3:])) / 0.05), 1.0)
    return jnp.where(jnp.isfinite(step), step / big, 0.0)


def _ends_above_bed(scene, out) -> bool:
    """Whether every catenary line's ends are on or above the seabed."""
    if scene.env.seabed is None:
        return True
    floor = -float(scene.env.depth) * (1.0 + 1e-6)
    return all(float(np.min(np.asarray(st.positions)[[0, -1], 2])) >= floor
               for st, m in zip(out.lines, out.methods) if m == "catenary")


def _system_newton(scene, poses, t, loads, tol, max_iterations, methods) -> SystemStatics:
    t = as_float(t)
    scale = None
    converged = False
    it = 0
    inits = tuple(s.warm_start() for s in line_statics_at(scene, poses, t, None, methods))
    stalls = 0
    for it in range(1, max_iterations + 1):
        g, jac = _newton_parts(scene, poses, t, bool(loads), inits, methods)
        g_np = np.asarray(g)
        if not np.all(np.isfinite(g_np)):
            break
        if scale is None:
            st = line_statics_at(scene, poses, t, inits, methods)
            tens = max(float(jnp.max(jnp.abs(s.tensions))) for s in st)
            scale = max(tens, float(np.max(np.abs(g_np))), 1.0)
        # moments are compared on the same scale times a unit lever arm
        if np.max(np.abs(g_np)) < tol * scale:
            converged = True
            break
        step = np.asarray(newton_step(jac, g))
        # backtracking: seabed contact makes the imbalance kinked, so a full
        # Newton step can overshoot and cycle
        size = np.max(np.abs(g_np))
        admissible = False
        for _ in range(HALVINGS):
            trial = poses + jnp.asarray(step)
            new = line_statics_at(scene, trial, t, inits, methods)
            if not all(bool(x.converged) for x in new):
                # a slack weightless line may not settle from its last shape but
                # does from the catenary guess
                cold = line_statics_at(scene, trial, t, None, methods)
                new = tuple(x if bool(x.converged) else c for x, c in zip(new, cold))
            ok = all(bool(x.converged) for x in new)
            if ok:
                ends = [(x.force_a, x.force_b) for x in new]
                w = jnp.stack(mooring_wrenches(scene.lines, scene.bodies, list(trial), ends))
                g_trial = np.asarray(body_forces(scene, trial, t, loads) + w)
                if np.max(np.abs(g_trial)) <= size + float(admissible_rise(tol, scale, new)):
                    admissible = True
                    break
            step = 0.5 * step
        if not admissible:  # no trial step was admissible: stop at the last good poses
            break
        stalls = stalls + 1 if bool(stalled(step, size, np.max(np.abs(g_trial)))) else 0
        poses = trial
        inits = tuple(x.warm_start() for x in new)
        if bool(jnp.any(sunk_bodies(scene, poses))) or stalls >= STALLS:  # no equilibrium reached
            break
    st = line_statics_at(scene, poses, t, inits, methods)
    wrench = mooring_wrench(scene, poses, t, inits, methods)
    residual = body_forces(scene, poses, t, loads) + wrench
    lines_ok = all(bool(s.converged) for s in st)
    return SystemStatics(poses, st, wrench, residual, it, bool(converged and lines_ok), methods)


def mooring_stiffness(scene, poses=None, t=0.0) -> Array:
    """Linearised mooring stiffness K = −∂F_moor/∂η, (6·n_bodies, 6·n_bodies).

    Exact (forward-mode AD through the lines' static solves); rows and columns
    ordered body by body as (surge, sway, heave, roll, pitch, yaw).
    """
    nb = len(scene.bodies)
    poses = jnp.zeros((nb, 6)) if poses is None else jnp.asarray(poses, float).reshape(nb, 6)
    jac = jax.jacfwd(lambda p: mooring_wrench(scene, p.reshape(nb, 6), t).ravel())(poses.ravel())
    return -jac


def system_stiffness(scene, poses=None, t=0.0) -> Array:
    """Hydrostatic plus mooring stiffness (6·n_bodies square) [N/m, N, N·m/rad]."""
    k = mooring_stiffness(scene, poses, t)
    hs = jax.scipy.linalg.block_diag(*[b.hydrostatic for b in scene.bodies])
    return k + hs


def offset_curve(scene, offsets, dof: int = 0, body: int = 0, t=0.0) -> Array:
    """Restoring force of the lines −F_moor[dof] (k,) at prescribed offsets (k,) of one dof.

    The other degrees of freedom stay at zero (the paper's static offset test).
    Returned relative to the force at zero offset, so it is the restoring force
    the moorings add [N or N·m]. The offsets are visited from zero outwards, each
    line's static solve starting from its solution at the previous offset
    (continuation); a line whose solve fails raises ``RuntimeError`` naming it.
    """
    nb = len(scene.bodies)
    offsets = np.asarray(offsets, dtype=float)

    def solve(x, inits):
        p = jnp.zeros((nb, 6)).at[body, dof].set(x)
        st = line_statics_at(scene, p, t, inits)
        bad = [scene.lines[i].label for i, s in enumerate(st) if not bool(s.converged)]
        if bad:
            raise RuntimeError(f"offset curve: static solve of line(s) {', '.join(bad)} failed at "
                               f"offset {x:g} of dof {dof}")
        ends = [(s.force_a, s.force_b) for s in st]
        f = -jnp.stack(mooring_wrenches(scene.lines, scene.bodies, list(p), ends))[body, dof]
        return float(f), tuple(s.warm_start() for s in st)

    f0, base = solve(0.0, None)
    out = np.empty(offsets.shape)
    for sign in (1.0, -1.0):
        idx = [i for i in np.argsort(np.abs(offsets)) if np.sign(offsets[i]) in (sign, 0.0)]
        inits, last = base, 0.0
        for i in idx:
            x = offsets[i]
            # small continuation steps (at most 0.25 m or 0.01 rad) between samples
            n_sub = int(np.ceil(abs(x - last) / (0.25 if dof < 3 else 0.01)))
            for k in range(1, n_sub):
                _, inits = solve(last + (x - last) * k / n_sub, inits)
            out[i], inits = solve(x, inits)
            out[i] -= f0
            last = x
    return jnp.asarray(out)


__all__ = ["SystemStatics", "LineStatics", "solve_system_statics", "mooring_stiffness",
           "system_stiffness", "offset_curve", "mooring_wrench", "body_forces"]
