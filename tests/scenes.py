"""Scenes shared by the tests (import with ``from scenes import ...``).

* ``case_b_*``: case B of the validation set, a 110 m line (d = 0.12 m,
  10.8 kg/m, EA = 150 MN) from an anchor 80 m deep to a fairlead near the
  surface (taut, goes slack and snaps when the fairlead surges 2 m);
* ``hermite_case_a``: case A (the OC3-like chain catenary, ``tests/data/case_A.dat``)
  with Hermite elements, its fairlead surging 5 m over 10 s;
* ``polyester_scene``: the same geometry with a polyester rope whose stiffness
  grows with the mean load (MBL-normalised EA(T)), for the identification and
  gradient tests.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import equinox as eqx
import numpy as np

import moorjax as mj

DATA = Path(__file__).parent / "data"

CASE_B_ANCHOR = (-80.5168, 0.0, -80.0)  # [m]

#: the polyester's MBL-normalised stiffness (α, β) and drag coefficients
POLY_TRUE = dict(alpha=18.5, beta=33.0, Cd_normal=1.6, Cd_axial=0.1)


def case_b_line_type(ea=1.5e8, cd=1.6, drag=True):
    """Case B's line type: d 0.12 m, 10.8 kg/m, EA ``ea`` [N], BA 1.771e5 N·s,
    Cd ``cd``/0.05 (none with ``drag=False``), Ca 1/0."""
    return mj.LineType(0.12, 10.8, ea, 1.771e5, mj.MorisonDrag(cd, 0.05) if drag else None,
                       mj.AddedMass(1.0, 0.0))


def case_b_scene(n=8, end_b=None, line_type=None):
    """Case B: 110 m of ``line_type`` (default :func:`case_b_line_type`) in ``n``
    segments, 80 m of water with a seabed, fairlead ``end_b`` (default: surging
    2 m around (0, 0, -5) m with an 8 s period)."""
    lt = case_b_line_type() if line_type is None else line_type
    env = mj.Environment(80.0, seabed=mj.Seabed(3e6, 3e5))
    end_b = end_b if end_b is not None else mj.SinePath([0, 0, -5.0], [2.0, 0, 0], 8.0)
    line = mj.Line(lt, 110.0, n, mj.FixedEnd(list(CASE_B_ANCHOR)), end_b)
    return mj.Scene([line], env)


def polyester_scene(centre=(0.0, 0.0, -5.0), amplitude=(0.5, 0.0, 0.0), period=4.0,
                    phase=np.pi / 2, length=109.5, current=(0.0, 0.0, 0.0), n=8, **values):
    """A polyester line (d = 0.12 m, 15.6 kg/m, MBL 7.5 MN) with the MBL-normalised
    load-dependent stiffness EA(T) = MBL·(α + β·T/MBL), between a point 20 m above
    the seabed and a fairlead on a sine path (starting at rest: phase π/2). With the
    default length and centre (case B geometry) it is taut, pretension ≈ 10 % MBL.
    ``values`` override :data:`POLY_TRUE`."""
    v = dict(POLY_TRUE, **values)
    law = mj.PolyesterMBL(7.5e6, v["alpha"], v["beta"])
    lt = mj.LineType(0.12, 15.6, law, 1.771e5, mj.MorisonDrag(v["Cd_normal"], v["Cd_axial"]),
                     mj.AddedMass(1.0, 0.1))
    env = mj.Environment(100.0, seabed=mj.Seabed(3e6, 3e5), current=mj.UniformCurrent(current))
    end_b = mj.SinePath(list(centre), list(amplitude), period, phase)
    line = mj.Line(lt, length, n, mj.FixedEnd(list(CASE_B_ANCHOR)), end_b)
    return mj.Scene([line], env)


def hermite_case_a(n, motion=True, element=None):
    """Case A's deck at ``n`` elements of ``element`` (default ``HermiteElement()``),
    the fairlead on its 5 m / 10 s surge (``motion``) or held."""
    from moorjax.element import HermiteElement
    from moorjax.io import build_scene, read_deck

    element = HermiteElement() if element is None else element
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = build_scene(read_deck(DATA / "case_A.dat"), segments=n, element=element)
    if motion:
        path = mj.SinePath([-5.2, 0.0, -70.0], [5.0, 0.0, 0.0], 10.0)
        scene = eqx.tree_at(lambda s: s.lines[0].end_b, scene, path)
    return scene
