"""The records a deck is read into: line types, points, bodies, lines, the deck.

Plain frozen dataclasses of validated numbers in SI units (m, kg, N, s; angles
as written, in degrees, where noted). Pure Python; no JAX.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..currents import DeckCurrent
from ..waves import DeckWaves
from ..frames import body_point_positions
from ..seafloor import DeckSeafloor


@dataclass(frozen=True)
class DeckLineType:
    """One row of ``LINE TYPES``: physical properties of a line.

    Attributes:
        name: type name used by ``LINES`` rows.
        diameter: volume-equivalent diameter [m] (buoyancy, drag, added mass).
        mass_per_length: mass per unit unstretched length, in air [kg/m].
        ea: axial stiffness EA [N]; ``None`` when tabulated (see ``ea_table``).
        ea_table: ``((strain [-], tension [N]), ...)`` with strictly increasing
            strain and non-negative tension, read from the file named in the EA
            column (path relative to the deck's folder); ``None`` for a scalar EA.
        ba: internal axial damping [N·s] if >= 0; if negative it is ``-zeta``,
            the damping as a fraction of critical (MoorDyn convention), kept as
            given.
        ei: bending stiffness [N·m²] (> 0: bending stiffness of the line, see LineType.ei).
        cd: transverse drag coefficient [-], w.r.t. frontal area d·l.
        ca: transverse added-mass coefficient [-].
        cd_axial: tangential drag coefficient [-], w.r.t. surface area π·d·l.
        ca_axial: tangential added-mass coefficient [-].
        source_line: 1-based line number of the row in the deck.
    """

    name: str
    diameter: float
    mass_per_length: float
    ea: float | None
    ea_table: tuple[tuple[float, float], ...] | None
    ba: float
    ei: float
    cd: float
    ca: float
    cd_axial: float
    ca_axial: float
    source_line: int


@dataclass(frozen=True)
class DeckPoint:
    """One row of ``POINTS``: a line end held fixed, driven by the caller, free, or fixed in a body.

    Attributes:
        id: point number (1, 2, 3, ... in file order).
        attachment: ``'fixed'`` (Fixed/Anchor/Fix), ``'coupled'``
            (Coupled/Vessel/Ves/Cpld/Fairlead), ``'free'`` (Free/Point/
            Connect/Con: a point mass moved by its lines and loads; its
            position is the initial guess) or ``'body'`` (Body<n>).
        position: (x, y, z) [m], global frame; for coupled points the initial
            position; for body points the position in the body's axes relative
            to its reference point (X0, Y0, Z0) (see :meth:`Deck.point_position`
            for the global one).
        mass: point mass [kg].
        volume: displaced volume [m³].
        cda: drag coefficient times area [m²].
        ca: added-mass coefficient [-].
        source_line: 1-based line number of the row in the deck.
        body: id of the body a ``'body'`` point is fixed in, else ``None``.
    """

    id: int
    attachment: str
    position: tuple[float, float, float]
    mass: float
    volume: float
    cda: float
    ca: float
    source_line: int
    body: int | None = None


@dataclass(frozen=True)
class DeckBody:
    """One row of ``BODIES``: a rigid body that points (and so lines) are fixed in.

    Attributes:
        id: body number (1, 2, 3, ... in file order).
        attachment: ``'fixed'`` (Fixed/Fix/Anchor), ``'coupled'``
            (Coupled/Vessel/Ves/Cpld: pose driven by the caller), ``'free'``
            (Free: moved by its loads) or ``'coupled_pinned'``
            (CoupledPinned/VesselPinned/VesPin/CpldPin: position driven,
            rotation free).
        position: (X0, Y0, Z0) [m], the body reference point in the global
            frame (initial position of a coupled body).
        orientation: (r0, p0, y0) roll, pitch, yaw [deg] as written; the body
            axes are R = Rx(r0)·Ry(p0)·Rz(y0) (see :mod:`moorjax.io.frames`).
        mass: body mass [kg] (without attached points and rods).
        cg: (x, y, z) centre of gravity in body axes [m] (one value in the
            deck is z, x = y = 0).
        inertia: (Ixx, Iyy, Izz) [kg·m²] (one value in the deck is all three).
        volume: displaced volume [m³].
        cda: (6,) drag coefficient × area per degree of freedom, x, y, z then
            the three rotations [m²]: one value in the deck is all six, two
            are translation|rotation, three are x|y|z for both, or six.
        ca: (3,) added-mass coefficients [-] (one value is all three).
        source_line: 1-based line number of the row in the deck.

    Mass, CG, inertia, volume, CdA and Ca only matter to free bodies; MoorDyn
    ignores them for fixed and coupled ones, and so does moorjax.
    """

    id: int
    attachment: str
    position: tuple[float, float, float]
    orientation: tuple[float, float, float]
    mass: float
    cg: tuple[float, float, float]
    inertia: tuple[float, float, float]
    volume: float
    cda: tuple[float, float, float, float, float, float]
    ca: tuple[float, float, float]
    source_line: int

    def pose(self) -> tuple[float, ...]:
        """(6,) pose x, y, z [m], roll, pitch, yaw [rad] (the deck's r0, p0, y0 in radians)."""
        return (*self.position, *(math.radians(a) for a in self.orientation))


@dataclass(frozen=True)
class DeckLine:
    """One row of ``LINES``: a mooring line between two points.

    Attributes:
        id: line number (1, 2, 3, ... in file order).
        line_type: name of a :class:`DeckLineType`.
        point_a: id of the point at end A (anchor end, node 0).
        point_b: id of the point at end B (fairlead end, node N).
        length: unstretched length [m].
        n_segments: number of segments [-] (N + 1 nodes).
        outputs: MoorDyn line-output flags as written (``'-'`` for none).
        source_line: 1-based line number of the row in the deck.
    """

    id: int
    line_type: str
    point_a: int
    point_b: int
    length: float
    n_segments: int
    outputs: str
    source_line: int


@dataclass(frozen=True)
class Deck:
    """A parsed, validated MoorDyn v2 deck.

    Attributes:
        path: the file the deck came from (``'<string>'`` for :func:`parse_deck`
            without a path).
        title: the free text before the first section (lines joined by ``\\n``).
        line_types: type name -> :class:`DeckLineType`, in file order.
        points: point id -> :class:`DeckPoint`, in file order.
        lines: the :class:`DeckLine` rows, in file order.
        options: the ``OPTIONS`` given in the file, keyed by MoorDyn's canonical
            name (``'dtM'``, ``'tScheme'``, ``'g'`` [m/s²], ``'rho'`` [kg/m³],
            ``'WtrDpth'`` [m], ``'kBot'`` [Pa/m], ``'cBot'`` [Pa·s/m],
            ``'FrictionCoefficient'`` [-], ...; aliases such as ``kb``,
            ``rhoW``, ``ICthresh`` are mapped to them, names are matched
            case-insensitively).  Numbers are ``float``; ``tScheme`` is
            lower-cased text.  Unknown names are kept as written (float if
            numeric, else text) with a warning.  Missing options are *not*
            filled in: see :func:`options_with_defaults`.
        warnings: human-readable warnings (each also emitted with
            :func:`warnings.warn` as :class:`~moorjax.io.errors.InputWarning`).
        bodies: body id -> :class:`DeckBody`, in file order (empty without a
            ``BODIES`` section).
        current: the current of a deck with ``Currents`` 1, 2 or 5, read from
            the file MoorDyn-C reads next to the deck
            (:mod:`moorjax.io.currents`); ``None`` without currents.
        seafloor: the bathymetry grid of a deck with ``SeafloorFile``
            (:mod:`moorjax.io.seafloor`); ``None`` for a flat seabed.
        waves: the wave components of a deck with ``WaveKin`` 2, 3 or 7, read
            from the files MoorDyn-C reads next to the deck
            (:mod:`moorjax.io.waves`); ``None`` without waves.
    """

    path: str
    title: str
    line_types: dict[str, DeckLineType]
    points: dict[int, DeckPoint]
    lines: tuple[DeckLine, ...]
    options: dict[str, float | str]
    warnings: tuple[str, ...]
    bodies: dict[int, DeckBody] = field(default_factory=dict)
    current: DeckCurrent | None = None
    seafloor: DeckSeafloor | None = None
    waves: DeckWaves | None = None

    def point_position(self, point_id: int) -> tuple[float, float, float]:
        """Global position [m] of a point at the deck's initial poses (body
        points transformed by their body's X0..y0)."""
        p = self.points[point_id]
        if p.body is None:
            return p.position
        x, y, z = body_point_positions(self.bodies[p.body].pose(), p.position)
        return (float(x), float(y), float(z))
