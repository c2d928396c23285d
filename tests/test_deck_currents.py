"""MoorDyn's ``Currents`` option from decks: files, fields, statics and dynamics.

- ``current_profile.txt`` (``Currents = 1``) and ``current_profile_dynamic.txt``
  (``Currents = 2``) are read as MoorDyn v2 documents them (header lines,
  missing components zero, bad rows named by file and line);
- the fields interpolate linearly and hold beyond the ends, as MoorDyn's grids;
- ``tests/data/current_steady/line.dat`` (MoorDyn's ``wavekin_2`` chain and its
  depth-varying ``current_profile.txt``, a line hung clear of the seabed across
  the flow): moorjax statics under the current against MoorDyn 2.7.2's state
  settled by 150 s of dynamics, and a 10 s transient from the still-water
  equilibrium (MoorDyn's IC runs without currents) against MoorDyn's history;
  the reference is ``moordyn_ref.json`` made by
  ``tests/data/make_moordyn_reference.py``.
"""

from __future__ import annotations

import time

import json
from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

from moorjax.dynamics import simulate
from moorjax.io import build_scene, read_deck
from moorjax.io.currents import read_current_profile, read_dynamic_current_profile
from moorjax.io.errors import InputError
from moorjax.model import ProfileCurrent, TimeProfileCurrent
from moorjax.statics import solve_line_statics

DATA = Path(__file__).parent / "data"
STEADY = DATA / "current_steady" / "line.dat"
REF = json.loads((DATA / "current_steady" / "moordyn_ref.json").read_text())


def _deck_with(tmp_path, currents, files):
    text = STEADY.read_text().replace(
        "1             Currents", f"{currents}             Currents")
    deck = tmp_path / "d.dat"
    deck.write_text(text)
    for name, content in files.items():
        (tmp_path / name).write_text(content)
    return deck


# ----------------------------------------------------------------------------
# files
# ----------------------------------------------------------------------------


def test_steady_profile_file_reads_missing_components_as_zero(tmp_path):
    f = tmp_path / "current_profile.txt"
    f.write_text("h1\nh2\nh3\n-20 0.5\n-10 0.7 0.1\n\n0 1.0 0.2 0.05\n")
    cur = read_current_profile(f)
    np.testing.assert_array_equal(cur.z, [-20, -10, 0])
    np.testing.assert_array_equal(cur.velocity, [[0.5, 0, 0], [0.7, 0.1, 0], [1.0, 0.2, 0.05]])


def test_steady_profile_errors_name_file_line_and_fix(tmp_path):
    f = tmp_path / "current_profile.txt"
    f.write_text("h1\nh2\nh3\n-10 0.5\n-20 0.7\n")
    with pytest.raises(InputError, match=r"current_profile.txt:5: z = -20.0 m .*strictly increasing"):
        read_current_profile(f)
    f.write_text("h1\nh2\nh3\n-10 fast\n")
    with pytest.raises(InputError, match=r":4: .*'fast' is not a number"):
        read_current_profile(f)


def test_dynamic_profile_file_layout(tmp_path):
    f = tmp_path / "current_profile_dynamic.txt"
    f.write_text("a\nb\n\n\n -20 -10 0\n\n0 0 0 0\n10 0.1 0.2 0.3 1 2 3\n")
    cur = read_dynamic_current_profile(f)
    np.testing.assert_array_equal(cur.t, [0, 10])
    np.testing.assert_array_equal(cur.velocity[1], [[0.1, 1, 0], [0.2, 2, 0], [0.3, 3, 0]])
    f.write_text("a\nb\n\n\n -20 -10 0\n\n0 0 0\n")
    with pytest.raises(InputError, match=r":7: .*3 numbers; with 3 depths expected 4"):
        read_dynamic_current_profile(f)


@pytest.mark.parametrize("mode, msg", [
    (3, "not implemented in MoorDyn v2 either"),
    (7, "not a MoorDyn current mode"),
])
def test_unsupported_current_modes_are_refused(tmp_path, mode, msg):
    with pytest.raises(InputError, match=rf"d.dat:\d+: OPTIONS: Currents = {mode}: ?.*{msg}"
                       if mode != 7 else msg):
        read_deck(_deck_with(tmp_path, mode, {}))


def test_missing_current_file_is_named(tmp_path):
    with pytest.raises(InputError, match=r"Currents = 2: the current file .*current_profile_dynamic.txt"
                                         r"' does not exist"):
        read_deck(_deck_with(tmp_path, 2, {}))


# ----------------------------------------------------------------------------
# fields
# ----------------------------------------------------------------------------


def test_profile_matches_moordyn_documented_example():
    # docs/waterkinematics.rst, "Currents = 1": the current at (10, -6, -5.5) is (0.65, 0, 0)
    z = np.arange(-10.0, 1.0)
    ux = [1.25, 1.1, 0.9, 0.8, 0.7, 0.6, 0.4, 0.3, 0.1, 0.0, 0.0]
    cur = ProfileCurrent(z, np.stack([ux, np.zeros(11), np.zeros(11)], axis=1))
    np.testing.assert_allclose(cur.velocity(jnp.array(-5.5)), [0.65, 0, 0], atol=1e-12)
    # held beyond the ends
    np.testing.assert_allclose(cur.velocity(jnp.array([-30.0, 3.0]))[:, 0], [1.25, 0.0])


def test_time_profile_is_bilinear_and_held_beyond_the_ends():
    u = np.zeros((2, 2, 3))
    u[1, :, 0] = [1.0, 2.0]  # at t = 10: 1 m/s at z = -10, 2 m/s at z = 0
    cur = TimeProfileCurrent([0.0, 10.0], [-10.0, 0.0], u)
    np.testing.assert_allclose(cur.velocity(jnp.array(-5.0), 5.0), [0.75, 0, 0])
    np.testing.assert_allclose(cur.velocity(jnp.array(-5.0), 20.0), [1.5, 0, 0])
    np.testing.assert_allclose(cur.velocity(jnp.array(-5.0), -1.0), [0, 0, 0])
    with pytest.raises(ValueError, match="strictly increasing"):
        TimeProfileCurrent([0.0, 0.0], [-10.0, 0.0], u)


def test_deck_builds_the_profile_current():
    deck = read_deck(STEADY)
    assert deck.current.mode == 1 and deck.current.z.shape == (57,)
    env = build_scene(deck).env
    assert isinstance(env.current, ProfileCurrent)
    np.testing.assert_allclose(env.current.velocity(jnp.array(-10.0)), [1.25, 0, 0])


# ----------------------------------------------------------------------------
# against MoorDyn 2.7.2
# ----------------------------------------------------------------------------


def _still(scene):
    import equinox as eqx

    return eqx.tree_at(lambda s: s.env.current, scene, None, is_leaf=lambda x: x is None)


@pytest.fixture(scope="module")
def scene():
    return build_scene(read_deck(STEADY))


@pytest.mark.slow
def test_statics_under_current_match_moordyn_settled_state(scene):
    st = solve_line_statics(scene.lines[0], scene.env)
    ref = REF["settled"]["lines"][0]
    pos = np.asarray(st.positions)
    err = np.max(np.linalg.norm(pos - np.asarray(ref["positions"]), axis=1))
    # the current pushes the line 0.29 m out of its plane at mid-length
    assert ref["positions"][10][0] > 0.28
    assert err < 5e-3, err
    t = np.asarray(st.tensions)
    np.testing.assert_allclose([t[0], t[-1]], [ref["tension_a"], ref["tension_b"]], rtol=2e-4)


def test_still_water_statics_match_moordyn_initial_condition(scene):
    st = solve_line_statics(scene.lines[0], _still(scene).env)
    ref = REF["initial"]["lines"][0]
    err = np.max(np.linalg.norm(np.asarray(st.positions) - np.asarray(ref["positions"]), axis=1))
    assert err < 0.1, err  # MoorDyn's IC solver stops at its own threshold (0.1 %)


@pytest.mark.slow
def test_transient_into_the_current_matches_moordyn(scene):
    """From the still-water equilibrium the line swings into the current."""
    init = (solve_line_statics(scene.lines[0], _still(scene).env).state(),)
    hist = REF["history"]
    ts = np.asarray(hist["t"])[19::20]  # every 1 s, 1..10 s
    t0 = time.perf_counter()
    res = simulate(scene, ts=ts, init=init, save_nodes=True, rtol=1e-5, atol=1e-4)
    mid = np.asarray(res.positions[0])[:, 10]
    wall = time.perf_counter() - t0
    ref_mid = np.asarray(hist["mid"])[19::20, 0]
    # the out-of-plane swing grows from 0 to 0.25 m
    assert ref_mid[-1, 0] > 0.25
    err = np.max(np.abs(mid[:, 0] - ref_mid[:, 0]))
    print(f"current deck, 10 s: mid-node swing error {err:.4f} m of {np.max(np.abs(ref_mid[:, 0])):.3f} m "
          f"({err / np.max(np.abs(ref_mid[:, 0])):.2%}); moorjax {wall:.1f} s with compilation")
    assert err < 0.02 * np.max(np.abs(ref_mid[:, 0])), err
    # the stiff chain rings axially (in both codes) around the mean tension:
    # samples agree to the ringing's amplitude, 0.15 % of the tension
    tb = np.asarray(res.segment_tensions[0])[:, -1]
    np.testing.assert_allclose(tb, np.asarray(hist["tension_b"])[19::20, 0], rtol=2.5e-3)
