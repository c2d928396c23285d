"""Energy balance of the undamped line: no drag, no internal damping, no seabed,
no current, no added mass, both ends fixed. The model is then a conservative
mechanical system and its total energy

    E = ½ vᵀM v  +  Σ_j ½·EA·l·ε_j²  +  Σ_k w·l_k·z_k

(kinetic; elastic, for taut segments of the tension-only law; potential of the wet
weight w = (m − ρA)g carried by each node's length l_k) must stay constant.

Added mass is left out on purpose: the model's added-mass tensor follows the
segment tangent, so M depends on the configuration and M(r)·a = f does not
conserve ½vᵀM(r)v exactly (a missing ½vᵀṀv term; Morison added mass is not
Lagrangian). With m alone, M is constant.

The line is plucked into its first transverse mode shape and run for 100
fundamental periods at tight tolerances. The state (positions *and* velocities)
is read from ``SimulationResult.final_state`` at the end of consecutive chunks;
the chunks restart at t0 = 0 (the ends are fixed, the system is autonomous), so
every chunk reuses one compilation.

Solvers: the default Kvaerno5 (implicit, L-stable: its numerical dissipation is
what the drift measures; at rtol = atol = 1e-10 it stays ~20× under the limit)
and the explicit Dopri8 (cheap on this small, non-stiff line), which also runs
the consistent mass: see :func:`test_consistent_mass_with_default_newton` for
why Kvaerno5 does not.
"""

from __future__ import annotations

import functools

import jax.numpy as jnp
import numpy as np
import pytest

import moorjax as mj
from moorjax.dynamics import simulate
from moorjax.element import ConsistentMass, LinearElement, NodalMass
from moorjax.statics import solve_line_statics

RHO, G = 1025.0, 9.80665
D, M, EA = 0.05, 5.0, 1.0e5  # [m], [kg/m], [N]; wet weight 29.3 N/m
L0, SPAN, N = 10.0, 10.5, 8  # strain 5 %: pretension ≈ 5 kN, sag 0.08 m, taut everywhere
END_A = np.array([0.0, 0.0, -50.0])
END_B = END_A + np.array([SPAN, 0.0, 0.0])
AMP = 0.1  # [m] pluck amplitude, in y and z (so gravity's potential takes part)
PLUCK = np.array([0.0, 1.0, 1.0]) / np.sqrt(2.0)
N_PERIODS = 100
N_CHUNKS = 16  # 6.25 periods each: samples fall at four phases of the cycle


def scene_with(mass, damping=0.0):
    lt = mj.LineType(D, M, EA, damping)  # drag=None, added_mass=None
    env = mj.Environment(100.0, RHO, G)  # seabed=None, current=None
    line = mj.Line(lt, L0, N, mj.FixedEnd(END_A), mj.FixedEnd(END_B),
                   element=LinearElement(mass=mass))
    return mj.Scene([line], env)


def energies(mass, r, v):
    """(kinetic, elastic, gravitational) energy [J] of free nodes r, v (n−1, 3)."""
    l = L0 / N
    w = (M - RHO * np.pi * D**2 / 4) * G
    nodes = np.vstack([END_A, r, END_B])
    strain = np.linalg.norm(np.diff(nodes, axis=0), axis=1) / l - 1
    assert np.all(strain > 0), "a segment went slack: the elastic energy below is invalid"
    elastic = 0.5 * EA * l * np.sum(strain**2)
    gravity = w * l * np.sum(r[:, 2])  # end nodes are fixed: constant terms dropped
    vel = np.vstack([np.zeros(3), v, np.zeros(3)])
    if isinstance(mass, NodalMass):  # node mass m·(l/2 + l/2)
        kinetic = 0.5 * M * l * np.sum(v**2)
    else:  # element mass (m·l/6)·[[2, 1], [1, 2]] on each segment's two nodes
        va, vb = vel[:-1], vel[1:]
        kinetic = M * l / 6 * np.sum(va * va + va * vb + vb * vb)
    return kinetic, elastic, gravity


@functools.lru_cache(maxsize=None)
def static_state():
    """Free-node static positions (n−1, 3) and the end tension [N] (one solve:
    statics does not depend on the mass treatment or on damping)."""
    scene = scene_with(NodalMass())
    st = solve_line_statics(scene.lines[0], scene.env)
    return np.asarray(st.positions[1:-1]), float(st.tension_b)


def plucked():
    r_static, tension = static_state()
    s = np.arange(1, N)[:, None] / N
    r0 = r_static + AMP * np.sin(np.pi * s) * PLUCK
    state = (mj.LineState(r=jnp.asarray(r0), v=jnp.zeros((N - 1, 3))),)
    period = 2 * SPAN * np.sqrt(M / tension)  # taut-string estimate, 0.66 s
    return r_static, r0, state, period


def run(mass, solver, tol, damping=0.0):
    """Energies at the end of each chunk, the static energy and the initial one."""
    scene = scene_with(mass, damping)
    r_static, r0, state, period = plucked()
    e_static = sum(energies(mass, r_static, 0 * r_static))
    e0 = sum(energies(mass, r0, 0 * r0))
    chunk = N_PERIODS * period / N_CHUNKS
    parts = []
    for _ in range(N_CHUNKS):
        res = simulate(scene, chunk, dt_out=chunk, init=state, solver=solver, rtol=tol,
                       atol=tol, atol_velocity=tol)
        state = res.final_state
        parts.append(energies(mass, np.asarray(state[0].r), np.asarray(state[0].v)))
    return np.array(parts), e_static, e0


@pytest.mark.parametrize(
    "mass, solver, tol",
    [(NodalMass(), "kvaerno5", 1e-10), (NodalMass(), "dopri8", 1e-10),
     (ConsistentMass(), "dopri8", 1e-10)],
    ids=["nodal-kvaerno5", "nodal-dopri8", "consistent-dopri8"],
)
@pytest.mark.slow
def test_energy_is_conserved_without_dissipation(mass, solver, tol):
    """|E(t) − E(0)| < 1e-6 of the vibration energy over 100 periods.

    Scale: E's absolute level is arbitrary (gravity's datum) and dominated by the
    pretension's strain energy (1257 J), which never changes; what the motion
    moves back and forth between kinetic, elastic and gravitational forms is the
    vibration energy E(0) − E_static (11.6 J, of which gravity's share is 13.0 J
    and the elastic one −1.4 J: the weight term matters). Relative to it the
    check is ~100× stricter than relative to the total. Measured drift: 5.2e-8
    (nodal, Kvaerno5: numerical dissipation, growing linearly in time), 1.0e-9
    (nodal, Dopri8), 4.9e-10 (consistent, Dopri8).
    """
    parts, e_static, e0 = run(mass, solver, tol)
    e_vib = e0 - e_static
    assert e_vib > 1.0
    total = parts.sum(axis=1)
    drift = np.max(np.abs(total - e0)) / e_vib
    assert drift < 1e-6, drift
    # the check is not vacuous: energy really moves between its forms
    kinetic = parts[:, 0]
    assert np.max(kinetic) > 0.5 * e_vib
    assert np.ptp(parts[:, 1] + parts[:, 2]) > 0.5 * e_vib


def test_energy_check_detects_internal_damping():
    """The same run with a small internal damping BA = 1 N·s (ζ ≈ 6e-4 of a
    segment's axial critical damping) loses energy far beyond the tolerance above
    (measured 3.4e-4 of the vibration energy) — so a dissipative force slipping
    into the undamped model would fail it.
    """
    parts, e_static, e0 = run(NodalMass(), "dopri8", 1e-10, damping=1.0)
    loss = (e0 - parts.sum(axis=1)) / (e0 - e_static)
    assert np.all(np.diff(loss) > 0)  # monotone: dissipation
    assert loss[-1] > 1e-4, loss[-1]


def test_consistent_mass_with_default_newton():
    """Kvaerno5 on the consistent-mass line, 1 s at 1e-7: a dense Newton needs 287
    steps (33 rejected); the default (which switches to the dense Newton for a
    consistent mass, whose Jacobian M⁻¹K is dense) must not need 10× that."""
    scene = scene_with(ConsistentMass())
    _, _, state, _ = plucked()
    res = simulate(scene, 1.0, dt_out=1.0, init=state, rtol=1e-7, atol=1e-7,
                   atol_velocity=1e-7, max_steps=3000, throw=False)
    assert bool(res.succeeded())
    assert int(res.num_steps) < 3000
