"""Wu et al.'s Newmark/Newton stepping of a Hermite line (Eq. 33–41): a reference solver.

Average-acceleration Newmark (β = ¼, γ = ½) on the node positions and slopes U,
with Newton–Raphson on the coupled (U, λ) system at every step: the equation of
motion (inertia minus the element's generalised forces, Eq. 19) on the free
unknowns and the extensibility condition (Eq. 27) on the tension field. The end
nodes follow their end conditions; their slopes are free. The Jacobian is dense
(forward-mode AD), fine for the ~10 elements this solver is meant for; it is a
check on the element and on diffrax runs, not the production driver.

Measured on the reference case A (10 elements, 60 s, against MoorDyn at 160
segments; fairlead force = the line's generalised force on the end node minus
its consistent inertia): RMS/std of the fairlead force 1.25 % at dt = 0.01 s
(1.06 % over the first 20 s, the same at dt = 0.005 s), peaks within 0.1 %.
It was 9.7 % while the element's tension field was bilateral: in the troughs
the lower line carried up to −170 kN of compression and the fairlead tension
fell to 12 kN where MoorDyn stays at 115 kN; the slack regularisation of
:mod:`moorjax.element.hermite` removed that. Newton (6 iterations) leaves a
scaled residual of up to 0.15 in a few steps where the tension field crosses
zero (the regularised law's kink); the histories do not change at dt = 0.005 s.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.lax as lax
import jax.numpy as jnp
import numpy as np

from ..element.hermite import HermiteDofs, extensibility, generalized_forces, inertia_forces


class NewmarkResult(eqx.Module):
    """Histories at the step times: ``t`` (m,) [s], ``force_a``/``force_b`` (m, 3) [N]
    (the line's force on its end points: the generalised force on the end node
    minus the consistent inertia of its shape function, which tends to the end
    tension as the elements shrink, as MoorDyn's end-node force does),
    ``tension_b`` (m,) [N], ``newton_residual`` (m,) (largest scaled residual
    after the step's Newton iterations), ``lam`` (m, 2n+1) the tension field [N]."""

    t: jax.Array
    force_a: jax.Array
    force_b: jax.Array
    tension_b: jax.Array
    newton_residual: jax.Array
    lam: jax.Array


def _pack(line, t, y):
    r_free, dr, lam = y
    ra, rb = line.end_a.position(t), line.end_b.position(t)
    return HermiteDofs(r=jnp.concatenate([ra[None], r_free, rb[None]]), dr=dr, lam=lam)


@eqx.filter_jit
def newmark_hermite(line, env, init: HermiteDofs, t0, dt, n_steps: int, newton_iterations: int = 6):
    """Integrate from the static state ``init`` at t0 [s] over ``n_steps`` steps of dt [s]."""
    h = line.segment_length
    k = line.line_type.axial.nominal_ea() / h
    n = line.n_segments

    def residual(y, prev, t):
        u_n, v_n, a_n = prev
        dofs = _pack(line, t, y)
        u = (dofs.r, dofs.dr)
        acc = jax.tree.map(lambda x, x0, v0, a0: 4.0 / dt**2 * (x - x0 - dt * v0) - a0, u, u_n, v_n, a_n)
        vel = jax.tree.map(lambda v0, a0, a: v0 + 0.5 * dt * (a0 + a), v_n, a_n, acc)
        f, m = generalized_forces(line, env, dofs, HermiteDofs(vel[0], vel[1], dofs.lam), t)
        fi, mi = inertia_forces(line, env, dofs, HermiteDofs(acc[0], acc[1], dofs.lam))
        return ((fi - f)[1:-1] / k, (mi - m) / (k * h), extensibility(line, dofs)), acc, vel, (f - fi, m)

    flat = lambda tree: jnp.concatenate([x.reshape(-1) for x in jax.tree.leaves(tree)])  # noqa: E731
    y_shapes = ((n - 1, 3), (n + 1, 3), (2 * n + 1,))

    def unflat(v):
        out, i = [], 0
        for s in y_shapes:
            size = int(np.prod(s))
            out.append(v[i:i + size].reshape(s))
            i += size
        return tuple(out)

    def step(carry, i):
        y, prev = carry
        t = t0 + (i + 1) * dt

        def newton(_, yv):
            fun = lambda z: flat(residual(unflat(z), prev, t)[0])  # noqa: E731
            rv, jac = fun(yv), jax.jacfwd(fun)(yv)
            return yv - jnp.linalg.solve(jac, rv)

        yv = lax.fori_loop(0, newton_iterations, newton, flat(y))
        y_new = unflat(yv)
        res, acc, vel, (f, _) = residual(y_new, prev, t)
        dofs = _pack(line, t, y_new)
        out = (f[0], f[-1], jnp.max(jnp.abs(flat(res))), y_new[2])
        return (y_new, ((dofs.r, dofs.dr), vel, acc)), out

    # start: the static state, free nodes at rest, ends moving with their paths
    u0 = (init.r, init.dr)
    v0 = (jnp.zeros_like(init.r).at[0].set(line.end_a.velocity(t0)).at[-1].set(line.end_b.velocity(t0)),
          jnp.zeros_like(init.dr))
    a0 = (jnp.zeros_like(init.r), jnp.zeros_like(init.dr))
    y0 = (init.r[1:-1], init.dr, init.lam)
    _, (fa, fb, res, lam) = lax.scan(step, (y0, (u0, v0, a0)), jnp.arange(n_steps))
    ts = t0 + dt * jnp.arange(1, n_steps + 1)
    return NewmarkResult(t=ts, force_a=fa, force_b=fb, tension_b=jnp.linalg.norm(fb, axis=-1),
                         newton_residual=res, lam=lam)
