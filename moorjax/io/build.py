"""From a parsed MoorDyn deck to a moorjax :class:`Scene`.

MoorDyn conventions kept (so a deck means the same in both codes):

- ``Diam`` is the volume-equivalent diameter (buoyancy, drag, added mass).
- ``BA/-zeta``: BA ≥ 0 is an internal damping coefficient [N·s]; BA < 0 means a
  fraction ζ = −BA of each segment's critical damping, BA = ζ·(L/N)·√(EA·m),
  evaluated with the segment count actually used (``--segments`` included).
- ``Cd`` acts on the frontal area d·l, ``CdAx`` on the surface area π·d·l.
- ``Ca``/``CaAx`` multiply the displaced mass ρ·A·l.
- Seabed: ``kBot`` [Pa/m] and ``cBot`` [Pa·s/m] on d·l; ``FrictionCoefficient``
  > 0 adds smoothed Coulomb friction (slip velocity 0.01 m/s).
- Coupled points hold their deck position unless a motion is given.
- Free points (``Free``/``Point``/``Connect``) become
  :class:`~moorjax.body.ConnectionPoint` s in ``Scene.bodies`` (file order),
  their lines ending on them through ``BodyEnd(k, (0, 0, 0))``; the deck's
  position is where the statics start (MoorDyn: the initial guess).
- Bodies (``BODIES``): a point ``Body<n>`` is fixed in body n, its coordinates
  in body axes relative to the body's reference point (X0, Y0, Z0), placed at
  (X0, Y0, Z0) + R·p with MoorDyn's R = Rx(r0)·Ry(p0)·Rz(y0) (degrees in the
  deck; :mod:`moorjax.io.frames`). A ``fixed`` body's points are
  :class:`FixedEnd` s there. A ``coupled`` body's points hold that place unless
  the motion gives the body's 6-DOF pose (``B<n>_x ... B<n>_yaw``): then each
  point follows the full (not linearised) rigid-body transform of the sampled
  poses — exact at the sample times, velocities from the sampled rates when
  given — interpolated per point like a coupled point's path. ``free`` and
  ``coupledpinned`` bodies are refused (:func:`build_scene` says why and what to
  do instead); a body's mass, CG, inertia, volume, CdA and Ca are not used.

- Currents (``Currents`` 1, 2): the depth profile MoorDyn reads from
  ``current_profile.txt`` / ``current_profile_dynamic.txt`` becomes the
  environment's current; line drag acts on the velocity relative to it.
- Waves (``WaveKin`` 2, 3, 7): the components read from MoorDyn's wave files
  (:mod:`moorjax.io.waves`) become the environment's :class:`AiryWaves`, summed
  at the line nodes (drag on the velocity relative to current plus waves, and
  the water's acceleration) and free points (drag, as MoorDyn's Point, which
  leaves out the water's acceleration).

- ``SeafloorFile``: the bathymetry grid becomes the seabed's
  :class:`Bathymetry` (contact along the local seabed normal); the
  environment's depth is the deepest of WtrDpth and the grid.

Scene structure follows the deck: no drag / added mass terms when their
coefficients are all zero, no seabed term when every line is buoyant (wet weight < 0).
"""

from __future__ import annotations

import warnings

import numpy as np

from ..body.point import ConnectionPoint
from ..model import (
    AddedMass,
    AiryWaves,
    Bathymetry,
    BodyEnd,
    Environment,
    FixedEnd,
    GridAiryWaves,
    IrregularWave,
    Line,
    LinearEA,
    LineType,
    MorisonDrag,
    ProfileCurrent,
    Seabed,
    SeabedFriction,
    TabulatedEA,
    TabulatedPath,
    TimeProfileCurrent,
)
from ..model.scene import Scene
from .deck import Deck, DeckBody, DeckPoint, options_with_defaults
from .errors import InputError, InputWarning
from .frames import body_point_positions, body_point_velocities
from .motion import Motion, read_motion


def _axial(dt):
    if dt.ea_table is not None:
        strain, tension = zip(*dt.ea_table)
        return TabulatedEA(strain, tension)
    return LinearEA(dt.ea)


def _line_type(dt, length, n_segments):
    axial = _axial(dt)
    ba = dt.ba
    if ba < 0:
        ba = -ba * (length / n_segments) * np.sqrt(float(axial.nominal_ea()) * dt.mass_per_length)
    drag = MorisonDrag(dt.cd, dt.cd_axial) if (dt.cd > 0 or dt.cd_axial > 0) else None
    added = AddedMass(dt.ca, dt.ca_axial) if (dt.ca > 0 or dt.ca_axial > 0) else None
    ei = dt.ei if dt.ei > 0 else None  # EI = 0: no bending term is traced
    return LineType(dt.diameter, dt.mass_per_length, axial, ba, drag, added, ei=ei)


def coupled_point_ids(deck: Deck) -> list[int]:
    """Ids of the deck's coupled (caller-driven) points, in file order."""
    return [p.id for p in deck.points.values() if p.attachment == "coupled"]


def coupled_body_ids(deck: Deck) -> list[int]:
    """Ids of the deck's coupled (caller-driven, 6-DOF) bodies, in file order."""
    return [b.id for b in deck.bodies.values() if b.attachment == "coupled"]


def read_deck_motion(path, deck: Deck) -> Motion:
    """The motion file ``path`` read for all of the deck's coupled points and bodies."""
    return read_motion(path, coupled_point_ids(deck), coupled_body_ids(deck))


def _check_body_supported(deck: Deck, body: DeckBody) -> None:
    where = f"{deck.path}:{body.source_line}: BODIES id {body.id}"
    if body.attachment == "free":
        raise InputError(
            f"{where}: Attachment = free: a free body cannot be built from a MoorDyn deck yet: "
            "moorjax lacks MoorDyn's submerged 6-DOF body (weight at the CG and buoyancy rho*V*g "
            "at the reference point with their moments at any rotation, per-DOF drag "
            "0.5*rho*CdA*|v|v in body axes on the velocity relative to the water, added mass "
            "rho*V*Ca, and the inertia of the points and line ends fixed in it). "
            "moorjax's moving body, moorjax.body.RigidBody, is a floating (Cummins-form) body: it "
            "needs a hydrostatic restoring matrix with positive heave stiffness C[2,2] [N/m] and "
            "added mass [kg], which a deck does not carry (it gives Mass, CG, I, Volume, CdA, Ca "
            "only). Build it in Python instead: body = moorjax.body.RigidBody(mass, inertia, "
            "hydrostatic=C, added_mass=A, origin=<centre of gravity [m]>), end each line on "
            "moorjax.BodyEnd(0, <fairlead in body axes relative to the centre of gravity [m]>) and "
            "simulate moorjax.Scene(lines, env, bodies=[body]); read_deck(...).bodies and .points "
            "give the deck's values. Or make the body Fixed or Coupled in the deck."
        )
    if body.attachment == "coupled_pinned":
        raise InputError(
            f"{where}: Attachment = coupledpinned: bodies with a prescribed position and free "
            "rotation are not supported; make the body Coupled (whole pose prescribed) or Fixed"
        )


def _body_point_end(deck: Deck, point: DeckPoint, motion: Motion | None):
    body = deck.bodies[point.body]
    if body.attachment == "coupled" and motion is not None and body.id in motion.body_poses:
        poses = motion.body_poses[body.id]
        rates = motion.body_rates.get(body.id)
        r = body_point_positions(poses, point.position)
        v = None if rates is None else body_point_velocities(poses, rates, point.position)
        return TabulatedPath(motion.t, r, v)
    return FixedEnd(deck.point_position(point.id))


def body_reference_end(deck: Deck, body_id: int, motion: Motion | None = None):
    """Where body ``body_id``'s reference point (X0, Y0, Z0) is, as an end
    (:class:`FixedEnd`, or a :class:`TabulatedPath` for a coupled body the
    motion drives) — e.g. to take moments of line forces about it."""
    body = deck.bodies[body_id]
    if body.attachment == "coupled" and motion is not None and body.id in motion.body_poses:
        rates = motion.body_rates.get(body.id)
        poses = motion.body_poses[body.id]
        return TabulatedPath(motion.t, poses[:, :3], None if rates is None else rates[:, :3])
    return FixedEnd(body.position)


def build_scene(deck: Deck, segments: int | None = None, motion=None, element=None) -> Scene:
    """A :class:`Scene` from a deck.

    Args:
        deck: from :func:`moorjax.io.read_deck`.
        segments: overrides every line's segment count.
        motion: optional :class:`moorjax.io.Motion` driving coupled points and
            coupled bodies (read it with :func:`read_deck_motion`).
        element: the discretisation of every line (default: ``LinearElement()``).

    Raises:
        InputError: bad ``segments``, no water depth, or a body kind that cannot
            be built (``free``, ``coupledpinned``).
    """
    if segments is not None and (int(segments) != segments or segments < 1):
        raise InputError(f"--segments = {segments} must be an integer >= 1")
    opts = options_with_defaults(deck)
    depth, rho, g = float(opts["WtrDpth"]), float(opts["rho"]), float(opts["g"])
    if deck.seafloor is not None:  # the environment's depth is the deepest water
        depth = max(depth, -float(deck.seafloor.z.min()))
    if depth <= 0:
        raise InputError(f"{deck.path}: WtrDpth = {depth} m must be > 0")

    for body in deck.bodies.values():
        _check_body_supported(deck, body)
        if body.attachment == "coupled" and motion is not None and body.id not in motion.body_poses:
            warnings.warn(
                f"{deck.path}:{body.source_line}: BODIES id {body.id}: the motion {motion.path!r} was "
                f"read without body {body.id}; the coupled body holds its deck pose (read the motion "
                "with moorjax.io.read_deck_motion to drive it)",
                InputWarning,
                stacklevel=2,
            )

    free_ids = [p.id for p in deck.points.values() if p.attachment == "free"]
    ends = {}
    for p in deck.points.values():
        if p.attachment == "free":
            ends[p.id] = BodyEnd(free_ids.index(p.id), (0.0, 0.0, 0.0), p.position)
        elif p.body is not None:
            ends[p.id] = _body_point_end(deck, p, motion)
        elif p.attachment == "coupled" and motion is not None and p.id in motion.positions:
            ends[p.id] = TabulatedPath(motion.t, motion.positions[p.id], motion.velocities[p.id])
        else:
            ends[p.id] = FixedEnd(p.position)

    lines, weights = [], []
    for dl in deck.lines:
        n = int(segments) if segments is not None else dl.n_segments
        dt = deck.line_types[dl.line_type]
        lt = _line_type(dt, dl.length, n)
        weights.append(float(lt.wet_weight(rho, g)))
        lines.append(Line(lt, dl.length, n, ends[dl.point_a], ends[dl.point_b], element=element,
                          label=str(dl.id)))

    seabed = None
    # neutral lines (to rounding) can be pushed onto the seabed too
    if any(w >= -1e-6 * float(ln.line_type.mass_per_length) * g for w, ln in zip(weights, lines)):
        mu = float(opts.get("FrictionCoefficient") or 0.0)
        friction = SeabedFriction(mu) if mu > 0 else None
        bathymetry = None
        if deck.seafloor is not None:
            sf = deck.seafloor
            bathymetry = Bathymetry(sf.x, sf.y, sf.z)
        seabed = Seabed(float(opts["kBot"]), float(opts["cBot"]), friction, bathymetry)
    env = Environment(depth, rho, g, seabed=seabed, current=deck_current(deck),
                      waves=deck_waves(deck, float(opts["WtrDpth"]) or depth, g))
    points = [_free_point(deck, deck.points[i], lines, rho, g, env.current) for i in free_ids]
    return Scene(lines, env, bodies=points)


def _free_point(deck: Deck, p: DeckPoint, lines, rho: float, g: float, current) -> ConnectionPoint:
    """A deck's free point as a :class:`ConnectionPoint` (MoorDyn's Point).

    MoorDyn's point: weight M·g, buoyancy ρ·V·g, drag ½ρ·CdA·|u|u on the velocity
    u relative to the water and added mass Ca·ρ·V; its inertia also holds the
    end nodes of its lines (half an element's mass plus its added mass
    ρA·(l/2)·Ca). The lines' end forces carry the end nodes' weight and drag,
    so those end-node inertias go into ``added_mass`` (inertia only, no
    weight): ΣμL/2 + ρA(l/2)·Ca_n, the normal Ca taken for every direction.
    """
    added = p.ca * rho * p.volume
    for line, dl in zip(lines, deck.lines):
        for end in ("a", "b"):
            if getattr(dl, f"point_{end}") == p.id:
                lt = line.line_type
                half = 0.5 * float(line.segment_length)
                added += float(lt.mass_per_length) * half
                if lt.added_mass is not None:
                    added += rho * float(lt.area) * half * float(lt.added_mass.ca_normal)
    if not p.mass + added > 0:
        raise InputError(
            f"{deck.path}:{p.source_line}: POINTS id {p.id}: a free point with Mass = 0 kg, no "
            "added mass and no line attached has no inertia; give it a Mass [kg] or attach a line")
    return ConnectionPoint(p.mass, p.position, volume=p.volume, added_mass=added, cda=p.cda,
                           rho=rho, g=g, label=f"P{p.id}",
                           current=current if p.cda > 0 else None)


def deck_current(deck: Deck):
    """The deck's current as a moorjax current field, or ``None``.

    ``Currents = 1``: a :class:`ProfileCurrent` (linear in z, held beyond the
    ends, as MoorDyn's steady current grid); ``Currents = 2``: a
    :class:`TimeProfileCurrent` (linear in z and t, held beyond the ends).
    """
    cur = deck.current
    if cur is None:
        return None
    if cur.mode == 1:
        return ProfileCurrent(cur.z, cur.velocity)
    return TimeProfileCurrent(cur.t, cur.z, cur.velocity)


def deck_waves(deck: Deck, depth: float, g: float):
    """The deck's waves as :class:`AiryWaves` of water depth ``depth`` [m] (MoorDyn
    takes the wave numbers at ``WtrDpth``) and gravity ``g`` [m/s²], or ``None``."""
    w = deck.waves
    if w is None:
        return None
    if w.grid is not None:
        outside = [pid for pid in deck.points
                   if any(not (ax[0] - 1e-9 <= c <= ax[-1] + 1e-9)
                          for ax, c in zip(w.grid, deck.point_position(pid)[:2]) if ax.shape[0] > 1)]
        if outside:
            warnings.warn(
                f"{deck.path}: WaveKin = {w.mode}: points {outside} lie outside the x/y extent of "
                "water_grid.txt, where MoorDyn holds the kinematics at the grid's edge; moorjax sums the "
                "wave components at every node, so the two differ there (widen the grid to compare)",
                InputWarning, stacklevel=3)
    wave = IrregularWave(w.omega, w.amplitude, w.phase, w.heading)
    opts = options_with_defaults(deck)
    # MoorDyn's wave grids carry the current at the stretched height (UnifyCurrentGrid = 1)
    kind = GridAiryWaves if w.mode in (2, 3) and float(opts["UnifyCurrentGrid"]) == 1 else AiryWaves
    return kind(wave, depth, g, w.mean_level)
