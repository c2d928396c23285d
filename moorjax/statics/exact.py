"""A line's static equilibrium from the exact elastic catenary, sampled at its nodes.

For a uniform line with Hooke's law (``LinearEA``), no bending stiffness (or a
negligible one: bending length √(EI/H) below 1e-4 of the length), in still water
over a flat seabed (or none), the continuum equilibrium is the analytic
elastic catenary (Irvine 1981; :mod:`moorjax.statics.catenary`), with a grounded
length when the lower end rests on the seabed. Its end tensions are those of the
line itself, whatever the number of segments, whereas the lumped-mass finite-element
equilibrium (:mod:`moorjax.statics.fem`) carries a discretisation error: it
represents the touchdown kink only to within about one segment, so where the
catenary parameter H/w is shorter than a few tens of segments its end tensions are
off by up to ~1 % at 80 segments (``tests/test_statics_property.py``).

This module gives that continuum answer as a :class:`~moorjax.statics.fem.LineStatics`:
node positions at the nodes' unstretched arc lengths (stretch included), segment
tensions at segment mid-lengths, end forces and grounded length of the catenary.
It is *not* an equilibrium of the discrete model, so it is not a dynamic start
state: dynamics start from the finite-element equilibrium (``method="fem"``).

Where the catenary does not apply or has no solution — a line whose sag would go
under the seabed with both ends above it, a slack line piled on the bed, a
weightless slack line — the ``ok`` flag of :func:`catenary_statics` is False at run
time and the caller falls back to the finite-element solve. Seabed friction is left out, as in
the finite-element statics and MoorDyn (a line at rest carries no friction).
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp

from .._numerics import as_float, safe_norm
from ..element.linear import LinearElement
from .catenary import catenary_line_forces, catenary_nodes, catenary_profile
from ..model.axial import LinearEA

__all__ = ["catenary_eligible", "catenary_statics", "catenary_solves"]


def catenary_eligible(line, env) -> bool:
    """Whether the analytic catenary is this line's exact continuum statics (structure only).

    True for the linear element with Hooke's law (tension-only), no current, and
    a flat seabed or none. Values (end positions, whether a catenary solution
    exists, whether a bending stiffness is negligible) are judged at run time by
    :func:`catenary_statics`.
    """
    lt = line.line_type
    flat = env.seabed is None or env.seabed.bathymetry is None
    return (isinstance(line.element, LinearElement) and type(lt.axial) is LinearEA
            and env.current is None and flat)


#: A bending stiffness EI is negligible when its bending length √(EI/H) is below
#: this fraction of the line's length (its effect on the end tensions is of that
#: relative order): e.g. the EI = 0.8 N·m² that MoorDyn decks often carry for chain.
BENDING_LENGTH_FRACTION = 1e-4


def catenary_statics(line, env, t):
    """The exact catenary equilibrium of ``line`` at time ``t`` [s], and whether it holds.

    Returns ``(LineStatics, ok)``; ``ok`` (a bool array) is False where the
    catenary has no solution or its profile dips under the seabed, in which case
    the statics must come from the finite-element solve. ``iterations`` counts
    the catenary's Newton steps; ``max_residual`` is its end-point mismatch times
    EA/L [N] (the force that mismatch would take to close).
    """
    from .fem import LineStatics  # fem imports this module

    lt = line.line_type
    ra, rb = line.end_a.position(t), line.end_b.position(t)
    w = lt.wet_weight(env.rho, env.g)
    ea = lt.axial.nominal_ea()
    length = line.length
    bed = None if env.seabed is None else -env.depth
    # grounded contact is modelled when the lower end rests on the seabed
    touchdown = (bed is not None) and (jnp.minimum(ra[2], rb[2]) <= bed * (1.0 - 1e-9))
    sol, fa, fb = catenary_line_forces(ra, rb, length, ea, w, 0.0, seabed=touchdown)
    l = line.segment_length
    s = l * jnp.arange(line.n_segments + 1)
    nodes = catenary_nodes(sol, ra, rb, s).at[0].set(ra).at[-1].set(rb)
    # segment tension at mid-length (profile measured from the lower end)
    mid = l * (jnp.arange(line.n_segments) + 0.5)
    swap = ra[2] > rb[2]
    _, _, tension = catenary_profile(sol, jnp.where(swap, length - mid, mid))
    ok = sol.converged & jnp.all(jnp.isfinite(nodes)) & jnp.all(jnp.isfinite(tension))
    if lt.ei is not None:  # a cable, unless the bending length is negligible
        bending_length = jnp.sqrt(lt.ei / jnp.maximum(sol.HF, jnp.finfo(float).tiny))
        ok = ok & (bending_length <= BENDING_LENGTH_FRACTION * length)
    # a line above the water surface is buoyant only where it is wet (the linear
    # element's submerged fraction): the uniform catenary then does not hold
    dry = jnp.any(nodes[:, 2] > 1e-9 * jnp.maximum(env.depth, length))
    ok = ok & ~(dry & (env.rho * lt.area * env.g != 0))
    if bed is not None:
        # the free catenary must not pass under the bed (else it would rest on it)
        scale = jnp.maximum(jnp.abs(bed), length)
        ok = ok & jnp.all(nodes[:, 2] >= bed - 1e-9 * scale)
        ok = ok & (jnp.asarray(touchdown) | jnp.all(_sag_above(sol, bed, ra, rb, length)))
    out = LineStatics(
        positions=nodes,
        tensions=tension,
        force_a=fa,
        force_b=fb,
        tension_a=safe_norm(fa),
        tension_b=safe_norm(fb),
        grounded_length=sol.grounded_length,
        converged=ok,
        iterations=sol.steps,
        max_residual=sol.residual * ea / length,
    )
    return out, ok


def _sag_above(sol, bed, ra, rb, length):
    """Whether the catenary between the nodes stays above the bed: the lowest point
    of a sagging catenary lies where the vertical tension vanishes (s = VA-free
    point), which may fall between nodes."""
    # arc length from the lower end where the vertical tension is zero: VA < 0 means
    # the line leaves the lower end going down
    s0 = jnp.clip(-sol.VA / jnp.where(sol.W > 0, sol.W, jnp.inf), 0.0, length)
    _, z0, _ = catenary_profile(sol, s0)
    lo = jnp.minimum(ra[2], rb[2])
    return lo + z0 >= bed - 1e-9 * jnp.maximum(jnp.abs(bed), length)


def catenary_solves(line, env, t=0.0) -> bool:
    """Whether the catenary statics of an eligible line holds at ``t`` (host-side)."""
    return bool(_ok(line, env, as_float(t)))


@eqx.filter_jit
def _ok(line, env, t):
    return catenary_statics(line, env, t)[1]
