"""Bodies carrying lines whose end forces depend on the ends' accelerations.

A line with a consistent mass (:class:`~moorjax.element.HermiteElement`) exerts
on its two ends the forces

    f = f₀ − M_e·(a_e − ā_e),         (its free unknowns: q̈ = q̈₀ − S·(a_e − ā_e))

where a_e = (a_A, a_B) are the ends' accelerations, ā_e their paths' (zero for a
fairlead placed by :func:`~moorjax.body.coupling.attach`), f₀, q̈₀ the forces and
rates at ā_e, and M_e (6×6, the Schur complement M_pp − M_pf·M_ff⁻¹·M_fp of the
consistent mass) the line's inertia as its ends feel it
(:meth:`~moorjax.element.AbstractElement.state_end_response`). A node element
has no such term: its end node's mass belongs to the body.

A fairlead on a body accelerates as a = G·ẍ + c, ẍ the rate of the body's
velocity state (η̈, or (v̇, ω̇) for a :class:`~moorjax.body.SubmergedBody`),
G = ∂a/∂ẍ (3×6) and c the centripetal part (the exact time derivative of
:meth:`~moorjax.body.base.AbstractBody.point_velocity`, by a JVP). Every body's
rate is affine in the mooring wrench W, ẍ = ẍ₀ + B·W with B = ∂ẍ/∂W its
mobility ((M + A∞)⁻¹ for a :class:`~moorjax.body.RigidBody`, by forward AD of
its ``rate``), and W holds Gᵀf per fairlead. Together:

    (I − B·K) ẍ = ẍ₀ + B·d,    K = Σ Gᵀ(−M_e)G,  d = Σ Gᵀ(−M_e)c

one dense solve over all bodies' 6·n_bodies accelerations (a line between two
bodies couples them); −K is the lines' end inertia seen by the bodies, so
I − B·K = B(M + (−K)) is regular. The lines' end forces, their rates and the
bodies' rates then follow with the consistent end accelerations.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..model.ends import BodyEnd
from .coupling import mooring_wrenches


def fairlead_map(body, z, pose_rate, local):
    """(G (3, 6), c (3,)): a body-fixed point's acceleration G·ẍ + c [m/s²], ẍ
    the rate of the body's velocity state ``z[6:12]``, ``pose_rate`` that of
    its pose ``z[:6]``, ``local`` (3,) the point in body axes [m]."""
    pose, vel = z[:6], z[6:12]

    def acceleration(x):
        return jax.jvp(lambda p, v: body.point_velocity(p, v, local), (pose, vel), (pose_rate, x))[1]

    zero = jnp.zeros(6)
    return jax.jacfwd(acceleration)(zero), acceleration(zero)


def couple(t, lines, bodies, zs, responses, env):
    """Line rates, end forces and body rates with the lines' end inertia.

    Args:
        t: time [s].
        lines: the scene's lines (with their :class:`BodyEnd` s, not attached).
        bodies: the scene's bodies; zs: their solver states.
        responses: per line, ``(rate, forces (2, 3), rate_gain, force_gain)`` from
            :meth:`~moorjax.element.AbstractElement.state_end_response` of the
            attached line (gains ``None`` for lines without end inertia).
        env: the scene's environment.

    Returns:
        (line rates, end forces (one (2, 3) per line) [N], body rates).
    """
    poses = [z[:6] for z in zs]
    forces0 = [r[1] for r in responses]
    w0 = mooring_wrenches(lines, bodies, poses, forces0)
    rates0 = [body.rate(t, z, w, env) for body, z, w in zip(bodies, zs, w0)]
    nb = len(bodies)
    size = 6 * nb
    k_mat = jnp.zeros((size, size))
    d = jnp.zeros(size)
    maps = []  # per line: {end index: (body, G, c)}
    for line, (_, _, _, force_gain) in zip(lines, responses):
        ends = {k: e for k, e in enumerate((line.end_a, line.end_b)) if isinstance(e, BodyEnd)}
        if force_gain is None or not ends:
            maps.append({})
            continue
        m = {k: (e.body, *fairlead_map(bodies[e.body], zs[e.body], rates0[e.body][:6], e.point))
             for k, e in ends.items()}
        for k, (b, g, _) in m.items():
            for k2, (b2, g2, c2) in m.items():
                gain = force_gain[k][:, 3 * k2:3 * k2 + 3]  # ∂f_k/∂a_k2 (3, 3)
                k_mat = k_mat.at[6 * b:6 * b + 6, 6 * b2:6 * b2 + 6].add(g.T @ gain @ g2)
                d = d.at[6 * b:6 * b + 6].add(g.T @ gain @ c2)
        maps.append(m)
    mobility = jax.scipy.linalg.block_diag(*[
        jax.jacfwd(lambda w, body=body, z=z: body.rate(t, z, w, env)[6:12])(w)
        for body, z, w in zip(bodies, zs, w0)])
    acc0 = jnp.concatenate([r[6:12] for r in rates0])
    x = jnp.linalg.solve(jnp.eye(size) - mobility @ k_mat, acc0 + mobility @ d).reshape(nb, 6)

    line_rates, forces = [], []
    for (rate, f0, rate_gain, force_gain), m in zip(responses, maps):
        if not m:
            line_rates.append(rate)
            forces.append(f0)
            continue
        a_e = jnp.concatenate([m[k][1] @ x[m[k][0]] + m[k][2] if k in m else jnp.zeros(3)
                               for k in (0, 1)])
        line_rates.append(rate + rate_gain @ a_e)
        forces.append(f0 + force_gain @ a_e)
    wrenches = mooring_wrenches(lines, bodies, poses, forces)
    body_rates = [body.rate(t, z, w, env) for body, z, w in zip(bodies, zs, wrenches)]
    return tuple(line_rates), forces, tuple(body_rates)
