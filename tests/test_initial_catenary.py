"""MoorDyn's ``TmaxIC = 0`` start: ``simulate(..., init="catenary")`` and
``moorjax simulate --initial catenary`` (:func:`moorjax.dynamics.initial.catenary_state`).

MoorDyn's ``docs/initialization.rst``: the catenary solver always runs first,
each line between its ends where the deck puts them (a line it cannot solve
starts straight), and with ``TmaxIC = 0`` nothing else runs: free points and
bodies start where the deck places them, not balanced.
"""

import subprocess
import sys

import jax.numpy as jnp
import numpy as np
import pytest

from moorjax.dynamics import simulate
from moorjax.dynamics.initial import catenary_state, equilibrium_state
from moorjax.io import build_scene, parse_deck
from moorjax.statics import solve_line_statics

from test_deck_free_points import DECK as _FREE_POINT_DECK  # a free point on two lines

DECK = _FREE_POINT_DECK.replace("{mass}", "500")


@pytest.fixture(scope="module")
def scene():
    return build_scene(parse_deck(DECK.format(word="Free")))


def test_catenary_start_is_each_line_with_the_point_held_where_the_deck_puts_it(scene):
    eq = catenary_state(scene)
    assert bool(eq.converged) and np.asarray(eq.lines_converged).all()
    held = build_scene(parse_deck(DECK.format(word="Fixed")))  # the same point, fixed
    for state, line in zip(eq.state[:2], held.lines):
        ref = solve_line_statics(line, held.env).state()
        np.testing.assert_allclose(np.asarray(state.r), np.asarray(ref.r), rtol=0, atol=1e-9)
        assert not np.any(np.asarray(state.v))
    np.testing.assert_array_equal(np.asarray(eq.state[2]), 0.0)  # the point at rest at η = 0
    # the system statics move the point (it is not balanced where the deck puts it)
    moved = np.asarray(equilibrium_state(scene).poses)[0, :3]
    assert np.linalg.norm(moved) > 0.5


def test_simulate_starts_from_the_catenary_start(scene):
    ts = np.array([0.0, 0.2])
    res = simulate(scene, ts=ts, init="catenary")
    pose = np.asarray(res.body_pose)[:, 0, :3]
    np.testing.assert_allclose(pose[0], 0.0, atol=1e-12)
    assert np.linalg.norm(pose[1]) > 1e-3  # out of balance: the point starts to move
    res = simulate(scene, ts=ts, init="statics")
    np.testing.assert_allclose(np.asarray(res.body_pose)[0, 0, :3],
                               np.asarray(equilibrium_state(scene).poses)[0, :3], atol=1e-9)
    with pytest.raises(ValueError, match="expected a tuple of states or one of"):
        simulate(scene, ts=ts, init="relaxed")


def test_a_line_that_cannot_be_solved_starts_straight():
    """MoorDyn starts a line its catenary solver cannot solve as a straight line."""
    scene = build_scene(parse_deck(DECK.format(word="Free")))
    import moorjax.dynamics.initial as initial

    real = initial.solve_line_statics

    def failing(line, env, t=0.0, init=None, **kw):
        st = real(line, env, t, init, **kw)
        if line.label == "2":
            import equinox as eqx
            st = eqx.tree_at(lambda s: s.converged, st, jnp.asarray(False))
        return st

    initial.solve_line_statics = failing
    try:
        with pytest.warns(RuntimeWarning, match=r"line\(s\) 2 .* start straight"):
            res = simulate(scene, ts=np.array([0.0, 0.05]), init="catenary", save_nodes=True)
        eq = catenary_state(scene)
    finally:
        initial.solve_line_statics = real
    assert not bool(eq.converged)
    r = np.asarray(eq.state[1].r)
    np.testing.assert_allclose(r, np.linspace([30, 0, -30], [60, 0, -5], 9)[1:-1], atol=1e-12)
    np.testing.assert_allclose(np.asarray(res.positions[1])[0, 1:-1], r, atol=1e-12)


def test_cli_initial_catenary(tmp_path):
    deck = tmp_path / "d.dat"
    deck.write_text(DECK.format(word="Free"))
    out = tmp_path / "run.csv"
    done = subprocess.run([sys.executable, "-m", "moorjax", "simulate", str(deck), "--duration", "0.2",
                           "--initial", "catenary", "--out", str(out), "--quiet"],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert out.exists()
