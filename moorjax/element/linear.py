"""Aamo & Fossen's Galerkin linear element for a cable in water.

Node k at r_k, element j between nodes j and j+1 with chord ℓ_j = |r_{j+1} − r_j|,
unit tangent t_j, strain e_j = ℓ_j/l − 1 (l = L/n unstretched). Forces on the nodes
(all vectorised over nodes/segments):

- elastic and internal damping: T_j = law(e_j) + BA·ė_j along t_j (Eq. 2/7, f_r);
- gravity and buoyancy: the wet weight w = (m − ρA)g per unstretched length,
  w·l/2 from each adjacent element (f_hg, whose (1+e) factors cancel). A line that
  reaches the free surface (z = 0, or the wave elevation η with ``env.waves``) is
  buoyant only where it is under water, as in MoorDyn v2 (``Line::calcSubSeg`` in
  ``source/Line.cpp``, v2.4+): element j is wet over the fraction F_j of its length
  that lies below the surface, linear between its nodes' heights h (1 below, 0
  above, −h_a/(h_b − h_a) across), and node k's buoyancy is ρAg·l·(F_{k−1} + F_k)/2;
  the drag, the water's inertia and the added mass of element j scale with F_j too.
  Under water F ≡ 1 and nothing changes;
- Morison drag on the velocity relative to the water (current plus wave particle
  velocity), per adjacent element half (stretched length ℓ_j/2), split on t_j into
  axial and normal parts (Eq. 7, f_dt, f_dn);
- with waves (``env.waves``), the water's acceleration a_w at each node loads it
  through each adjacent element half: ρA(ℓ_j/2)·[(1 + Ca_n)·a_n + (1 + Ca_ax)·a_t]
  with a_t = (a_w·t_j)t_j, a_n = a_w − a_t (Froude–Krylov plus the added-mass part,
  MoorDyn v2's line force ``Ap``/``Aq`` in ``source/Line.cpp``; Ca = 0 without
  ``added_mass``);
- seabed contact on nodes below z = −depth (MoorDyn's vertical spring–damper on
  d·l_node), with optional smoothed friction;
- bending, when the line type has ``ei``: the curvature at each interior node k
  from the turning of the tangent between its two segments, κ_k = |κb_k|/l with
  κb = 2·t_{k−1}×t_k/(1 + t_{k−1}·t_k) (|κb| = 2·tan(θ/2) ≈ θ, the discrete
  curvature of elastic rods, smooth through the straight state), in the beam
  energy ½·EI·κ²·l per node; forces are minus its gradient. An end node carries
  no moment (a pin) unless its end is clamped
  (:class:`~moorjax.model.ends.AbstractClampedEnd`): then the turning from the
  clamp's direction to the end segment adds EI·|κb|²/l (:func:`clamp_energy`).

Absent structure (no drag, no seabed, no current, no waves) is never traced.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .._numerics import safe_unit
from ..linalg import block_tridiagonal as btd
from ..linalg.mass_form import MassFormW
from ..model.ends import clamp_directions
from . import morison
from .base import AbstractElement
from .mass import AbstractMass, NodalMass


def _to_nodes(left, right):
    """Scatter per-segment contributions to its left (j) and right (j+1) nodes."""
    pad = jnp.zeros_like(left[:1])
    return jnp.concatenate([left, pad], axis=0) + jnp.concatenate([pad, right], axis=0)


def submerged_fraction(h):
    """Wet fraction F_j ∈ [0, 1] of each element (n,) from its nodes' heights above the
    free surface h (n+1,) [m]: 1 below, 0 above, −h_a/(h_b − h_a) for an element that
    crosses it (MoorDyn v2's ``calcSubSeg``), 1/2 for one lying in the surface. It is
    continuous in the node heights (kinked where a node crosses the surface)."""
    ha, hb = h[:-1], h[1:]
    wet = jnp.maximum(-ha, 0.0) + jnp.maximum(-hb, 0.0)
    span = jnp.abs(ha) + jnp.abs(hb)
    ok = span > 0.0
    return jnp.where(ok, wet / jnp.where(ok, span, 1.0), 0.5)


def _node_lengths(line):
    """Unstretched length carried by each node (n+1,) [m]: l/2 at the ends, l inside."""
    n = line.n_segments
    w = jnp.ones(n + 1).at[0].set(0.5).at[-1].set(0.5)
    return w * line.segment_length


class LinearElement(AbstractElement):
    """Linear (two-node) Galerkin element; ``mass`` chooses Eq. 7 or Eq. 2."""

    mass: AbstractMass = NodalMass()

    @property
    def banded_jacobian(self) -> bool:
        return self.mass.banded

    @property
    def wets_partially(self) -> bool:
        return True

    def line_banded(self, line) -> bool:
        return self.mass.banded and line.line_type.ei is None

    # -- geometry -------------------------------------------------------------
    @staticmethod
    def _segments(r):
        d = r[1:] - r[:-1]
        tangent, stretched = safe_unit(d)
        return tangent, stretched

    def segment_tensions(self, line, r, v):
        tangent, stretched = self._segments(r)
        l = line.segment_length
        strain = stretched / l - 1.0
        lt = line.line_type
        tension = lt.axial.tension(strain)
        strain_rate = jnp.sum(tangent * (v[1:] - v[:-1]), axis=-1) / l
        return tension + lt.damping * strain_rate

    # -- forces ---------------------------------------------------------------
    def nodal_forces(self, line, env, r, v, t=0.0):
        return self._forces(line, env, r, v, t)[0]

    def _forces(self, line, env, r, v, t):
        """All-node forces (n+1, 3) [N], the elements' unit tangents (n, 3) and their wet
        (stretched, under the surface) lengths (n,) [m]."""
        lt = line.line_type
        tangent, stretched = self._segments(r)
        tension = self.segment_tensions(line, r, v)
        f_seg = tension[:, None] * tangent
        force = _to_nodes(f_seg, -f_seg)

        wave_u = wave_a = None
        r_current = r
        surface = 0.0
        if env.waves is not None:
            eta, wave_u, wave_a = env.waves.kinematics(r, t)
            r_current = r.at[:, 2].set(env.waves.current_height(r, eta))
            surface = eta
        frac = submerged_fraction(r[:, 2] - surface)
        wet = stretched * frac  # the wet length of each element

        node_len = _node_lengths(line)
        weight = lt.wet_weight(env.rho, env.g)
        # buoyancy lost above the surface: exactly zero for a line under water
        half_dry = 0.5 * line.segment_length * (frac - 1.0)
        dry = _to_nodes(half_dry, half_dry)
        force = force.at[:, 2].add(-weight * node_len + env.rho * lt.area * env.g * dry)

        if wave_a is not None:
            force = force + _to_nodes(
                _fluid_inertia(lt, env, wave_a[:-1], tangent, wet),
                _fluid_inertia(lt, env, wave_a[1:], tangent, wet),
            )

        if lt.drag is not None:
            u = v if env.current is None else v - env.current.velocity_at(r_current, t)
            if wave_u is not None:
                u = u - wave_u
            force = force + _to_nodes(
                _drag(lt, env, u[:-1], tangent, wet),
                _drag(lt, env, u[1:], tangent, wet),
            )

        if env.seabed is not None:
            force = force + _seabed(lt, env, r, v, node_len)
        if lt.ei is not None:
            force = force + _bending(lt.ei, line.segment_length, r,
                                    *clamp_directions(line.end_a, line.end_b, t))
        return force, tangent, wet

    def accelerations(self, line, env, t, r, v):
        force, tangent, wet = self._forces(line, env, r, v, t)
        # the added mass of each element is that of its wet length
        return self.mass.accelerations(line, env, t, force, tangent, wet)

    def end_forces(self, line, env, r, v, t=0.0):
        force = self.nodal_forces(line, env, r, v, t)
        return force[0], force[-1]

    def provides_stiff_band(self, line) -> bool:
        return self.line_banded(line)

    def stiff_band(self, line, env, t, q):
        """W ≈ ∂(state rate)/∂q from the terms that make a line stiff, each
        differentiated exactly on its own small function (forward mode), in
        mass form (see :func:`stiff_band`). ``None`` for lines with bending
        (their Jacobian is not block-tridiagonal)."""
        if not self.provides_stiff_band(line):
            return None
        return stiff_band(line, env, t, q)

    def stiff_linearisation(self, line, env, t, q):
        """(:meth:`stiff_band`, its time column): in steady water the line's
        equations depend on time through its ends alone, and W's couplings of
        the end nodes give ∂(state rate)/∂t (see :func:`stiff_band`)."""
        if not self.provides_stiff_band(line):
            return None, None
        if not env.steady:
            return stiff_band(line, env, t, q), None
        return stiff_band(line, env, t, q, with_time=True)


def stiff_band(line, env, t, q, with_time: bool = False):
    """W ≈ ∂[v, a]/∂[r, v] of a line's free nodes in mass form
    (:class:`~moorjax.linalg.mass_form.MassFormW`: the nodal masses M and the
    3×3 block-tridiagonal force derivatives K_r, K_v, W = [[0, I], [M⁻¹K_r,
    M⁻¹K_v]]); ``with_time``: ``(W, W_t)`` with W_t ≈ ∂[v, a]/∂t (rows, 6) from the
    same couplings to the end nodes, valid where time enters only through the
    ends' motions (steady water).

    Exact for the terms that make a mooring line stiff, each differentiated by
    forward mode on its own small function rather than through the whole
    vector field (18 coloured JVPs of it cost ~30 evaluations of it):

    - the segment tension T(ℓ, ṡ)·t (elastic law and internal damping; 6 JVPs
      of the per-segment force in the chord d and the relative velocity Δv);
    - the seabed contact (spring, damping ramp, friction; node-local, 6 JVPs);
    - the Morison drag's dependence on the node velocities (node-local with the
      tangents held, 3 JVPs).

    Left out (non-stiff, and a W-method keeps its order with any W): the
    dependence of the mass matrix (added mass), drag, fluid inertia and
    buoyancy on the tangents and wet lengths, and of currents and waves on the
    node positions. a = M⁻¹F with M the nodal mass at the current tangents.

    The time column: a free node next to an end feels the end's motion through
    the segment between them, W_t = M⁻¹(K_d·ṙ_end + K_v·r̈_end) on the
    accelerations of nodes 1 and n−1 (K_d, K_v the segment force's derivatives
    in its chord and relative velocity, as in the band) and 0 elsewhere. It
    replaces the Rosenbrock-W stepper's forward difference of the whole vector
    field in t (:meth:`~moorjax.dynamics.rosenbrock.RosenbrockW._time_derivative`),
    with the same terms left out as W leaves out: ROS34PW2's W-method order
    conditions (order 2 for any W) hold for any time column too, since in the
    autonomous form (Hairer & Wanner II, IV.7) it is one more column of W.
    """
    from ..model.line import LineState
    from .mass import _segment_mass_tensors

    lt = line.line_type
    l = line.segment_length
    r, v = line.nodes(t, LineState(r=q[:, :3], v=q[:, 3:]))
    d, dv = r[1:] - r[:-1], v[1:] - v[:-1]

    def segment_force(d, dv):
        tangent, stretched = safe_unit(d)
        tension = lt.axial.tension(stretched / l - 1.0) + lt.damping * jnp.sum(tangent * dv, -1) / l
        return tension[:, None] * tangent

    def columns(fn, x):
        """(rows, 3 out, 3 in) node- or segment-local Jacobian of fn at x (rows, 3)."""
        seeds = jnp.broadcast_to(jnp.eye(3)[:, None, :], (3,) + x.shape)
        cols = jax.vmap(lambda e: jax.jvp(fn, (x,), (e,))[1])(seeds)  # (3 in, rows, 3 out)
        return jnp.moveaxis(cols, 0, -1)

    k_d = columns(lambda x: segment_force(x, dv), d)  # (n, 3, 3) ∂f_j/∂d_j
    k_v = columns(lambda x: segment_force(d, x), dv)
    # node k gets +f_k (as the left node of segment k) and −f_{k−1}
    zero = jnp.zeros_like(k_d[:1])
    f_r_self = -jnp.concatenate([k_d, zero]) - jnp.concatenate([zero, k_d])  # (n+1, 3, 3)
    f_v_self = -jnp.concatenate([k_v, zero]) - jnp.concatenate([zero, k_v])
    f_r_next, f_v_next = k_d, k_v  # ∂F_k/∂x_{k+1} = +K_k (k = 0..n−1)
    f_r_prev, f_v_prev = k_d, k_v  # ∂F_k/∂x_{k−1} = +K_{k−1} (k = 1..n)

    tangent, stretched = safe_unit(d)
    surface = 0.0 if env.waves is None else env.waves.kinematics(r, t)[0]
    wet = stretched * submerged_fraction(r[:, 2] - surface)  # as in _forces
    node_len = _node_lengths(line)
    if env.seabed is not None:
        f_r_self = f_r_self + columns(lambda x: _seabed(lt, env, x, v, node_len), r)
        f_v_self = f_v_self + columns(lambda x: _seabed(lt, env, r, x, node_len), v)
    if lt.drag is not None:

        def drag(u):
            return _to_nodes(_drag(lt, env, u[:-1], tangent, wet), _drag(lt, env, u[1:], tangent, wet))

        f_v_self = f_v_self + columns(drag, v)  # relative velocity: ∂u/∂v = I

    mu = _segment_mass_tensors(line, env, tangent, wet)  # added mass of the wet length
    mass = 0.5 * (mu[:-1] + mu[1:])  # free nodes 1..n−1
    m_inv = btd.inv3(mass)

    def band(prev, own, nxt):  # node k couples to k−1 through K_{k−1}, to k+1 through K_k
        return prev[:-1].at[0].set(0.0), own[1:-1], nxt[1:].at[-1].set(0.0)  # nodes 0, n: ends

    w = MassFormW(mass=mass, mass_inv=m_inv, k_r=band(f_r_prev, f_r_self, f_r_next),
                  k_v=band(f_v_prev, f_v_self, f_v_next))
    if not with_time:
        return w
    # ∂F_1/∂[r_0, v_0] = [K_d, K_v] of segment 0, ∂F_{n−1}/∂[r_n, v_n] of segment n−1
    ends = ((0, 0, line.end_a), (-1, -1, line.end_b))
    time = jnp.zeros((q.shape[0], 6), dtype=q.dtype)
    for row, seg, end in ends:
        pull = btd.bmv(k_d[seg], end.velocity(t)) + btd.bmv(k_v[seg], end.acceleration(t))
        time = time.at[row, 3:].add(btd.bmv(m_inv[row], pull))
    return w, time


def bending_energy(ei, l, r):
    """Beam energy Σ_k ½·EI·κ_k²·l [J] of the polyline r (n+1, 3) with segment length l.

    κ_k = |κb_k|/l at the interior nodes, κb = 2·t_a×t_b/(1 + t_a·t_b) for the unit
    tangents t_a, t_b of the segments before and after node k: |κb| = 2·tan(θ/2)
    for the turning angle θ, so κ → θ/l for small turning, and the energy and its
    gradient are smooth when the line is straight (no norm of a zero cross product).
    """
    t, _ = safe_unit(r[1:] - r[:-1])
    ta, tb = t[:-1], t[1:]
    cross = jnp.cross(ta, tb)
    dot = jnp.sum(ta * tb, axis=-1)
    kb2 = 4.0 * jnp.sum(cross * cross, axis=-1) / (1.0 + dot) ** 2
    return 0.5 * ei / l * jnp.sum(kb2)


def clamp_energy(ei, l, direction, tangent):
    """Bending energy EI·|κb|²/l [J] at a clamped end node.

    ``direction``: the clamp's unit vector continued through the end (for end B
    the reverse of the direction in which the line leaves it); ``tangent``: the
    end segment's unit tangent along the line (A to B). A mirrored ghost segment
    beyond the clamp turns by twice the angle θ between them, over the end node's
    half length l/2: ½·EI·(2θ/l)²·l/2 = EI·θ²/l, the curvature 2θ/l being
    MoorDyn's end curvature 4·sin(θ/2)/l at a line end held by a rod (its
    ``CANTILEVERED`` end type) to leading order; |κb| = 2·tan(θ/2) as at the
    interior nodes keeps it smooth at θ = 0.
    """
    cross = jnp.cross(direction, tangent)
    dot = jnp.sum(direction * tangent, axis=-1)
    return ei / l * 4.0 * jnp.sum(cross * cross, axis=-1) / (1.0 + dot) ** 2


def _bending(ei, l, r, d_a=None, d_b=None):
    """Bending forces (n+1, 3) [N]: minus the gradient of :func:`bending_energy`
    and, at clamped ends (``d_a``/``d_b`` not ``None``), of :func:`clamp_energy`."""
    import jax

    def energy(r):
        e = bending_energy(ei, l, r)
        if d_a is not None:
            e = e + clamp_energy(ei, l, d_a, safe_unit(r[1] - r[0])[0])
        if d_b is not None:
            e = e + clamp_energy(ei, l, safe_unit(r[-1] - r[-2])[0], d_b)
        return e

    return -jax.grad(energy)(r)


def _drag(lt, env, u, tangent, stretched):
    """Drag on one node from one adjacent element half: (n, 3) [N]."""
    return (0.5 * stretched)[:, None] * morison.drag(lt, env, u, tangent)


def _fluid_inertia(lt, env, a, tangent, stretched):
    """Froude–Krylov and added-mass load of the water's acceleration ``a`` (n, 3)
    [m/s²] on one node from one adjacent element half: (n, 3) [N]."""
    return (0.5 * stretched)[:, None] * morison.fluid_inertia(lt, env, a, tangent)


def _seabed(lt, env, r, v, node_len):
    """Contact force (n+1, 3) [N]: the bed's load per unit length
    (:meth:`~moorjax.model.environment.Seabed.contact`: kBot·δ − cBot·v·n along
    the bed's normal, friction along it) on each node's length, and the bed's
    support of a grounded end (:func:`_end_support`; on a bathymetry its
    component along the normal, the rest stays on the end as on an inclined
    catenary)."""
    load, height, n = env.seabed.contact(r, v, lt.diameter, lt.wet_weight(env.rho, env.g), env.depth)
    ends = jnp.array([0, -1])
    support = _end_support(lt, env, -height, node_len) * n[ends, 2]
    return (load * node_len[:, None]).at[ends].add(support[:, None] * n[ends])


def _end_support(lt, env, pen, node_len):
    """Vertical support (2,) [N] of the bed under the end nodes.

    An end node held on the bed (an anchor) never sinks into it, so the spring
    gives it no support; where the adjacent node rests on the bed, the line's first
    half segment lies on the seabed and the bed carries its wet weight, as it does
    for the continuous line (the anchor then feels only the grounded tension, as in
    the analytic catenary), instead of the end node hanging that weight on the
    anchor. ``pen``: (n+1,) penetration of the nodes below the bed [m].
    """
    on_bed = pen[jnp.array([0, -1])] > -1e-6 * env.depth
    neighbour_rests = pen[jnp.array([1, -2])] > 0
    share = jnp.maximum(lt.wet_weight(env.rho, env.g), 0.0) * node_len[jnp.array([0, -1])]
    return jnp.where(on_bed & neighbour_rests, share, 0.0)
