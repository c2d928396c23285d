"""Wu et al.'s moored floating box (seed paper 003, Table 1), built as a scene.

A 45 m × 45 m × 27.5 m box, 20 m draft, 41,512 t, in 80 m of water, held by four
110 m lines of steel wire, chain or polyester (α = 2.5, β = 2.0). The paper's
Figure 3 (layout) is missing from the text and Table 1 leaves much open; every
input, its value and its source (a Table 1 line, an equation, or our assumption
and why) is listed in :data:`ASSUMPTIONS` (paper line numbers refer to the text
extraction ``seeds/003_*.txt``). The main readings:

Layout
    Fairleads at the four keel corners (±22.5, ±22.5, −20) m; each line runs
    outward along the corner's diagonal (line k at 45° + 90°·(k−1): lines 1–4 at
    45°, 135°, 225°, 315°). The environment pushes the box towards 30°, so line 3
    (anchor at 225°) is the weather-side line, the most loaded: the paper's
    "cable 3" (Fig. 5, lines 260–262) is taken to be this line (:data:`CABLE_3`).
Pretension
    "20 kN" is taken as the *horizontal* fairlead tension: a chain's top tension
    is at least its wet weight times the 60 m fairlead height (45 kN), so a 20 kN
    top tension is impossible for chain and steel wire. For each material the
    anchor radius is solved so that the horizontal tension at rest is 20 kN.
Polyester stiffness
    Wu's Eq. 15 as written, AE = RHOL·(α + β·T/MBL)·10⁶ with RHOL = 10.8 kg/m
    (Table 1's dry weight): AE = 2.7e7 N at rest and 4.86e7 N at MBL (AE/MBL
    10–18, an ordinary polyester rope). Table 1's "linearised stiffness 1.50E8"
    is reached by no reading of the units for 0 ≤ T ≤ MBL (kg/m gives 2.7–4.9e7,
    N/m gives 2.6–4.8e8); it is Eq. 15's small-tension value for a 60 kg/m rope,
    kept only as the labelled sensitivity variant ``"polyester_ae150"``
    (:data:`VARIANTS`), which strains 1 % at MBL and turns singular at 2.25 %.
Diameters
    Table 1 gives 0.12 m for all three; that is the volume-equivalent diameter of
    the chain (88.22 kg/m of steel: 0.1196 m, nominal 66.5 mm). A 0.12 m
    polyester line of 10.8 kg/m would float, while the paper has part of it on
    the seabed; we give it its volume-equivalent diameter at 1380 kg/m³
    (0.0998 m) and the steel wire 0.12 m as tabled.
Line coefficients
    Not given by the paper. Chain: the common studless values Cd = 2.4 (normal)
    and 1.15 (axial) refer to the *nominal* diameter d_n; on the volume-equivalent
    diameter d_ve ≈ 1.8·d_n that moorjax uses they become Cd·d_n/d_ve = 1.33 and
    0.64 (applying 2.4 on d_ve would be 1.8× too much drag). Steel wire and
    polyester: 1.2 / 0.008, added mass 1.0 (chain 1.0 / 0.5).
Environment
    Table 1's environmental values are maxima over the 100 cases. Base case:
    Hs = 2 m, Tz = 6 s (≤ the 60 s maximum), wind 13.8 m/s, all from 60°
    measured from the sway (y) axis, i.e. heading 30° from +x ("more close to
    surge", line 264). Current 1.2 m/s, chosen so that the polyester box's mean
    surge is near Fig. 10's focal point (about 3 m, line 280); the earlier guess
    0.4 m/s (:data:`CURRENT_GUESS`) is run beside it, and Table 1's 4 m/s
    (:data:`CURRENT_MAX`, 7.4 MN on the hull) only as a stress case.
Loads
    Wind (Eq. 2) with C_h = C_s = 1 on the 45 m × 7.5 m freeboard; current on the
    hull (Eq. 3) with C_D = 1.0 on 45 m × 20 m; the lines feel the current in
    their Morison drag. First-order wave forces and Newman slow drift from
    Capytaine coefficients; radiation memory by a fitted state-space model.
Inertia
    Table 1's moments of inertia are used as given, although their radii of
    gyration (33.0, 32.1, 34.3 m) exceed the box's half-diagonals (26.4 m in the
    vertical planes, 31.8 m in plan); a uniform box has 15.2, 15.2, 18.4 m.
"""

from __future__ import annotations

import functools
from importlib import resources

import numpy as np

from .. import model as mj
from ..body import RigidBody
from ..body.hydro import fit_radiation, load_hydro
from ..body.loads import ConstantLoad, current_force, directional_load, wind_force
from ..body.waves import wave_loads

LENGTH, WIDTH, HEIGHT, DRAFT = 45.0, 45.0, 27.5, 20.0
MASS = 41_512e3  # [kg]
INERTIA = (4.5316e10, 4.2748e10, 4.8877e10)  # [kg·m²]
ZG = -DRAFT + HEIGHT / 2  # centre of gravity [m]
DEPTH, RHO, G = 80.0, 1025.0, 9.81  # g as in the hydrodynamic coefficients
LINE_LENGTH = 110.0
PRETENSION_H = 20e3  # horizontal fairlead tension at rest [N]
HEADING = np.radians(30.0)  # 60° from the sway axis
WIND, HS, TZ = 13.8, 2.0, 6.0  # [m/s], [m], [s]
CURRENT = 1.2  # [m/s] mean polyester surge near Fig. 10's 3 m focal point
CURRENT_GUESS = 0.4  # [m/s] the earlier guess, run beside CURRENT
CURRENT_MAX = 4.0  # [m/s] Table 1's maximum: a stress case only
TZ_MAX = 60.0  # [s] Table 1's maximum zero-crossing period
CABLE_3 = 2  # 0-based index of the paper's "cable 3": line "3", anchor at 225°, weather side

#: chain: volume-equivalent over nominal diameter (studless, MoorDyn/OrcaFlex convention)
CHAIN_DVE_OVER_DN = 1.8
#: studless-chain drag on the nominal diameter (normal, axial) [-]
CHAIN_CD_NOMINAL = (2.4, 1.15)

#: Table 1 line data plus the choices above. ``rhol`` is Eq. 15's RHOL [kg/m];
#: Cd/Ca refer to ``diameter`` (the volume-equivalent one for chain).
MATERIALS = {
    "steel": dict(diameter=0.12, mass=70.37, ea=1.36e8, mbl=7.25e6, cd=(1.2, 0.008), ca=(1.0, 0.0)),
    "chain": dict(diameter=0.12, mass=88.22, ea=3.06e8, mbl=2.155e6,
                  cd=tuple(c / CHAIN_DVE_OVER_DN for c in CHAIN_CD_NOMINAL), ca=(1.0, 0.5)),
    "polyester": dict(diameter=0.0998, mass=10.8, rhol=10.8, mbl=2.70e6, cd=(1.2, 0.008),
                      ca=(1.0, 0.0), alpha=2.5, beta=2.0),
}
#: sensitivity variants (not the paper's equations as written)
VARIANTS = {
    # Eq. 15 scaled so that AE(0) is Table 1's "linearised 1.50E8": RHOL = 60 kg/m
    "polyester_ae150": dict(MATERIALS["polyester"], rhol=1.5e8 / (2.5 * 1e6)),
    # chain with Cd = 2.4 / 1.15 applied on the volume-equivalent diameter (1.8x the drag)
    "chain_cd_on_dve": dict(MATERIALS["chain"], cd=CHAIN_CD_NOMINAL),
}


#: One row per input: (input, value, source). "Lnnn" is a line of the paper's text
#: extraction; "ours" marks an assumption, with the reason.
ASSUMPTIONS = (
    ("box length × width × height", "45 × 45 × 27.5 m", "Table 1, L229–231"),
    ("draft", "20 m", "Table 1, L232"),
    ("mass", "41,512 t", "Table 1, L233"),
    ("Ixx, Iyy, Izz", "4.5316e10, 4.2748e10, 4.8877e10 kg·m²",
     "Table 1, L234–236, used as given; radii of gyration 33.0/32.1/34.3 m exceed the "
     "half-diagonals (26.4 m vertical planes, 31.8 m plan): not physical for a 45 m box"),
    ("centre of gravity", "mid-height, z = −6.25 m", "ours: not given; the reference point of "
     "the Capytaine coefficients"),
    ("water density, depth", "1025 kg/m³, 80 m", "Table 1, L237–238"),
    ("hydrodynamics", "Capytaine A(ω), B(ω), excitation, Newman drift; radiation memory by "
     "a 6th-order state-space fit", "Eq. 1 (L35), L56 (the paper uses a full QTF: ours is "
     "Newman's approximation)"),
    ("wave spectrum", "Pierson–Moskowitz, 100 random components", "Eq. 4 (L60); the number "
     "of components is ours"),
    ("Hs", "2 m (base); uniformity draws 1–2 m", "Table 1 L240: maximum"),
    ("Tz", "6 s (base); uniformity draws 4–10 s", "Table 1 L239 gives 60 s as the maximum; "
     "ours: a 2 m sea with a 6 s period, kept within the maximum"),
    ("wind speed", "13.8 m/s (base); uniformity draws 6.9–13.8 m/s", "Table 1 L242: maximum"),
    ("wind force", "Eq. 2 with C_h = C_s = 1, A = 45 × 7.5 m, ρ_air = 1.225",
     "Eq. 2 (L46); coefficients and area ours (OCIMF values not given, L220)"),
    ("current speed", "1.2 m/s (base), 0.4 m/s (run beside), 4 m/s (stress case only); "
     "uniformity draws 0.6–1.2 m/s",
     "Table 1 L241 gives 4 m/s as the maximum (7.4 MN on the hull); ours: 1.2 m/s puts the "
     "polyester box's mean surge near Fig. 10's focal point of 3 m (L280)"),
    ("current force", "Eq. 3 with C_D = 1.0, A = 45 × 20 m; lines feel it in Morison drag",
     "Eq. 3 (L52); coefficient and area ours"),
    ("direction", "60° from the sway axis = heading 30° from +x (all loads); uniformity ±30°",
     "Table 1 L243; 'more close to surge direction' (L264)"),
    ("layout", "fairleads at the keel corners, lines along the diagonals at 45°+90°k",
     "ours: Fig. 3 (L214) missing"),
    ("cable 3", "line 3, anchor at 225°: the weather-side line", "Fig. 5 caption (L260), claims "
     "L262; ours: the most loaded line under heading 30°"),
    ("pretension", "20 kN horizontal at the fairlead, anchor radius solved per material",
     "Table 1 L244; ours: 20 kN top tension is impossible for chain (45 kN suspended weight)"),
    ("line length", "110 m (sweep 106–116 m, anchors fixed)", "Table 1 L246; Fig. 4 (L252)"),
    ("diameter", "0.12 m steel; 0.12 m chain (= its volume-equivalent diameter); "
     "0.0998 m polyester", "Table 1 L247; ours for polyester: 0.12 m at 10.8 kg/m would "
     "float, the paper has it on the seabed (L252)"),
    ("MBL", "steel 7.25e6, chain 2.155e6, polyester 2.70e6 N", "Table 1 L248"),
    ("dry mass", "steel 70.37, chain 88.22, polyester 10.8 kg/m", "Table 1 L249"),
    ("EA steel, chain", "1.36e8, 3.06e8 N", "Table 1 L250"),
    ("AE polyester", "Eq. 15: 10.8e6·(2.5 + 2·T/MBL) N (2.7e7 at rest, 4.86e7 at MBL)",
     "Eq. 15 (L125) with RHOL = Table 1's 10.8 kg/m (L249), α, β (L250); Table 1's "
     "'linearised 1.50E8' only as the sensitivity variant polyester_ae150"),
    ("strain", "ε = T/AE (no pressure term)", "Eq. 13–14 with ν = 0.5 (L113–121)"),
    ("Eq. 15 beyond its singular strain", "continued linearly beyond 0.9·ε* (ε* = 12.5 %)",
     "ours (moorjax PolyesterWu); not reached in these runs"),
    ("line drag, added mass", "steel/polyester Cd 1.2/0.008, Ca 1.0/0; chain Cd 1.33/0.64 "
     "(= 2.4/1.15 on nominal d × d_n/d_ve), Ca 1.0/0.5",
     "ours: C_D, C_A named in Eq. 21/26 (L163) without values; chain converted from the "
     "nominal to the volume-equivalent diameter (d_ve ≈ 1.8 d_n)"),
    ("seabed", "vertical spring–damper 3e6 Pa/m, 3e5 Pa·s/m, no friction", "ours (moorjax "
     "default); the paper only says the grounded part's weight is carried (L252)"),
    ("element", "linear (lumped-mass) segments", "the paper uses Hermite shape functions "
     "(L163); moorjax's HermiteElement runs the same box (benchmarks/wu_hermite_check.py: polyester, "
     "60 s from rest, cable-3 maximum 2038.0 kN with 8 Hermite elements against 2054.7 kN and "
     "2046.1 kN with 8 and 16 linear segments)"),
    ("time integration", "Kvaerno3, adaptive, rtol 1e-3, atol 1 cm", "ours; the paper uses "
     "Newmark-like Newton steps (Eq. 33–41)"),
    ("start", "both: from rest (unloaded equilibrium, loads switched on at t = 0) and from "
     "the loaded equilibrium", "'fastest rate of decay' (L262), 'damping decay' (L280) "
     "suggest a start from rest"),
)

HYDRO_FILE = "wu_box_hydro.npz"


def hydro_path() -> str:
    return str(resources.files("moorjax.examples").joinpath("data", HYDRO_FILE))


@functools.lru_cache(maxsize=1)
def _default_coeffs():
    return load_hydro(hydro_path())


@functools.lru_cache(maxsize=4)
def _default_radiation(order):
    return fit_radiation(_default_coeffs(), order=order)[0]


def line_type(material: str) -> mj.LineType:
    """The line section of ``material`` ('steel', 'chain', 'polyester' or a :data:`VARIANTS` key)."""
    known = {**MATERIALS, **VARIANTS}
    if material not in known:
        raise ValueError(f"unknown material {material!r}; choose one of {', '.join(known)}")
    p = known[material]
    if "rhol" in p:  # Eq. 15, AE = RHOL·(α + β·T/MBL)·10⁶
        axial = mj.PolyesterWu(p["rhol"], p["alpha"], p["beta"], p["mbl"])
    else:
        axial = p["ea"]
    return mj.LineType(p["diameter"], p["mass"], axial, drag=mj.MorisonDrag(*p["cd"]),
                       added_mass=mj.AddedMass(*p["ca"]), mbl=p["mbl"])


def fairleads() -> np.ndarray:
    """(4, 3) fairleads in body axes (about the centre of gravity) [m]."""
    s = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], float)
    return np.column_stack([s * LENGTH / 2, np.full(4, -DRAFT - ZG)])


def directions() -> np.ndarray:
    """(4, 2) unit horizontal directions of the lines, fairlead → anchor."""
    return fairleads()[:, :2] / np.linalg.norm(fairleads()[:, :2], axis=1, keepdims=True)


@functools.lru_cache(maxsize=32)
def anchor_radius(material: str, length: float = LINE_LENGTH, n_segments: int = 10,
                  pretension: float = PRETENSION_H) -> float:
    """Horizontal fairlead-to-anchor distance [m] giving ``pretension`` (horizontal) at rest."""
    from ..statics import solve_line_statics

    lt = line_type(material)
    env = environment(current=False)
    fl = np.array([0.0, 0.0, ZG + (-DRAFT - ZG)])

    def horizontal(x):
        line = mj.Line(lt, length, n_segments, mj.FixedEnd([x, 0.0, -DEPTH]), mj.FixedEnd(fl))
        st = solve_line_statics(line, env, throw=False)
        # a very slack line (much of it on the seabed) may not converge: its
        # horizontal tension is then far below any pretension of interest
        return float(np.hypot(st.force_b[0], st.force_b[1])) if bool(st.converged) else 0.0

    # the horizontal tension rises monotonically with x: bracket, then bisect
    h = DEPTH + fl[2]
    chord = np.sqrt(length**2 - h**2)
    lo, hi = 0.6 * chord, chord * 1.001
    while horizontal(hi) < pretension and hi < 1.3 * length:
        hi *= 1.001
    if horizontal(lo) > pretension or horizontal(hi) < pretension:
        raise RuntimeError(f"{material}: no anchor radius gives {pretension:g} N horizontal pretension")
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if horizontal(mid) < pretension:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-7 * chord:
            return float(0.5 * (lo + hi))
    raise RuntimeError(f"{material}: no anchor radius gives {pretension:g} N horizontal pretension")


def environment(current: bool = True, current_speed: float = CURRENT, heading: float = HEADING) -> mj.Environment:
    cur = (mj.UniformCurrent([current_speed * np.cos(heading), current_speed * np.sin(heading), 0.0])
           if current and current_speed > 0 else None)
    return mj.Environment(DEPTH, RHO, G, seabed=mj.Seabed(), current=cur)


def body(*, hs=HS, tz=TZ, wind=WIND, current=CURRENT, heading=HEADING, seed=0,
         n_components=100, radiation=True, waves=True, drift=True, coeffs=None, radiation_order=6):
    """The box as a :class:`RigidBody` with its environmental loads."""
    coeffs = _default_coeffs() if coeffs is None else coeffs
    loads = []
    steady = 0.0
    if wind > 0:
        steady = steady + wind_force(wind, 1.0, 1.0, LENGTH * (HEIGHT - DRAFT))
    if current > 0:
        steady = steady + current_force(current, 1.0, WIDTH * DRAFT, RHO)
    if wind > 0 or current > 0:
        loads.append(ConstantLoad(directional_load(steady, heading)))
    if waves and hs > 0:
        loads.append(wave_loads(coeffs, hs, tz, heading, n_components=n_components, seed=seed,
                                drift=drift))
    if not radiation:
        rad = None
    elif coeffs is _default_coeffs():
        rad = _default_radiation(radiation_order)
    else:
        rad = fit_radiation(coeffs, order=radiation_order)[0]
    return RigidBody(MASS, INERTIA, added_mass=coeffs.added_mass_inf, hydrostatic=coeffs.hydrostatic,
                     origin=(0.0, 0.0, ZG), radiation=rad, loads=tuple(loads),
                     half_size=(LENGTH / 2, WIDTH / 2, HEIGHT / 2), label="box")


def scene(material: str = "polyester", *, length: float = LINE_LENGTH, radius: float | None = None,
          n_segments: int = 10, current_on_lines: bool = True, **body_kw) -> mj.Scene:
    """The moored box with four lines of ``material``.

    Args:
        material: 'steel', 'chain' or 'polyester'.
        length: unstretched line length [m] (the anchors stay where the
            110 m lines have 20 kN horizontal pretension unless ``radius`` is given).
        radius: horizontal fairlead-to-anchor distance [m] (default: solved).
        n_segments: elements per line.
        body_kw: passed to :func:`body` (hs, tz, wind, current, heading, seed, …).
    """
    radius = anchor_radius(material) if radius is None else float(radius)
    lt = line_type(material)
    lines = []
    for k, (fl, d) in enumerate(zip(fairleads(), directions())):
        anchor = np.array([fl[0] + radius * d[0], fl[1] + radius * d[1], -DEPTH])
        lines.append(mj.Line(lt, length, n_segments, mj.FixedEnd(anchor), mj.BodyEnd(0, fl),
                             label=str(k + 1)))
    cur = body_kw.get("current", CURRENT)
    env = environment(current=current_on_lines and cur > 0, current_speed=cur,
                      heading=body_kw.get("heading", HEADING))
    return mj.Scene(lines, env, bodies=[body(**body_kw)])


def start_state(scene: mj.Scene, start: str = "equilibrium", *, throw: bool = True):
    """Static solution and solver-ready initial state of ``scene``.

    Args:
        start: ``"equilibrium"``: the loaded equilibrium (mean wind, current and
            drift), at rest; ``"rest"``: the equilibrium without the body's loads
            (the lines in their static shape), at rest, so that the loads act
            suddenly at t = 0, as the paper's decaying histories suggest (L262, L280).
        throw: raise if the statics do not converge (else start where they stopped).

    Returns:
        ``(statics, init)`` with ``init`` the line states followed by the body state.
    """
    from ..statics import solve_system_statics

    if start not in ("equilibrium", "rest"):
        raise ValueError(f"start must be 'equilibrium' or 'rest', not {start!r}")
    st = solve_system_statics(scene, loads=start == "equilibrium", throw=throw)
    return st, st.state() + st.body_states(scene)
