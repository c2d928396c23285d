"""Lines of one structure computed as one vmapped call (moorjax.model.grouping):
the same answers as line by line, and one traced copy of a body scene's line
statics per structure, not per line."""

from pathlib import Path

import equinox as eqx
import jax
from jax.extend.core import jaxprs_in_params
import numpy as np

import moorjax as mj
from moorjax.dynamics.initial import equilibrium_state
from moorjax.element import HermiteElement
from moorjax.io import build_scene, read_deck
from moorjax.model.grouping import line_groups, map_lines
from moorjax.statics.fem import solve_line_statics

DATA = Path(__file__).parent / "data"
LT = mj.LineType(diameter=0.08, mass_per_length=40.0, axial=mj.LinearEA(5e8))
ENV = mj.Environment(50.0, seabed=mj.Seabed(3e6, 3e5))


def _line(x, length=80.0, n=10, label="1", element=None):
    kw = {} if element is None else dict(element=element)
    return mj.Line(LT, length, n, mj.FixedEnd([x, 0.0, -50.0]), mj.FixedEnd([0.0, 0.0, -20.0]),
                   label=label, **kw)


def test_groups_ignore_labels_and_values_not_structure():
    lines = [_line(-70.0, label="a"), _line(-60.0, 85.0, label="b"), _line(-70.0, n=8),
             _line(-70.0, element=HermiteElement()), _line(-65.0, label="c")]
    groups = line_groups(lines)
    assert groups == [[0, 1, 4], [2], [3]]
    # per-line arguments of different structure split a group
    assert line_groups(lines[:2], [None, lines[1].straight_state()]) == [[0], [1]]


def test_mapped_statics_equal_line_by_line():
    lines = [_line(-70.0, label="a"), _line(-62.0, 86.0, label="b"), _line(-70.0, n=6),
             _line(-75.0, 90.0, label="c")]
    solve = eqx.filter_jit(lambda ls: map_lines(
        lambda ln: solve_line_statics(ln, ENV, throw=False), ls))
    mapped = solve(lines)
    for line, st in zip(lines, mapped):
        one = solve_line_statics(line, ENV)
        assert bool(st.converged)
        np.testing.assert_allclose(np.asarray(st.positions), np.asarray(one.positions),
                                   rtol=0, atol=1e-9)
        assert abs(float(st.tension_b) / float(one.tension_b) - 1) < 1e-10


def _while_loops(jaxpr):
    n = 0
    for eqn in jaxpr.eqns:
        n += eqn.primitive.name == "while"
        for sub in jaxprs_in_params(eqn.params):
            n += _while_loops(sub)
    return n


def test_body_statics_trace_one_line_solve_per_structure():
    """The free buoy on three equal chains traces as many loops as the buoy on
    one chain (before: three times the line solves' loops)."""
    with_three = build_scene(read_deck(DATA / "free_body_buoy.dat"))
    with_one = eqx.tree_at(lambda s: s.lines, with_three, with_three.lines[:1])

    def loops(scene):
        return _while_loops(jax.make_jaxpr(lambda s: equilibrium_state(s).poses)(scene).jaxpr)

    assert loops(with_three) == loops(with_one) > 0
