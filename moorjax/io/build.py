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

- Currents (``Currents`` 1, 2, 5): the depth profile MoorDyn reads from
  ``current_profile.txt`` / ``current_profile_dynamic.txt``, or the 4-D grid
  of ``current_profile_4d.txt``, becomes the environment's current; the drag
  on lines, free points and bodies acts on the velocity relative to it.
- Waves (``WaveKin`` 2, 3, 7): the components read from MoorDyn's wave files
  (:mod:`moorjax.io.waves`) become the environment's :class:`AiryWaves`, summed
  at the line nodes (drag on the velocity relative to current plus waves, and
  the water's acceleration) and free points (drag, as MoorDyn's Point, which
  leaves out the water's acceleration).
- ``WaveKin = 1`` (MoorDyn's external kinematics, set through its API at run
  time): the ``waves`` argument of :func:`build_scene`, e.g. an
  :class:`~moorjax.model.ExternalWaves` of the user's function (the CLI's
  ``--wave-kinematics FILE.py:NAME``). Without one the water is still, as in
  MoorDyn before its first ``MoorDyn_ExternalWaveKinSet``, and an
  :class:`InputWarning` says so.

- ``SeafloorFile``: the bathymetry grid becomes the seabed's
  :class:`Bathymetry` (contact along the local seabed normal); the
  environment's depth is the deepest of WtrDpth and the grid.

Scene structure follows the deck: no drag / added mass terms when their
coefficients are all zero, no seabed term when every line is buoyant (wet weight < 0).
"""

from __future__ import annotations

import warnings

import equinox as eqx
import jax
import numpy as np

from ..body.point import ConnectionPoint
from ..body.submerged import SubmergedBody
from ..model import (
    AddedMass,
    AiryWaves,
    Bathymetry,
    BodyEnd,
    Environment,
    FixedEnd,
    GridAiryWaves,
    GridCurrent,
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


def build_scene(deck: Deck, segments: int | None = None, motion=None, element=None,
                waves=None) -> Scene:
    """A :class:`Scene` from a deck.

    Args:
        deck: from :func:`moorjax.io.read_deck`.
        segments: overrides every line's segment count.
        motion: optional :class:`moorjax.io.Motion` driving coupled points and
            coupled bodies (read it with :func:`read_deck_motion`).
        element: the discretisation of every line (default: ``LinearElement()``).
        waves: the water's kinematics of a ``WaveKin = 1`` deck (MoorDyn's
            external waves), an :class:`~moorjax.model.AbstractWaveKinematics`
            such as ``ExternalWaves(f)``; without it such a deck's water is
            still (with a warning). Decks with other ``WaveKin`` values take
            their waves from their files and refuse this argument.

    Raises:
        InputError: bad ``segments``, no water depth, a body kind that cannot
            be built (``coupledpinned``), or ``waves`` for a deck whose
            ``WaveKin`` is not 1.
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
    free_bodies = [b.id for b in deck.bodies.values() if b.attachment == "free"]
    ends = {}
    for p in deck.points.values():
        if p.attachment == "free":
            ends[p.id] = BodyEnd(free_ids.index(p.id), (0.0, 0.0, 0.0), p.position)
        elif p.body is not None and p.body in free_bodies:
            ends[p.id] = BodyEnd(len(free_ids) + free_bodies.index(p.body), p.position,
                                 deck.bodies[p.body].position)
        elif p.body is not None:
            ends[p.id] = _body_point_end(deck, p, motion)
        elif p.attachment == "coupled" and motion is not None and p.id in motion.positions:
            ends[p.id] = TabulatedPath(motion.t, motion.positions[p.id], motion.velocities[p.id])
        else:
            ends[p.id] = FixedEnd(p.position)

    lines, weights = [], []
    for dl in deck.lines:
        n = int(segments) if segments is not None else dl.n_segments
        if n < 2 and segments is not None:
            raise InputError(
                "--segments 1: a line of one segment has no free node; moorjax's line statics solve "
                "for the free nodes and its dynamic state would hold none; give --segments N >= 2")
        if n < 2:
            # MoorDyn makes a one-segment line a spring-damper between its ends, its mass
            # lumped half on each; moorjax needs a free node, so the deck's line is built
            # with two segments: the same line, its mass on three nodes (the middle one
            # free to sag), a finer discretisation of what the deck describes
            warnings.warn(
                f"{deck.path}:{dl.source_line}: LINES id {dl.id}: NumSegs = 1 is built with 2 segments "
                "(moorjax needs a free node; MoorDyn lumps the line's mass half on each end, moorjax "
                "puts half on the middle node, which may sag); give --segments to choose",
                InputWarning, stacklevel=2)
            n = 2
        dt = deck.line_types[dl.line_type]
        lt = _line_type(dt, dl.length, n)
        # on the host: the line type with NumPy leaves computes without XLA operations
        weights.append(float(jax.tree_util.tree_map(np.asarray, lt).wet_weight(rho, g)))
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
                      waves=_scene_waves(deck, waves, float(opts["WtrDpth"]) or depth, g))
    points = [_free_point(deck, deck.points[i], lines, rho, g, env.current) for i in free_ids]
    bodies = [_free_body(deck, deck.bodies[i], lines, rho, g, env.current) for i in free_bodies]
    return Scene(lines, env, bodies=points + bodies)


def _free_point(deck: Deck, p: DeckPoint, lines, rho: float, g: float, current) -> ConnectionPoint:
    """A deck's free point as a :class:`ConnectionPoint` (MoorDyn's Point).

    MoorDyn's point: weight M·g, buoyancy ρ·V·g, drag ½ρ·CdA·|u|u on the velocity
    u relative to the water and added mass Ca·ρ·V; its inertia also holds the
    end nodes of its lines (half an element's mass plus its added mass
    ρA·(l/2)·Ca). The lines' end forces carry the end nodes' weight and drag,
    so those end-node inertias go into ``added_mass`` (inertia only, no
    weight): ΣμL/2 + ρA(l/2)·Ca_n, the normal Ca taken for every direction —
    except for lines whose element carries its end inertia itself (Hermite).
    """
    added = p.ca * rho * p.volume
    for line, dl in zip(lines, deck.lines):
        if line.element.carries_end_inertia:  # the line's end forces hold it (Hermite)
            continue
        for end in ("a", "b"):
            if getattr(dl, f"point_{end}") == p.id:
                lt = line.line_type
                half = 0.5 * float(line.segment_length)
                added += float(lt.mass_per_length) * half
                if lt.added_mass is not None:
                    added += rho * float(lt.area) * half * float(lt.added_mass.ca_normal)
    ends = sum((dl.point_a == p.id) + (dl.point_b == p.id) for dl in deck.lines)
    if ends == 1 and p.mass == 0 and p.volume == 0:
        warnings.warn(
            f"{deck.path}:{p.source_line}: POINTS id {p.id}: a free point on one line end with no "
            "Mass or Volume is a free line end: it is in equilibrium only where the line's end "
            "force (its tension plus the end half-element's wet weight) vanishes, which a "
            "tension-only line reaches only hanging straight from it (a dry, heavy or a wet, "
            "buoyant end); elsewhere system statics cannot converge (and MoorDyn's relaxation "
            "need not settle)", InputWarning, stacklevel=3)
    if not p.mass + added > 0:
        raise InputError(
            f"{deck.path}:{p.source_line}: POINTS id {p.id}: a free point with Mass = 0 kg, no "
            "added mass and no line attached has no inertia; give it a Mass [kg] or attach a line")
    return ConnectionPoint(p.mass, p.position, volume=p.volume, added_mass=added, cda=p.cda,
                           rho=rho, g=g, label=f"P{p.id}",
                           current=current if p.cda > 0 else None)


def _end_node_inertia(deck: Deck, point_id: int, lines, rho: float) -> np.ndarray:
    """(3, 3) inertia [kg] of the end nodes of the lines on point ``point_id``:
    half an element's mass μ·l/2 and its added mass ρ·A·(l/2)·(Ca_n·(I − qqᵀ) +
    Ca_t·qqᵀ), q along the line's chord at the deck's geometry (MoorDyn takes the
    line's current end tangent)."""
    out = np.zeros((3, 3))
    for line, dl in zip(lines, deck.lines):
        if line.element.carries_end_inertia:  # the line's end forces hold it (Hermite)
            continue
        for end, other in (("a", dl.point_b), ("b", dl.point_a)):
            if getattr(dl, f"point_{end}") != point_id:
                continue
            # on the host (NumPy leaves): no XLA operation
            host = jax.tree_util.tree_map(lambda x: np.asarray(x) if eqx.is_array(x) else x, line)
            lt = host.line_type
            half = 0.5 * float(host.segment_length)
            out += float(lt.mass_per_length) * half * np.eye(3)
            if lt.added_mass is not None:
                chord = np.subtract(deck.point_position(other), deck.point_position(point_id))
                q = chord / max(np.linalg.norm(chord), 1e-300)
                qq = np.outer(q, q)
                ca_n, ca_t = float(lt.added_mass.ca_normal), float(lt.added_mass.ca_axial)
                out += rho * float(lt.area) * half * (ca_n * (np.eye(3) - qq) + ca_t * qq)
    return out


def _free_body(deck: Deck, body: DeckBody, lines, rho: float, g: float, current) -> SubmergedBody:
    """A deck's free body as a :class:`~moorjax.body.SubmergedBody` (MoorDyn's free Body).

    MoorDyn's body: Mass at CG with inertia I about it (body axes), weight and
    buoyancy ρ·V·g both at the CG, drag ½ρ·CdA·|u|u in body axes on the
    velocity relative to the water at the reference point, added mass ρ·V·Ca
    in translation. Its points add their Mass (weighed), Volume (buoyant) and
    Ca·ρ·V, and the end nodes of their lines (inertia only: the lines' end
    forces carry their weight). A point's own CdA on a body is not modelled
    (a warning says so).
    """
    where = f"{deck.path}:{body.source_line}: BODIES id {body.id}"
    pts = [p for p in deck.points.values() if p.body == body.id]
    for p in pts:
        if p.cda > 0:
            warnings.warn(f"{deck.path}:{p.source_line}: POINTS id {p.id}: CdA = {p.cda} m^2 of a "
                          f"point fixed in free body {body.id} is ignored (moorjax models the "
                          "body's own CdA only)", InputWarning, stacklevel=3)
    fixtures = (np.array([p.position for p in pts]).reshape(-1, 3),
                np.array([p.mass for p in pts]),
                np.array([p.volume for p in pts]),
                np.array([p.ca * rho * p.volume * np.eye(3) + _end_node_inertia(deck, p.id, lines, rho)
                          for p in pts]).reshape(-1, 3, 3))
    try:
        return SubmergedBody(body.mass, body.position, orientation=np.radians(body.orientation),
                             cg=body.cg, inertia=body.inertia, volume=body.volume, cda=body.cda,
                             ca=body.ca, fixtures=fixtures, rho=rho, g=g,
                             current=current if any(c > 0 for c in body.cda[:3]) else None,
                             label=f"B{body.id}")
    except ValueError as err:
        raise InputError(f"{where}: {err}") from None


def deck_current(deck: Deck):
    """The deck's current as a moorjax current field, or ``None``.

    ``Currents = 1``: a :class:`ProfileCurrent` (linear in z, held beyond the
    ends, as MoorDyn's steady current grid); ``Currents = 2``: a
    :class:`TimeProfileCurrent` (linear in z and t, held beyond the ends);
    ``Currents = 5``: a :class:`GridCurrent` (linear in x, y, z and t, held
    beyond the grid).
    """
    cur = deck.current
    if cur is None:
        return None
    if cur.mode == 1:
        return ProfileCurrent(cur.z, cur.velocity)
    if cur.mode == 5:
        return GridCurrent(cur.x, cur.y, cur.z, cur.t, cur.velocity)
    return TimeProfileCurrent(cur.t, cur.z, cur.velocity)


def _scene_waves(deck: Deck, waves, depth: float, g: float):
    """The environment's waves: the deck's own (``WaveKin`` 2, 3, 7), or for
    ``WaveKin = 1`` the external kinematics given to :func:`build_scene`."""
    mode = int(float(options_with_defaults(deck)["WaveKin"]))
    where = f"{deck.path}: OPTIONS: WaveKin = {mode}"
    if waves is not None:
        if mode != 1:
            raise InputError(
                f"{where}: external wave kinematics (--wave-kinematics, build_scene's waves) are "
                "MoorDyn's WaveKin = 1; this deck has its own wave setting, so set WaveKin to 1 in the "
                "deck to drive it from a function")
        return waves  # (Environment checks its type)
    if mode == 1:
        warnings.warn(
            f"{where}: the wave kinematics are external (MoorDyn sets them through its API at run "
            "time) and none were given, so the water is still, as in MoorDyn before the first "
            "MoorDyn_ExternalWaveKinSet; give them with --wave-kinematics FILE.py:FUNCTION or "
            "build_scene(..., waves=moorjax.model.ExternalWaves(f))",
            InputWarning, stacklevel=3)
        return None
    return deck_waves(deck, depth, g)


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
