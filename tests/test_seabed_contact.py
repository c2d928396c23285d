"""Seabed contact law: the damping ramp (moorjax.Seabed, damping_depth)."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import moorjax as mj
from moorjax.element.linear import _seabed
from moorjax.io import build_scene, read_deck
from moorjax.examples import example_path


def _chain_scene(depth=None):
    scene = build_scene(read_deck(example_path("oc3_catenary")), segments=20)
    value = None if depth is None else jnp.asarray(depth, dtype=float)
    return eqx.tree_at(lambda s: s.env.seabed.damping_depth, scene, value,
                       is_leaf=lambda x: x is None)


def _vertical_force(scene, pen, vz):
    """Bed force [N] on an interior node at penetration pen [m], speed vz [m/s]."""
    line, env = scene.lines[0], scene.env
    n = line.n_segments
    r = jnp.zeros((n + 1, 3)).at[:, 2].set(-env.depth + 1.0).at[5, 2].set(-env.depth - pen)
    v = jnp.zeros((n + 1, 3)).at[5, 2].set(vz)
    node_len = jnp.full(n + 1, line.length / n)
    return _seabed(line.line_type, env, r, v, node_len)[5, 2]


def test_rest_penetration_of_chain():
    scene = _chain_scene()
    lt, env = scene.lines[0].line_type, scene.env
    w = float(lt.wet_weight(env.rho, env.g))
    rest = float(env.seabed.rest_penetration(w, lt.diameter))
    assert rest == pytest.approx(w / (3e6 * 0.09), rel=1e-9)
    assert 2e-3 < rest < 3e-3  # 2.6 mm for the chain of case A


def test_damping_ramps_in_continuously():
    """The damping force is 0 at the bed, full at the rest penetration and
    beyond, and continuous (no jump of cBot·|ż|·d·l on landing)."""
    scene = _chain_scene()
    lt, env = scene.lines[0].line_type, scene.env
    rest = float(env.seabed.rest_penetration(lt.wet_weight(env.rho, env.g), lt.diameter))
    area = float(lt.diameter * scene.lines[0].length / scene.lines[0].n_segments)
    vz = -0.7

    def damping(pen):
        return float(_vertical_force(scene, pen, vz) - _vertical_force(scene, pen, 0.0))

    full = 3e5 * 0.7 * area
    assert damping(-1e-3) == 0.0
    assert abs(damping(1e-9)) < 1e-6 * full  # continuous at first contact
    assert damping(0.5 * rest) == pytest.approx(0.5 * full, rel=1e-9)  # smoothstep(1/2)
    assert damping(rest) == pytest.approx(full, rel=1e-9)
    assert damping(10 * rest) == pytest.approx(full, rel=1e-9)
    # the spring is unchanged
    assert float(_vertical_force(scene, rest, 0.0)) == pytest.approx(3e6 * rest * area, rel=1e-9)


def test_zero_depth_is_moordyn_step():
    scene = _chain_scene(0.0)
    lt = scene.lines[0].line_type
    area = float(lt.diameter * scene.lines[0].length / scene.lines[0].n_segments)
    jump = float(_vertical_force(scene, 1e-9, -0.7) - _vertical_force(scene, 1e-9, 0.0))
    assert jump == pytest.approx(3e5 * 0.7 * area, rel=1e-9)
    assert float(_vertical_force(scene, -1e-9, -0.7)) == 0.0


def test_contact_force_gradient_finite_at_bed():
    scene = _chain_scene()
    g = jax.grad(lambda p: _vertical_force(scene, p, -0.5))(jnp.asarray(0.0))
    assert np.isfinite(float(g))


def test_negative_depth_refused():
    with pytest.raises(ValueError, match="damping ramp depth"):
        mj.Seabed(damping_depth=-1.0)


@pytest.mark.slow
def test_grounded_chain_converges_at_second_order_in_n_while_taut():
    """A grounded chain whose touchdown moves along the bed but which stays taut
    (case A's line on a 2.5 m sine, least fairlead tension ≈ 0.5 MN) converges at
    second order in the number of segments, as the line hanging free does: the
    node-lumped contact does not cost an order. (At case A's 5 m the grounded
    part goes slack and snaps taut, and the tension converges at first
    order: 0.86 between N = 20, 40 and 80 over the first 10 s;
    benchmarks/order_in_n.py, benchmarks/README.md session 42)."""
    from moorjax.dynamics import simulate

    histories = {}
    for n in (20, 40, 80):  # coarser pairs are second order in either regime
        scene = build_scene(read_deck(example_path("oc3_catenary")), segments=n)
        scene = eqx.tree_at(lambda s: s.lines[0].end_b, scene,
                            mj.SinePath((-5.2, 0.0, -70.0), [2.5, 0.0, 0.0], 10.0))
        res = simulate(scene, 10.0, rtol=1e-6, atol=1e-5, dt_out=0.05)
        assert bool(res.succeeded())
        ts = np.asarray(res.ts)
        histories[n] = np.asarray(res.tension_b[:, 0])[ts >= 0.5]
    d1 = np.sqrt(np.mean((histories[20] - histories[40]) ** 2)) / np.std(histories[40])
    d2 = np.sqrt(np.mean((histories[40] - histories[80]) ** 2)) / np.std(histories[80])
    assert np.log2(d1 / d2) > 1.4, (d1, d2)  # measured 1.70 (at 5 m: 0.86)
