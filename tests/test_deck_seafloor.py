"""3-D seabed from MoorDyn's ``SeafloorFile`` bathymetry grids.

- the grid file is read as MoorDyn v2 documents it (docs/inputs.rst,
  "Seafloor/Bathymetry File"), bad grids are named by file and line;
- heights are bilinear inside the grid and held at the nearest edge outside;
- a flat grid at −depth gives exactly the flat seabed's contact forces (with
  friction), at random node positions and velocities;
- on a tilted plane the contact force is along the plane's normal with the
  magnitude kBot·(distance below the plane)·d·l, and friction opposes the
  sliding velocity along the plane;
- MoorDyn's own deck ``tests/Mooring/seafloor.txt`` (a pendulum over the
  sloped grid ``seafloor_profile_3d.txt``, copied to ``tests/data/seafloor/``)
  is read and built with its grid.
"""

from __future__ import annotations

from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

import moorjax as mj
from moorjax.element import LinearElement
from moorjax.io import build_scene, read_deck
from moorjax.io.errors import InputError
from moorjax.io.seafloor import read_seafloor
from moorjax.model import Bathymetry, Seabed, SeabedFriction

DATA = Path(__file__).parent / "data" / "seafloor"


def test_moordyn_grid_file_and_deck():
    sf = read_seafloor(DATA / "seafloor_profile_3d.txt")
    assert sf.z.shape == (100, 5)
    np.testing.assert_allclose(sf.z[0], -40.0)
    deck = read_deck(DATA / "pendulum.txt")
    scene = build_scene(deck)
    bed = scene.env.seabed.bathymetry
    assert isinstance(bed, Bathymetry)
    # the grid rises from -40 m at x = -50 m by 0.2 m per m along x
    np.testing.assert_allclose(bed.height(jnp.array(0.0), jnp.array(0.3)), sf.z[:, 0].mean(), atol=1e-9)
    np.testing.assert_allclose(bed.height(jnp.array(-80.0), jnp.array(9.0)), -40.0)  # held at the edge


def test_bad_grid_rows_are_named(tmp_path):
    f = tmp_path / "g.txt"
    f.write_text("2 2\n0 1\n0 1\n0 0 -10\n0 1 -10\n1 0 -10\n1 0.5 -10\n")
    with pytest.raises(InputError, match=r"g.txt:7: point \(1.0, 0.5\) m is not on the grid"):
        read_seafloor(f)
    f.write_text("2 2\n0 1\n0 1\n0 0 -10\n0 1 -10\n1 0 -10\n")
    with pytest.raises(InputError, match=r"no depth for grid point \(1.0, 1.0\) m"):
        read_seafloor(f)


def _line(n=6):
    lt = mj.LineType(0.1, 50.0, 1e8)
    return mj.Line(lt, 60.0, n, mj.FixedEnd((0.0, 0.0, -50.0)), mj.FixedEnd((55.0, 0.0, -50.0)))


def test_flat_grid_equals_flat_seabed():
    rng = np.random.default_rng(0)
    line = _line()
    r = jnp.asarray(rng.normal(size=(7, 3)) * [20, 5, 0.05] + [25, 0, -50])
    v = jnp.asarray(rng.normal(size=(7, 3)) * 0.2)
    friction = SeabedFriction(0.6)
    flat = mj.Environment(50.0, seabed=Seabed(3e6, 3e5, friction))
    grid = Bathymetry([-100.0, 0.0, 200.0], [-10.0, 10.0], np.full((3, 2), -50.0))
    gridded = mj.Environment(50.0, seabed=Seabed(3e6, 3e5, friction, grid))
    el = LinearElement()
    np.testing.assert_allclose(el.nodal_forces(line, gridded, r, v), el.nodal_forces(line, flat, r, v),
                               rtol=1e-12, atol=1e-9)


def test_seabed_height_under_points():
    """``Environment.seabed_height`` (where the bodies' statics look for a body
    sunk through the bed): −depth on a flat bed or none, the grid's bilinear
    height on a bathymetry, for any array shape."""
    x, y = np.array([[-50.0, 0.0], [100.0, 300.0]]), np.array([[0.0, -10.0], [5.0, 10.0]])
    for seabed in (None, Seabed(3e6, 3e5)):
        np.testing.assert_array_equal(mj.Environment(50.0, seabed=seabed).seabed_height(x, y),
                                      np.full((2, 2), -50.0))
    grid = Bathymetry([0.0, 100.0], [-10.0, 10.0], [[-40.0, -40.0], [-60.0, -60.0]])  # a slope in x
    z = mj.Environment(50.0, seabed=Seabed(3e6, 3e5, bathymetry=grid)).seabed_height(x, y)
    np.testing.assert_allclose(z, [[-40.0, -40.0], [-60.0, -60.0]], rtol=1e-12)  # held at the edges
    mid = mj.Environment(50.0, seabed=Seabed(3e6, 3e5, bathymetry=grid)).seabed_height(25.0, 3.0)
    assert float(mid) == pytest.approx(-45.0, rel=1e-12)


def test_tilted_plane_contact_is_normal_to_the_seabed():
    slope = 0.2  # z_b = -50 + 0.2 x
    grid = Bathymetry([0.0, 100.0], [-10.0, 10.0], [[-50.0, -50.0], [-30.0, -30.0]])
    n = np.array([-slope, 0.0, 1.0]) / np.hypot(slope, 1.0)
    line = _line()
    env = mj.Environment(60.0, rho=0.0, g=0.0, seabed=Seabed(3e6, 0.0, None, grid))
    x = np.linspace(0.0, 55.0, 7)
    depth_below = 0.01  # [m] below the plane, measured along its normal
    r = np.stack([x, np.zeros(7), -50.0 + slope * x], axis=1) - depth_below * n
    # a straight, unstretched line lying in the plane: only contact acts on interior nodes
    r = jnp.asarray(r)
    seg = np.linalg.norm(np.diff(np.asarray(r), axis=0), axis=1)
    line = mj.Line(line.line_type, float(seg.sum()), 6, mj.FixedEnd(r[0]), mj.FixedEnd(r[-1]))
    f = np.asarray(LinearElement().nodal_forces(line, env, r, jnp.zeros_like(r)))[1:-1]
    expected = 3e6 * depth_below * 0.1 * float(line.segment_length)
    np.testing.assert_allclose(f, np.outer(np.full(5, expected), n), rtol=1e-9, atol=1e-6)

    # friction opposes sliding along the plane, not the normal velocity
    env = mj.Environment(60.0, rho=0.0, g=0.0,
                         seabed=Seabed(3e6, 0.0, SeabedFriction(0.5, v_slip=1e-6), grid))
    along = np.array([1.0, 0.0, slope]) / np.hypot(slope, 1.0)
    v = jnp.asarray(np.tile(0.3 * along + 0.05 * n, (7, 1)))
    f = np.asarray(LinearElement().nodal_forces(line, env, r, v))[1:-1]
    tangential = f - np.outer(f @ n, n)
    np.testing.assert_allclose(tangential, np.outer(np.full(5, -0.5 * expected), along), rtol=1e-6, atol=1e-6)


@pytest.mark.slow
def test_line_resting_on_a_sloped_seabed_matches_moorpy_inclined_catenary():
    """Statics on a seabed rising 0.1 m per m along the line: MoorPy's catenary
    with a seabed incline alpha = atan(0.1) (stiff bed, kBot = 3e8 Pa/m)."""
    from moorpy.Catenary import catenary

    slope, w, d = 0.1, 500.0, 0.1
    grid = Bathymetry([-100.0, 300.0], [-10.0, 10.0], [[-60.0, -60.0], [-20.0, -20.0]])
    lt = mj.LineType(d, w / 9.80665 + 1025.0 * np.pi * d**2 / 4, 1e9)
    # 80 segments: the grounded anchor's tension carries the along-slope weight of
    # the first half segment only (the bed the rest), -1.1e-3 at 40, -3.2e-5 at 80
    line = mj.Line(lt, 100.0, 80, mj.FixedEnd((0.0, 0.0, -50.0)), mj.FixedEnd((80.0, 0.0, -5.0)))
    env = mj.Environment(70.0, seabed=Seabed(3e8, 0.0, None, grid))
    from moorjax.statics import solve_line_statics

    st = solve_line_statics(line, env)
    fah, fav, fbh, fbv, info = catenary(80.0, 45.0, 100.0, 1e9, w, CB=0, alpha=np.degrees(np.arctan(slope)))
    assert info["LBot"] > 30  # a third of the line lies on the slope
    np.testing.assert_allclose(float(st.tension_b), np.hypot(fbh, fbv), rtol=1e-3)
    np.testing.assert_allclose(float(st.tension_a), np.hypot(fah, fav), rtol=1e-3)


@pytest.mark.slow
def test_moordyn_pendulum_deck_settles_on_the_slope():
    """MoorDyn's ``tests/Mooring/seafloor.txt``: a 10 kg point on a 32 m line as
    dense as the water, from a fixed point at the surface, starting on the seabed
    (z_b = -30 + 0.2·x m) with the line slack. Nothing holds the point along the
    frictionless slope until the line is taut, so it slides down to where the
    sphere of radius L around the anchor meets the bed; there its weight W, the
    bed's normal reaction N·n and the line's pull T·u balance:
    T = W·n_x/(n_x·u_z − n_z·u_x) with u the unit vector to the anchor.
    (The static solve once stopped: the slack weightless line's shape, and so
    its implicit derivative, is undetermined; see moorjax.linalg.undetermined.
    Then it took 105 Newton iterations, or more than 200 under other rounding,
    and the compiled twin that starts ``simulate`` did not converge: the line's
    statics crawled from its last shape at most trial poses, and trials were
    refused for force rises below what the lines resolve. Then 15–16 under
    either rounding, until an AMD EPYC host's first Newton step went 5 m up
    against the weight and stopped after 10 iterations (session 42): a step
    that does negative work is now regularised, 29 iterations there.)"""
    from moorjax.dynamics import equilibrium_state
    from moorjax.statics import solve_system_statics

    scene = build_scene(read_deck(DATA / "pendulum.txt"))
    st = solve_system_statics(scene)
    assert st.converged and int(st.iterations) <= 40, int(st.iterations)
    eq = equilibrium_state(scene)  # the compiled iteration simulate starts from
    assert bool(eq.converged)
    np.testing.assert_allclose(np.asarray(eq.poses), np.asarray(st.poses), atol=1e-4)
    p = np.asarray(scene.bodies[0].origin + st.poses[0, :3])
    anchor, length = np.array([0.0, -1.0, 0.0]), 32.0
    # the lowest point of the circle |p - anchor| = L on the plane z = -30 + 0.2 x
    a, b, c = 1.0 + 0.2**2, -2 * 0.2 * 30.0, 30.0**2 - length**2
    x = (-b - np.sqrt(b * b - 4 * a * c)) / (2 * a)
    np.testing.assert_allclose(p, [x, -1.0, -30.0 + 0.2 * x], atol=2e-3)  # bed penetration 0.2 mm
    n = np.array([-0.2, 0.0, 1.0]) / np.hypot(0.2, 1.0)
    u = (anchor - p) / np.linalg.norm(anchor - p)
    weight = 10.0 * 9.80665
    tension = weight * -n[0] / (-n[0] * u[2] + n[2] * u[0])
    seg = np.asarray(st.lines[0].tensions)
    np.testing.assert_allclose(seg[[0, -1]], tension, rtol=1e-3)  # weightless: uniform
    # the line's end node carries the bed reaction too: the point's whole weight
    np.testing.assert_allclose(np.asarray(st.mooring[0, :3]), [0.0, 0.0, weight], rtol=1e-6, atol=1e-3)
