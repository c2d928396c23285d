"""The initial state of a run: the static equilibrium at t0, for lines and bodies.

:func:`equilibrium_state` is the one place a run's default start is built, for
``simulate``, ensembles and identification alike. It is a pure function of the
scene's arrays (jittable, vmappable, differentiable through the statics'
implicit-function gradients):

- without bodies, each line's static solve with its ends where they are at t0;
- with bodies (rigid bodies, free connection points), the poses η that balance
  each body's mean load (:meth:`~moorjax.body.base.AbstractBody.mean_load`) and
  the lines' static wrench, by the damped, backtracking Newton iteration of
  :func:`moorjax.statics.solve_system_statics` written with ``lax`` loops (so
  an ensemble of body scenes solves its statics in one vmapped call), then each
  body at rest at its pose.

It never raises on non-convergence: ``converged`` says whether it did (and the
state is where the iteration stopped).
"""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array

from .._cache import StoredProgram
from .._numerics import as_float
from ..body.coupling import attach, mooring_wrenches
from ..statics import fem
from ..statics.fem import _solve_core, element_core, solve_line_statics
from ..statics.system import (HALVINGS, MAX_ITERATIONS, admissible_rise, body_forces, line_starts,
                              STALLS, imbalance_report, line_statics_at, mooring_wrench,
                              newton_step, stalled, sunk_bodies)


class Equilibrium(eqx.Module):
    """A static equilibrium as a start.

    Attributes:
        state: the line states (:class:`~moorjax.model.line.LineState`), then each
            body's 1-D state at rest at its pose — ``simulate``'s ``init``.
        lines_converged: (n_lines,) whether each line's static solve converged.
        converged: whether every line's solve and (with bodies) the bodies'
            force balance converged.
        poses: (n_bodies, 6) body poses η [m, rad] (``None`` without bodies).
        imbalance, mooring: (n_bodies, 6) force and moment left on each body, and
            the lines' part of it, at ``poses`` [N, N·m] (``None`` without bodies).
        statics: per line the ``LineStatics`` of the line's own static solve
            where its state comes from one, else ``None``. Without bodies every
            line's; with bodies those of the lines of other elements than the
            linear one, solved again at ``poses`` (the others' states come from
            the bodies' iteration). :func:`equilibrium_state` checks these
            lines' touchdown resolution as
            :func:`~moorjax.statics.fem.solve_line_statics` does; ensembles
            check them batched (:func:`resolution_offsets`).
    """

    state: tuple
    lines_converged: Array
    converged: Array
    poses: Array | None = None
    imbalance: Array | None = None
    mooring: Array | None = None
    statics: tuple | None = None


def check_geometry(scene, t0=0.0):
    """Refuse impossible geometry before anything runs: ``ValueError`` naming the
    line whose end is below the seabed or that cannot reach its ends (bodies at
    η = 0). Skipped for traced values."""
    for line in lines_at_rest(scene):
        fem.check_geometry(line, scene.env, t0)


def lines_at_rest(scene):
    """The scene's lines with their fairleads where the bodies are at η = 0, at rest."""
    if not scene.bodies:
        return scene.lines
    return _attached_at_rest(scene.lines, scene.bodies)


@eqx.filter_jit
def _attached_at_rest(lines, bodies):
    """(one small program, not an eager XLA operation per array operation)"""
    zero = [jnp.zeros(6)] * len(bodies)
    return attach(lines, bodies, zero, zero)


def start_layout(scene) -> tuple:
    """The layout of a start's packed solver state (see
    :func:`~moorjax.dynamics.vector_field.pack`) as ``jax.ShapeDtypeStruct``s,
    without solving anything: each line's (rows, 6) array, then each body's
    state at rest."""
    dtype = jax.dtypes.canonicalize_dtype(float)
    lines = tuple(jax.ShapeDtypeStruct((line.element.state_rows(line), 6), dtype)
                  for line in scene.lines)
    return lines + tuple(jax.eval_shape(body.rest_state) for body in scene.bodies)


def equilibrium_state(scene, t0=0.0, *, loads: bool = True, tol: float = 1e-6,
                      max_iterations: int = MAX_ITERATIONS) -> Equilibrium:
    """The static equilibrium of ``scene`` at ``t0`` as a start (see the module notes).

    Args:
        loads: with bodies, include their mean external loads (mean wind,
            current, wave drift); else hydrostatics and weights only.
        tol, max_iterations: the bodies' Newton iteration (relative force
            tolerance on the scale of the lines' tensions; iteration limit, as
            :func:`moorjax.statics.solve_system_statics`'s).
    """
    if not scene.bodies:
        sts = [solve_line_statics(line, scene.env, t0, throw=False) for line in scene.lines]
        return _lines_equilibrium(tuple(sts))
    check_geometry(scene, t0)
    eq = _body_equilibrium(scene, as_float(t0), bool(loads), float(tol), int(max_iterations))
    _check_resolution_at_poses(scene, eq, t0)
    return eq


def _check_resolution_at_poses(scene, eq: Equilibrium, t0):
    """:func:`~moorjax.statics.hermite.check_resolution` (what
    :func:`~moorjax.statics.fem.solve_line_statics` runs outside ``jit``) for
    the lines a body scene's start solved at the poses found: a grounded line
    of equal Hermite elements whose touchdown they do not follow warns here as
    it does without bodies. Nothing under ``jit``/``vmap`` (ensembles)."""
    from .._checks import _concrete
    from ..statics.hermite import check_lines
    from ..statics.system import _attached

    if eq.statics is None or all(st is None for st in eq.statics) or _concrete(eq.poses) is None:
        return
    check_lines(_attached(scene, eq.poses), scene.env, eq.statics, t0)


def resolution_offsets(scene, eq: Equilibrium, t0=0.0):
    """Traceable touchdown check of a start's Hermite lines: (n_lines, 2)
    relative end-tension differences (ends A, B) from the linear element at
    :data:`~moorjax.statics.hermite.FINE_SEGMENTS` segments per element
    (:func:`moorjax.statics.hermite.resolution_offsets`), NaN where it does not
    apply; ``None`` where no line of the scene is checked (by structure:
    :func:`~moorjax.statics.hermite.resolution_checked`). What
    :func:`equilibrium_state` checks on values, for ``vmap``: ensembles warn
    with it, naming the members."""
    from ..statics.hermite import resolution_checked
    from ..statics.hermite import resolution_offsets as offsets
    from ..statics.system import _attached

    lines = scene.lines if eq.poses is None else _attached(scene, eq.poses)
    sts = eq.statics if eq.statics is not None else (None,) * len(lines)
    checked = [st is not None and resolution_checked(line, scene.env) for line, st in zip(lines, sts)]
    if not any(checked):
        return None
    return jnp.stack([offsets(line, scene.env, st, t0)[0] if c else jnp.full(2, jnp.nan)
                      for line, st, c in zip(lines, sts, checked)])


@eqx.filter_jit
def _lines_equilibrium(sts) -> Equilibrium:
    """The lines' static solves as one start (one small program, not one eager
    XLA operation per slice and stack)."""
    ok = jnp.stack([st.converged for st in sts])
    return Equilibrium(tuple(st.state() for st in sts), ok, jnp.all(ok), statics=sts)


def catenary_state(scene, t0=0.0) -> Equilibrium:
    """MoorDyn's "catenary solver alone" start (its ``TmaxIC = 0``): each line's
    own static shape with its ends where the scene puts them at t0 — free points
    and bodies held at η = 0, where the deck places them — everything at rest.

    MoorDyn's ``docs/initialization.rst``: the catenary solver is always applied
    first, and a line it cannot solve starts as a straight line; with
    ``TmaxIC = 0`` nothing else runs. Here each line's discrete static solve
    (:func:`~moorjax.statics.fem.solve_line_statics`) plays the catenary's part
    and a line whose solve does not converge starts straight between its ends
    (``lines_converged`` says which). The points and bodies are not balanced: the
    run starts out of equilibrium wherever the deck's positions are, as MoorDyn's
    does. ``converged`` is ``lines_converged.all()``.
    """
    check_geometry(scene, t0)
    states, oks = [], []
    for line in lines_at_rest(scene):
        st = solve_line_statics(line, scene.env, t0, throw=False)
        state, straight, ok = st.state(), line.straight_state(t0), st.converged
        if jax.tree_util.tree_structure(state) == jax.tree_util.tree_structure(straight):
            state = jax.tree_util.tree_map(lambda a, b: jnp.where(ok, a, b), state, straight)
        states.append(state)  # (a Hermite line keeps where its solve stopped)
        oks.append(ok)
    ok = jnp.stack(oks)
    bodies = tuple(b.rest_state() for b in scene.bodies)
    return Equilibrium(tuple(states) + bodies, ok, jnp.all(ok),
                       jnp.zeros((len(scene.bodies), 6)) if scene.bodies else None)


def _states(sts):
    return tuple(s.state() for s in sts)


def _stop_gradient(tree):
    diff, static = eqx.partition(tree, eqx.is_inexact_array)
    return eqx.combine(jax.lax.stop_gradient(diff), static)


# eqx.filter_jit, its program also stored on disk (moorjax._cache) and compiled
# for one run per structure (moorjax._xla_flags.PRESETS), as the line statics
@functools.partial(StoredProgram, compile_for="once")
def _body_equilibrium(scene_d, t, loads, tol, max_iterations):
    """The Newton iteration on constants (``lax`` loops are not reverse-
    differentiable); the poses' derivatives come from the implicit function
    theorem at the solution (see the end)."""
    # ``states``: each line's warm start at the poses (a linear line's state; a
    # Hermite line's static unknowns, replaced below by its state)
    poses, states, lines_ok, converged, jac, g, wrench = _body_newton(
        _stop_gradient(scene_d), jax.lax.stop_gradient(t), loads, tol, max_iterations)
    # the imbalance, the lines' wrench and states at the poses come from the
    # iteration; the poses' and the states' derivatives from the implicit
    # function theorem, traced only where a derivative is taken (_implicit_poses,
    # _implicit_states): the program holds one copy of the lines' statics, the
    # iteration's (a second solve at the poses found was 3.5 s of tracing and a
    # second compiled copy in a body scene's start)
    poses = _implicit_poses(poses, jac, scene_d, t, loads, states)
    # lines of other elements (Hermite) are solved again at the poses, as before:
    # their warm start compares the state with the catenary guess, and on a point
    # scene of 2-element Hermite lines the re-solve left the iteration's root for
    # a better one (tests/test_hermite_bodies.py's gradient scene)
    again = tuple(i for i, ln in enumerate(scene_d.lines) if element_core(ln) is not _solve_core)
    statics = None
    if again:
        sub = eqx.tree_at(lambda s: s.lines, scene_d, tuple(scene_d.lines[i] for i in again))
        solved_again = dict(zip(again, line_statics_at(sub, poses, t, tuple(states[i] for i in again))))
        statics = tuple(solved_again.get(i) for i in range(len(states)))
        states = tuple(st.state() if st is not None else s_i for st, s_i in zip(statics, states))
        lines_ok = lines_ok.at[jnp.array(again)].set(jnp.stack([solved_again[i].converged for i in again]))
    keep = tuple(i for i in range(len(states)) if i not in again)
    if keep:
        solved = _implicit_states(tuple(states[i] for i in keep), scene_d, poses, t, keep)
        states = tuple(solved[keep.index(i)] if i in keep else s_i for i, s_i in enumerate(states))
    state = states + tuple(b.rest_state(p) for b, p in zip(scene_d.bodies, poses))
    return Equilibrium(state, lines_ok, converged & jnp.all(lines_ok), poses,
                       jax.lax.stop_gradient(g), jax.lax.stop_gradient(wrench), statics)


@eqx.filter_custom_jvp
def _implicit_states(states, scene, poses, t, which):
    """``states``, the static states of the lines ``which`` (indices) with their
    fairleads where ``poses`` put them (the iteration's solve), with the
    derivative of the lines' statics attached (their implicit-function
    derivative, through the poses' too): the rule solves the lines again from
    ``states``, only under differentiation."""
    return states


@_implicit_states.def_jvp
def _implicit_states_jvp(primals, tangents):
    states, scene, poses, t, which = primals
    _, t_scene, t_poses, t_t, _ = tangents

    def solved(sc, p, tt):
        sub = eqx.tree_at(lambda s: s.lines, sc, tuple(sc.lines[i] for i in which))
        return _states(line_statics_at(sub, p, tt, states))

    _, dot = eqx.filter_jvp(solved, (scene, poses, t), (t_scene, t_poses, t_t))
    return states, dot


@eqx.filter_custom_jvp
def _implicit_poses(poses, jac, scene, t, loads, inits):
    """``poses``, the bodies' equilibrium G(η, θ) = 0 of ``scene`` (θ: its
    arrays, and t), with the derivative dη/dθ = −J⁻¹ ∂G/∂θ·θ̇ attached (J = ``jac``,
    the iteration's last Jacobian, at the solution; its own derivative does not
    enter since G = 0). The rule evaluates the lines' wrench only under
    differentiation: a run's start program holds no copy of the lines' statics
    for it (compiled without XLA's passes, every copy is compiled)."""
    return poses


@_implicit_poses.def_jvp
def _implicit_poses_jvp(primals, tangents):
    poses, jac, scene, t, loads, inits = primals
    _, _, t_scene, t_t, _, _ = tangents

    def imbalance(sc, tt):
        return body_forces(sc, poses, tt, loads) + mooring_wrench(sc, poses, tt, inits)

    _, g_dot = eqx.filter_jvp(imbalance, (scene, t), (t_scene, t_t))
    # linear in the tangent (reverse mode transposes it): J⁻¹ formed from the
    # primal, its non-finite entries (a singular J) zeroed
    inv = jnp.linalg.solve(jac, jnp.eye(jac.shape[0]))
    inv = jnp.where(jnp.isfinite(inv), inv, 0.0)
    return poses, -(inv @ g_dot.ravel()).reshape(poses.shape)


def _body_newton(scene, t, loads, tol, max_iterations):
    """Damped, backtracking Newton on the bodies' force balance (the steps of
    :func:`moorjax.statics.system.newton_step`, the acceptance and halvings of
    :func:`~moorjax.statics.system.solve_system_statics`' host loop), as one loop whose
    body solves the lines' statics once (warm, linearised for the Jacobian) at a
    trial pose: accepted trials become the base of the next Newton step, rejected
    ones halve the step. One traced copy of the warm line statics keeps the
    compile small (XLA inlines every copy). Returns (poses, the lines' warm
    starts there (``LineStatics.warm_start``) and whether each line's solve
    converged there, converged, Jacobian at the poses, and the imbalance and
    the lines' wrench there)."""
    nb = len(scene.bodies)
    n_dof = 6 * nb
    eye = jnp.eye(n_dof).reshape((n_dof,) + (nb, 6))

    def evaluate(poses, inits):
        def imbalance(p):
            st = line_statics_at(scene, p, t, inits)
            ends = [(s.force_a, s.force_b) for s in st]
            w = jnp.stack(mooring_wrenches(scene.lines, scene.bodies, list(p), ends))
            return body_forces(scene, p, t, loads) + w, (st, w)

        g, jvp_fn, (st, w) = jax.linearize(imbalance, poses, has_aux=True)
        jac = jax.vmap(jvp_fn)(eye).reshape(n_dof, n_dof).T
        ok = jnp.all(jnp.stack([s.converged for s in st]))
        tens = jnp.max(jnp.stack([jnp.max(jnp.abs(s.tensions)) for s in st]))
        return g, jac, tuple(s.warm_start() for s in st), ok, tens, st, w

    poses0 = jnp.zeros((nb, 6))
    inits0 = line_starts(scene, poses0, t)  # the first trial solves from here

    def iteration(c):
        (k, newton_its, trial, base, inits, size, jac, step, scale, _, _, stalls, g_base,
         w_base, lines_ok) = c
        g, jac_t, states, ok, tens, sts, w = evaluate(trial, inits)
        finite = jnp.all(jnp.isfinite(g))  # (a non-finite J gets newton_step's regularised step)
        size_t = jnp.max(jnp.abs(g))
        first = newton_its == 0
        # backtracking: seabed contact makes the imbalance kinked, so a full
        # Newton step can overshoot and cycle; a trial is taken when its lines
        # converged and its largest force is not larger (by more than
        # admissible_rise: as the host loop)
        scale = jnp.where(first, jnp.maximum(jnp.maximum(tens, size_t), 1.0), scale)
        accept = ok & finite & (first | (size_t <= size + admissible_rise(tol, scale, sts)))
        stalls = jnp.where(accept, jnp.where(~first & stalled(trial - base, size, size_t),
                                             stalls + 1, 0), stalls)
        base = jnp.where(accept, trial, base)
        keep = accept | first  # (the first trial is the base, accepted or not)
        # the lines' states and flags at the base (a first trial that is not
        # accepted ends the loop: its states, converged or not, are the answer)
        inits = jax.tree_util.tree_map(lambda a, b: jnp.where(keep, a, b), states, inits)
        lines_ok = jnp.where(keep, jnp.stack([s.converged for s in sts]), lines_ok)
        size = jnp.where(accept, size_t, size)
        jac = jnp.where(accept, jac_t, jac)
        g_base, w_base = jnp.where(keep, g, g_base), jnp.where(keep, w, w_base)
        converged = accept & (size_t < tol * scale)
        step = jnp.where(accept, newton_step(jac, jnp.where(finite, g, 0.0)), 0.5 * step)
        k = jnp.where(accept, 0, k + 1)
        # a body that sank through the seabed has no equilibrium (no body contact)
        gave_up = ((k >= HALVINGS) | (first & ~accept) | jnp.any(sunk_bodies(scene, base))
                   | (stalls >= STALLS))
        newton_its = newton_its + accept
        return (k, newton_its, base + step, base, inits, size, jac, step, scale,
                converged | gave_up, converged, stalls, g_base, w_base, lines_ok)

    zero = jnp.zeros((nb, 6))
    c0 = (0, 0, poses0, poses0, inits0, jnp.inf, jnp.eye(n_dof), zero, 1.0,
          jnp.asarray(False), jnp.asarray(False), 0, jnp.full((nb, 6), jnp.nan),
          jnp.full((nb, 6), jnp.nan), jnp.zeros(len(scene.lines), bool))
    c = lax.while_loop(lambda c: (c[1] <= max_iterations) & ~c[9], iteration, c0)
    _, _, _, poses, inits, _, jac, _, _, _, converged, _, g, w, lines_ok = c
    return poses, inits, lines_ok, converged, jac, g, w


def failed_lines(scene, eq: Equilibrium) -> list[str]:
    """Labels of the lines whose static solve did not converge (concrete ``eq``)."""
    return [scene.lines[i].label for i, ok in enumerate(np.asarray(eq.lines_converged)) if not ok]


def not_converged_message(scene, eq: Equilibrium) -> str:
    """Why an equilibrium (concrete) is no start, naming the lines that failed."""
    bad = failed_lines(scene, eq)
    if bad:
        return (f"the static solve of line(s) {', '.join(bad)} did not converge (Newton failed "
                "or left a force imbalance); check the geometry (can the line reach its ends?), "
                "or give `init`")
    why = ("" if eq.imbalance is None else
           ": " + imbalance_report(scene, eq.poses, eq.imbalance, eq.mooring))
    return ("the bodies' static equilibrium did not converge (force imbalance left after the "
            f"Newton iterations{why}); check the bodies' loads and lines, give `init`, or start as "
            "MoorDyn does with TmaxIC = 0, from each line's own static shape with the points and "
            "bodies where the scene puts them: init='catenary' (command line: --initial catenary)")


def initial_state(scene, t0=0.0) -> tuple:
    """The static equilibrium at t0 as ``simulate``'s ``init``: line states, then each
    body at rest at its equilibrium pose (mean loads included). Raises
    ``RuntimeError`` when it does not converge (concrete scenes)."""
    eq = equilibrium_state(scene, t0)
    if not isinstance(eq.converged, jax.core.Tracer) and not bool(eq.converged):
        raise RuntimeError(f"static equilibrium at t0 = {float(t0):g} s: "
                           + not_converged_message(scene, eq))
    return eq.state
