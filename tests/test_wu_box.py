"""The Wu et al. example box: its inputs read from the paper (Eq. 15 as written,
chain drag on the right diameter, cable 3 on the weather side), pretension, and the
static offset behaviour the paper reports (polyester hardens relative to steel wire)."""

from __future__ import annotations

import numpy as np
import pytest

from moorjax.examples import wu_box as wu
from moorjax.statics import offset_curve, solve_line_statics

pytestmark = pytest.mark.slow  # long physics/compile checks: CI runs them, `-m "not slow"` skips


def _axial_stiffness_at(law, tension):
    """Secant AE = T/ε at the strain where the law gives ``tension`` (bisection)."""
    lo, hi = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if float(law.tension(mid)) < tension else (lo, mid)
    return tension / (0.5 * (lo + hi))


def test_polyester_stiffness_is_eq15_with_table1_dry_weight():
    # Eq. 15: AE = RHOL·(α + β·T/MBL)·10⁶ with RHOL = 10.8 kg/m, α = 2.5, β = 2.0
    law = wu.line_type("polyester").axial
    mbl = wu.MATERIALS["polyester"]["mbl"]
    assert float(law.nominal_ea()) == pytest.approx(10.8e6 * 2.5)
    for t in (0.2 * mbl, mbl):
        assert _axial_stiffness_at(law, t) == pytest.approx(10.8e6 * (2.5 + 2.0 * t / mbl), rel=1e-6)
    # the strain at MBL is that of an ordinary polyester rope, far from Eq. 15's singularity
    assert mbl / _axial_stiffness_at(law, mbl) == pytest.approx(2.7e6 / 4.86e7, rel=1e-6)


def test_linearised_stiffness_is_only_a_variant():
    law = wu.line_type("polyester_ae150").axial
    assert float(law.nominal_ea()) == pytest.approx(1.5e8)
    assert "polyester_ae150" not in wu.MATERIALS


def test_chain_drag_converted_to_volume_equivalent_diameter():
    # drag per unit length, Cd·d, is the nominal-diameter value 2.4·d_n with d_n = d_ve/1.8
    lt = wu.line_type("chain")
    d_ve = float(lt.diameter)
    d_n = d_ve / wu.CHAIN_DVE_OVER_DN
    assert float(lt.drag.cd_normal) * d_ve == pytest.approx(2.4 * d_n)
    assert float(lt.drag.cd_axial) * d_ve == pytest.approx(1.15 * d_n)
    # 0.12 m is the chain's volume-equivalent diameter: 88.22 kg/m of steel (7850 kg/m³)
    assert d_ve == pytest.approx(np.sqrt(4 * 88.22 / 7850 / np.pi), rel=0.01)
    # studless chain of that nominal diameter weighs 0.0199·d² kg/m (d in mm)
    assert 0.0199 * (1e3 * d_n) ** 2 == pytest.approx(88.22, rel=0.02)


def test_cable_3_is_the_weather_side_line():
    # the environment pushes the box towards HEADING; the line whose anchor lies
    # opposite is stretched most: the paper's cable 3
    push = np.array([np.cos(wu.HEADING), np.sin(wu.HEADING)])
    assert int(np.argmin(wu.directions() @ push)) == wu.CABLE_3
    sc = wu.scene("steel", radius=80.0, waves=False, wind=0.0, current=0.0, radiation=False)
    assert sc.lines[wu.CABLE_3].label == "3"


def test_every_input_has_a_source():
    names = [row[0] for row in wu.ASSUMPTIONS]
    assert len(names) == len(set(names))
    for name, value, source in wu.ASSUMPTIONS:
        assert value and ("L" in source or "Eq." in source or source.startswith("ours")), name
    assert wu.TZ <= wu.TZ_MAX and wu.CURRENT <= wu.CURRENT_MAX


@pytest.mark.parametrize("material", ["chain", "polyester"])
def test_anchor_radius_gives_20kN_horizontal_pretension(material):
    import moorjax as mj

    r = wu.anchor_radius(material)
    line = mj.Line(wu.line_type(material), wu.LINE_LENGTH, 10, mj.FixedEnd([r, 0.0, -wu.DEPTH]),
                   mj.FixedEnd([0.0, 0.0, -wu.DRAFT]))
    st = solve_line_statics(line, wu.environment(current=False))
    assert np.hypot(*np.asarray(st.force_b[:2])) == pytest.approx(wu.PRETENSION_H, rel=1e-4)


def test_polyester_hardens_relative_to_steel():
    offsets = [0.25, 0.5, 1.0]
    calm = dict(waves=False, wind=0.0, current=0.0, radiation=False)
    poly = np.asarray(offset_curve(wu.scene("polyester", **calm), offsets))
    steel = np.asarray(offset_curve(wu.scene("steel", **calm), offsets))
    assert np.all(poly > 0) and np.all(steel > 0)
    # secant stiffness of polyester grows with offset faster than steel's
    ratio = poly / steel
    assert np.all(np.diff(ratio) > 0), ratio


def test_unknown_material_is_named():
    with pytest.raises(ValueError, match="unknown material 'nylon'"):
        wu.line_type("nylon")


def test_unknown_start_is_named():
    with pytest.raises(ValueError, match="start must be"):
        wu.start_state(None, "moving")
