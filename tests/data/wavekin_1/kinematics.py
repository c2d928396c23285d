"""External wave kinematics for the ``WaveKin = 1`` tests (moorjax's
``ExternalWaves`` and, through ``make_moordyn_reference.py --kinematics``,
MoorDyn's ``ExternalWaveKinSet``). Written with ``jax.numpy`` so that both can
evaluate them; r (..., 3) [m], t [s] -> (u, a) (..., 3) [m/s, m/s²].
"""

import math

import jax.numpy as jnp


def current(r, t):
    """MoorDyn's ``tests/wavekin.cpp`` callback ``current``: 1 m/s along +x everywhere."""
    del t
    u = jnp.zeros(jnp.shape(r)).at[..., 0].set(1.0)
    return u, jnp.zeros(jnp.shape(r))


DEPTH, AMPLITUDE, PERIOD = 50.0, 1.0, 8.0  # m, m, s
OMEGA = 2.0 * math.pi / PERIOD


def _wave_number(omega, h, g=9.80665):
    k = omega * omega / g
    for _ in range(60):  # Newton on ω² = g k tanh(kh)
        f = g * k * math.tanh(k * h) - omega * omega
        df = g * math.tanh(k * h) + g * k * h / math.cosh(k * h) ** 2
        k -= f / df
    return k


K = _wave_number(OMEGA, DEPTH)


def wave(r, t):
    """A regular Airy wave along +x (amplitude 1 m, period 8 s, 50 m water),
    linear kinematics at the node's own height (no stretching), held at their
    z = 0 values above the still-water level."""
    r = jnp.asarray(r)
    z = jnp.minimum(r[..., 2], 0.0)
    psi = OMEGA * t - K * r[..., 0]
    ch = jnp.cosh(K * (z + DEPTH)) / math.sinh(K * DEPTH)
    sh = jnp.sinh(K * (z + DEPTH)) / math.sinh(K * DEPTH)
    aw = AMPLITUDE * OMEGA
    zero = jnp.zeros_like(psi)
    u = jnp.stack([aw * ch * jnp.cos(psi), zero, -aw * sh * jnp.sin(psi)], axis=-1)
    a = jnp.stack([-aw * OMEGA * ch * jnp.sin(psi), zero, -aw * OMEGA * sh * jnp.cos(psi)], axis=-1)
    return u, a
