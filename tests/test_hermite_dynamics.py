"""Hermite lines in the dynamics driver (``simulate`` with ``Line(element=HermiteElement())``).

The tension field is eliminated at every evaluation (Wu's Eq. 27, see
:mod:`moorjax.element.hermite_motion`), so a Hermite line is an ODE on its node
positions and slopes, integrated by the same diffrax driver as the linear
element. Checked: the static state stays put; the diffrax run follows the
paper's Newmark/Newton stepping (an independent integrator of the same
semi-discrete equations); the CLI option and the errors for what is not
supported.
"""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import equinox as eqx
import numpy as np
import pytest

from moorjax.cli import main
from moorjax.dynamics import simulate
from moorjax.dynamics.hermite_newmark import newmark_hermite
from moorjax.element import HermiteElement
from moorjax.element.hermite_motion import HermiteState, MixedTension
from moorjax.statics.hermite import hermite_equilibrium
from gradcheck import gradient_and_central_difference
from scenes import hermite_case_a

DATA = Path(__file__).parent / "data"


case_a = hermite_case_a


def test_static_state_stays_at_rest():
    """Case A at 4 elements with both ends held: the static solve is a fixed point
    of the dynamics with the default (strain) tension closure, whose own
    equilibrium the start is (fairlead tension constant to 1e-6, nodes still)."""
    scene = case_a(4, motion=False)
    res = simulate(scene, 1.0, dt_out=0.5)
    tb = np.asarray(res.tension_b[:, 0])
    assert np.ptp(tb) < 1e-6 * tb.mean(), tb
    assert 9.0e5 < tb.mean() < 9.2e5  # MoorPy's catenary: 911 kN
    final = res.final_state[0]
    assert isinstance(final, HermiteState)
    assert float(np.max(np.abs(np.asarray(final.v)))) < 1e-5


@pytest.mark.slow
def test_diffrax_follows_the_newmark_reference():
    """Case A, 10 elements, first 3 s (the fairlead pulled out to 1.8 MN): Kvaerno5
    at rtol 1e-6 with Wu's tension field (:class:`MixedTension`, the equations the
    Newmark reference steps) and the Newmark/Newton reference at dt = 2.5 ms agree
    to 0.2 % RMS and 0.6 % at worst of the 0.68 MN tension range (their
    time-discretisation errors; Newmark starts from zero accelerations)."""
    scene = case_a(10, element=HermiteElement(tension=MixedTension()))
    res = simulate(scene, 3.0, rtol=1e-6, atol=1e-5)
    line, env = scene.lines[0], scene.env
    dofs, _ = hermite_equilibrium(line, env, 0.0)
    ref = newmark_hermite(line, env, dofs, 0.0, 0.0025, 1200)
    ts = np.asarray(res.ts)[1:]
    ours = np.asarray(res.tension_b[1:, 0])
    theirs = np.interp(ts, np.asarray(ref.t), np.asarray(ref.tension_b))
    span = np.ptp(theirs)
    assert span > 6e5
    err = ours - theirs
    rms, worst = np.sqrt(np.mean(err**2)) / span, np.max(np.abs(err)) / span
    assert rms < 0.002 and worst < 0.006, (rms, worst)


def test_cli_element_option_on_dynamics():
    """``--element`` is offered by simulate, ensemble and fit."""
    for cmd in ("simulate", "ensemble", "fit"):
        out = io.StringIO()
        with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
            main([cmd, "--help"])
        assert "--element" in out.getvalue(), cmd
        assert "--hermite-tension" in out.getvalue(), cmd


def test_cli_hermite_tension_option_names_the_closure():
    """``--hermite-tension`` picks the dynamics' tension closure (default: the
    projected field), and is refused with an unknown name."""
    import argparse

    from moorjax._cli_load import element_from
    from moorjax.element.hermite_motion import MixedTension, ProjectedTension, StrainTension

    def of(**kw):
        return element_from(argparse.Namespace(element="hermite", **kw)).tension

    assert isinstance(of(), ProjectedTension) and of().continuous
    assert of(hermite_tension="element") == ProjectedTension(continuous=False)
    assert isinstance(of(hermite_tension="strain"), StrainTension)
    assert isinstance(of(hermite_tension="mixed"), MixedTension)
    err = io.StringIO()
    with contextlib.redirect_stderr(err), pytest.raises(SystemExit):
        main(["simulate", "example:oc3_catenary", "--duration", "1", "--element", "hermite",
              "--hermite-tension", "exact"])
    assert "invalid choice" in err.getvalue()


@pytest.mark.slow
def test_cli_hermite_lines_on_a_free_body(tmp_path):
    """A deck with a free body on Hermite lines runs (statics and a short
    simulation: finite tensions that start at the system statics' fairlead
    tensions; 260 s here, mostly compiling)."""
    import json

    deck = ["--segments", "4", "--element", "hermite"]
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["statics", str(DATA / "free_body_buoy.dat"), *deck, "--json"]) == 0
    static = [row["tension_b"] for row in json.loads(buf.getvalue())]
    out = tmp_path / "o.csv"
    assert main(["simulate", str(DATA / "free_body_buoy.dat"), "--duration", "0.1", *deck,
                 "--out", str(out), "-q"]) == 0
    header = out.read_text().splitlines()[0].split(",")
    data = np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)
    tb = data[:, [header.index(f"L{i}_tension_b") for i in (1, 2, 3)]]
    assert np.all(np.isfinite(tb))
    np.testing.assert_allclose(tb[0], static, rtol=2e-3)


@pytest.mark.slow
def test_gradient_and_vmap_of_a_hermite_run():
    """d(fairlead tension at 1 s)/d(Cd_normal) of case A at 4 Hermite elements
    (fixed steps of 20 ms) equals central differences (measured 7e-8 relative),
    and a vmapped batch of drag coefficients equals the loop."""
    import jax
    import jax.numpy as jnp

    scene = case_a(4)

    def tension(cd):
        s = eqx.tree_at(lambda s: s.lines[0].line_type.drag.cd_normal, scene, cd)
        return simulate(s, 1.0, dt=0.02, dt_out=0.5, throw=False).tension_b[-1, 0]

    # two compiled programs: the value with its gradient (also the differences'
    # and the loop's values), and the vmapped run
    grad, fd, f = gradient_and_central_difference(tension, 1.6, 1e-3)
    assert abs(grad) > 1e3  # drag matters in the first surge
    assert abs(grad / fd - 1) < 1e-5, (grad, fd)
    cds = jnp.array([1.2, 2.0])
    np.testing.assert_allclose(np.asarray(jax.jit(jax.vmap(tension))(cds)), [f(c) for c in cds], rtol=1e-9)


def test_cli_simulate_with_hermite_elements(tmp_path):
    """``moorjax simulate example:taut_polyester --element hermite``: a short run
    held at rest writes finite tensions equal to the Hermite statics' fairlead
    tension (the start is the closure's own equilibrium)."""
    import json

    out = tmp_path / "run.csv"
    rc = main(["simulate", "example:taut_polyester", "--duration", "0.5", "--segments", "4",
               "--motion", "none", "--element", "hermite", "--out", str(out), "-q"])
    assert rc == 0
    data = np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)
    header = out.read_text().splitlines()[0].split(",")
    tb = data[:, header.index("L1_tension_b")]
    assert np.all(np.isfinite(tb))
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["statics", "example:taut_polyester", "--segments", "4", "--element",
                     "hermite", "--json"]) == 0
    static = json.loads(buf.getvalue())[0]["tension_b"]
    np.testing.assert_allclose(tb, static, rtol=2e-3)
