"""The Wu et al. example box: pretension, layout symmetry and the static offset
behaviour the paper reports (polyester hardens relative to steel wire and chain)."""

from __future__ import annotations

import numpy as np
import pytest

from moorjax.examples import wu_box as wu
from moorjax.statics import offset_curve, solve_line_statics


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
