"""The differentiable forward model of an identification: end-tension histories.

``tension_histories(scene, sim)`` is a pure function of the scene's arrays: it
takes the static equilibrium at t0 (implicit-function gradients,
:func:`~moorjax.dynamics.initial.equilibrium_state`), integrates the dynamics
(:func:`~moorjax.dynamics.integrate.integrate`) and returns the end tensions at
the output times. Every array leaf of the scene (axial law constants, damping,
drag and added-mass coefficients, length, mass, diameter, end positions and
motions, current, seabed) is reachable by ``jax.grad``.

How derivatives pass through the integration (adjoints, checkpoints, the
structured implicit-function solves) and why fixed, guarded steps are the
default: see :mod:`moorjax.dynamics.adjoint`.
"""

from __future__ import annotations

import equinox as eqx
import jax
import numpy as np

from ..dynamics.adjoint import ADJOINTS as ADJOINTS
from ..dynamics.adjoint import CHECKPOINT_BYTES as CHECKPOINT_BYTES
from ..dynamics.adjoint import banded as banded
from ..dynamics.adjoint import check_adjoint
from ..dynamics.adjoint import structured_implicit_gradients as structured_implicit_gradients
from ..dynamics.initial import equilibrium_state
from ..dynamics.integrate import integrate
from ..dynamics.settings import Settings, plan
from ..dynamics.vector_field import pack

#: the settings of an identification's simulations (built by :func:`simulation`)
Simulation = Settings


def simulation(ts, *, dt=0.01, solver="kvaerno3", rtol=1e-6, atol=1e-6, t0=0.0,
               adjoint="checkpointed", max_steps=None) -> Settings:
    """Settings of the simulations of an identification (scene-independent).

    Args:
        ts: output times [s] (> t0, increasing): the times of the measurements.
        dt: step [s] (default 0.01 s), or ``None`` for error-controlled adaptive
            steps (whose gradients hold the step sequence frozen, see
            :mod:`moorjax.dynamics.adjoint`). With ``dt`` the integration takes
            fixed steps of ``dt``; only a step whose implicit (Newton) solve fails
            — a node touching the seabed, a snap load, which the very-chord Newton
            with the Jacobian frozen at the step start cannot follow at that step
            — is retried with a quarter of it, and the steps then grow back to
            ``dt``. Where no step fails (the usual case) the steps are exactly fixed.
        solver: a solver name (default ``"kvaerno3"``: L-stable, cheap stages).
        rtol, atol: Newton tolerances of the implicit stages (relative, and
            absolute [m]); with ``dt=None`` also the error control. Keep ≈ 1e-6.
        t0: start time [s] (the static equilibrium is taken there).
        adjoint: ``"checkpointed"`` (reverse mode, default) or ``"forward"``.
        max_steps: step limit (default: twice the fixed-step count + 100, or 100 000).
    """
    check_adjoint(adjoint)
    ts = np.asarray(ts, dtype=float)
    if ts.ndim != 1 or ts.size < 1:
        raise ValueError("output times ts must be a non-empty 1-D array [s]")
    common = dict(ts=ts, t0=t0, solver=solver, rtol=rtol, atol=atol, adjoint=adjoint)
    if dt is None:
        max_steps = 100_000 if max_steps is None else int(max_steps)
        return plan(max_steps=max_steps, **common)
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt = {dt} s must be > 0")
    n_fixed = int(np.ceil(float(ts[-1] - t0) / float(dt) - 1e-9))
    max_steps = 2 * n_fixed + 100 if max_steps is None else int(max_steps)
    # one checkpoint per possible step (when they fit in CHECKPOINT_BYTES)
    return plan(dt=dt, max_steps=max_steps, checkpoints=max_steps, retry_failed_steps=True,
                **common)


def initial_states(scene, t0=0.0):
    """Static equilibrium at t0 (differentiable), and whether it converged."""
    eq = equilibrium_state(scene, t0)
    return eq.state, eq.converged


class Histories(eqx.Module):
    """End tensions (k, n_lines) [N] at the output times and a success flag."""

    tension_a: jax.Array
    tension_b: jax.Array
    ok: jax.Array


def tension_histories(scene, sim: Settings) -> Histories:
    """Simulate ``scene`` from its static equilibrium at ``sim``'s t0; pure and differentiable.

    Never raises on a failed solve: ``ok`` is False and the tensions after the
    failure are not finite (diffrax fills them with inf).
    """
    eq = equilibrium_state(scene, sim.t0)
    res = integrate(scene, pack(eq.state), sim, keep_final=False)
    return Histories(res.tension_a, res.tension_b, eq.converged & res.succeeded())
