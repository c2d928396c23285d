"""The Rosenbrock-W stepper ROS34PW2 (``solver="ros34pw2"``, moorjax/dynamics/rosenbrock.py).

* its order on problems with known solutions: 3 on a non-stiff forced problem,
  2 (Prothero–Robinson order reduction, small constant) on a stiff one, and at
  least 2 with a wrong matrix W (the W-method property the option of keeping
  the Jacobian rests on);
* the ∂f/∂t term: the driven line needs it (on a linear problem its
  contributions cancel in ROS34PW2's solution);
* on a mooring line (case B, slack–snap polyester-like line) against a
  converged Kvaerno5 run; the dense and the structured linear algebra agree;
* it runs under ``vmap`` (ensembles) and its reverse-mode gradient matches a
  central difference.
"""

import dataclasses

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from moorjax.dynamics import simulate
from moorjax.dynamics.rosenbrock import ROS34PW2, RosenbrockW
from moorjax.dynamics.solvers import SOLVERS, make_solver
from gradcheck import gradient_and_central_difference
from scenes import case_b_scene

H = (0.1, 0.05, 0.025, 0.0125)


def _final(f, solver, h, y0, t1=2.0, args=None):
    sol = diffrax.diffeqsolve(diffrax.ODETerm(f), solver, 0.0, t1, h, jnp.asarray(y0), args=args,
                              saveat=diffrax.SaveAt(t1=True),
                              stepsize_controller=diffrax.ConstantStepSize())
    return np.asarray(sol.ys[-1])


def _slopes(errors):
    e = np.asarray(errors)
    return np.log2(e[:-1] / e[1:])


def _forced(t, y, lam):
    """y' = −λ(y − sin t) + cos t, y(0) = 0: y = sin t for every λ."""
    return -lam * (y - jnp.sin(t)) + jnp.cos(t)


@pytest.mark.parametrize("lam, order, tol", [(1.0, 3, 1e-5), (1e3, 2, 1e-6)])
def test_order_on_a_forced_problem(lam, order, tol):
    solver = RosenbrockW(structured=False)
    errors = [abs(_final(_forced, solver, h, [0.0], args=lam)[0] - np.sin(2.0)) for h in H]
    slopes = _slopes(errors)
    print("λ", lam, "errors", errors, "slopes", slopes)
    assert np.all(slopes > order - 0.3), slopes
    assert errors[0] < tol


def _dense_errors(lam, delta=0.0, thetas=(0.25, 0.5, 0.75), hermite=False):
    """The largest error of the output inside one step of the forced problem from
    y(t₀) = sin t₀ + δ (t₀ = 0.3; exact: sin t + δ·e^(−λ(t − t₀))), for each step in
    H: the stages' dense output, or diffrax's cubic Hermite interpolation through
    h·f at both ends."""
    solver, term = RosenbrockW(structured=False), diffrax.ODETerm(_forced)
    errors = []
    for h in H:
        t0 = 0.3
        y0 = jnp.asarray([np.sin(t0) + delta])
        state = solver.init(term, t0, t0 + h, y0, lam)
        y1, _, dense, _, _ = solver.step(term, t0, t0 + h, y0, lam, state, False)
        if hermite:
            interp = diffrax.ThirdOrderHermitePolynomialInterpolation(
                t0=t0, t1=t0 + h, y0=y0, y1=y1, k0=h * _forced(t0, y0, lam),
                k1=h * _forced(t0 + h, y1, lam))
        else:
            interp = solver.interpolation_cls(t0=t0, t1=t0 + h, **dense)
        exact = lambda t: np.sin(t) + delta * np.exp(-lam * (t - t0))  # noqa: E731
        errors.append(max(abs(float(interp.evaluate(t0 + th * h)[0]) - exact(t0 + th * h))
                          for th in thetas))
    return np.asarray(errors)


def test_dense_output_is_third_order_and_bounded_on_stiff_components():
    """Between steps, the outputs are the stages' dense output of order 3
    (moorjax/dynamics/rosenbrock.py, ``_dense_weights``): local error O(h⁴) on
    the non-stiff problem, O(h³) on the stiff one (λ = 1e6). A step that starts
    off the slow solution by δ = 1e-3 (as every step of a mooring line does, by
    its tolerance, in the stiff axial modes) keeps the output within δ
    (measured 7.2e-4), where the cubic Hermite interpolation through h·f(t₀, y₀)
    is off by about 0.14·hλδ (1.8 to 14 here)."""
    weights = np.asarray(ROS34PW2.dense)
    np.testing.assert_allclose(weights.sum(axis=0), ROS34PW2.m, atol=1e-12)  # θ = 1: y₁
    errors = _dense_errors(1.0)
    assert np.all(_slopes(errors) > 3.6), errors
    stiff = _dense_errors(1e6)
    assert np.all(_slopes(stiff) > 2.7) and np.all(stiff < 2e-2 * np.asarray(H) ** 3), stiff
    off, off_hermite = _dense_errors(1e6, 1e-3), _dense_errors(1e6, 1e-3, hermite=True)
    print("errors", errors, "stiff", stiff, "off by 1e-3", off, "Hermite", off_hermite)
    assert np.all(off < 1e-3), off
    assert np.all(off_hermite > 1.0), off_hermite


class _OffJacobian(RosenbrockW):
    """W = 0.3·J + 0.2 (a wrong matrix)."""

    def _jacobian(self, terms, t, y, args):
        return 0.3 * super()._jacobian(terms, t, y, args) + 0.2


def test_w_method_keeps_order_two_with_a_wrong_matrix():
    def f(t, y, args):
        return jnp.array([y[1], -y[0] - 0.3 * y[1] ** 3])

    ref = diffrax.diffeqsolve(diffrax.ODETerm(f), diffrax.Tsit5(), 0.0, 2.0, 1e-3,
                              jnp.array([0.0, 1.0]), saveat=diffrax.SaveAt(t1=True),
                              stepsize_controller=diffrax.ConstantStepSize()).ys[-1]
    errors = [np.max(np.abs(_final(f, _OffJacobian(structured=False), h, [0.0, 1.0]) - ref))
              for h in H]
    assert np.all(_slopes(errors) > 1.8), errors


def test_registered_by_name():
    assert "ros34pw2" in SOLVERS
    solver = make_solver("ros34pw2")
    assert isinstance(solver, RosenbrockW) and solver.structured
    assert not make_solver("ros34pw2", linear_solver="dense").structured


def _case_b_error(scene, solver, ref, **kw):
    res = simulate(scene, 6.0, solver=solver, **kw)
    t_ref, t_ros = np.asarray(ref.tension_b[:, 0]), np.asarray(res.tension_b[:, 0])
    return res, np.sqrt(np.mean((t_ros - t_ref) ** 2)) / np.std(t_ref)


@pytest.mark.slow
def test_case_b_against_converged_kvaerno5():
    """Case B (N = 10, 6 s, slack and snap) at default tolerances: the fairlead
    tension within 0.3 % of its std of a converged Kvaerno5 run, with the
    element's W and with the exact Jacobian (band or dense: the same run)."""
    scene = case_b_scene(n=10)
    ref = simulate(scene, 6.0, solver="kvaerno5", rtol=1e-8, atol=1e-7)
    res, err = _case_b_error(scene, "ros34pw2", ref)
    t_ref, t_ros = np.asarray(ref.tension_b[:, 0]), np.asarray(res.tension_b[:, 0])
    print("ros34pw2 steps", int(res.num_steps), "rejected", int(res.num_rejected_steps),
          "error / std", err, "max tension", t_ref.max())
    assert t_ref.max() > 1.5e6  # it snaps
    assert err < 3e-3
    # ∂f/∂t (the driven fairlead) is needed: without it, at rtol 1e-4, the error grows
    no_ft = RosenbrockW(tableau=dataclasses.replace(ROS34PW2, gamma_sum=(0.0,) * 4))
    _, err_ft = _case_b_error(scene, RosenbrockW(), ref, rtol=1e-4, atol=1e-3)
    _, err_no_ft = _case_b_error(scene, no_ft, ref, rtol=1e-4, atol=1e-3)
    print("rtol 1e-4: error / std with ∂f/∂t", err_ft, "without", err_no_ft)
    assert err_no_ft > 1.5 * err_ft
    # the exact Jacobian's band (18 coloured JVPs) and the dense Jacobian give the
    # same run; the element's W (what "ros34pw2" uses) another, equally accurate
    exact_band = simulate(scene, 6.0, solver=RosenbrockW())
    dense = simulate(scene, 6.0, solver=RosenbrockW(structured=False))
    np.testing.assert_allclose(np.asarray(dense.tension_b[:, 0]),
                               np.asarray(exact_band.tension_b[:, 0]), rtol=1e-6,
                               atol=1e-6 * t_ref.max())
    _, err_exact = _case_b_error(scene, RosenbrockW(), ref)
    print("error / std with the exact Jacobian", err_exact)
    assert err_exact < 3e-3


@pytest.mark.slow
def test_ensemble_and_gradient():
    """vmap over two drag coefficients gives the single runs; d(mean tension)/d(Cd)
    through a fixed-step run matches a central difference."""
    from moorjax.ensemble import simulate_ensemble
    from moorjax.model.parameters import get_parameter, set_parameter

    base = case_b_scene(n=6)
    cd = float(get_parameter(base, "Cd"))
    members = [set_parameter(base, "Cd", cd * k) for k in (0.8, 1.2)]
    ens = simulate_ensemble(members, 2.0, solver="ros34pw2")
    for i, m in enumerate(members):
        one = simulate(m, 2.0, solver="ros34pw2")
        np.testing.assert_allclose(np.asarray(ens.tension_b[i]), np.asarray(one.tension_b),
                                   rtol=1e-5)

    from moorjax.dynamics.settings import plan
    from moorjax.dynamics.vector_field import pack
    from moorjax.statics import solve_line_statics

    y0 = pack(tuple(solve_line_statics(ln, base.env).state() for ln in base.lines))
    settings = plan(1.0, solver="ros34pw2", dt=0.01, scene=base)

    def mean_tension(x):
        scene = set_parameter(base, "Cd", x)
        return jnp.mean(settings.run(scene, y0).tension_b)

    g, fd, _ = gradient_and_central_difference(mean_tension, cd, 1e-4 * cd)
    print("d mean T / d Cd", g, "central difference", fd)
    assert abs(g - fd) < 1e-4 * abs(fd) + 1e-6


def test_equinox_module_is_hashable_static():
    # the tableau is static: two solvers of the same settings compile once
    a, b = RosenbrockW(), RosenbrockW()
    assert eqx.tree_equal(a, b)


@pytest.mark.parametrize("terms", ["all", "stiff only"])
def test_stiff_band_against_the_full_jacobian(terms):
    """The linear element's W (tension, seabed, drag differentiated on their own)
    against the band of the whole vector field's Jacobian (18 coloured JVPs).

    Without drag and added mass ("stiff only"), on moving nodes one of which is
    pressed into the seabed: exact. With them ("all"): the velocity columns are
    exact; the position columns leave out the tangent dependence of the added
    mass (a term ∝ the net force, i.e. the acceleration) and of the drag (∝ the
    relative velocity), so at rest in equilibrium they agree too."""
    from moorjax.dynamics.vector_field import pack, stiff_band, vector_field
    from moorjax.linalg.banded_solver import band_of
    from moorjax.statics import solve_line_statics

    scene = case_b_scene(n=8)
    if terms == "stiff only":
        scene = eqx.tree_at(lambda s: (s.lines[0].line_type.drag, s.lines[0].line_type.added_mass),
                            scene, (None, None), is_leaf=lambda x: x is None)
    y = pack(tuple(solve_line_statics(ln, scene.env).state() for ln in scene.lines))
    t = 0.0
    if terms == "stiff only":  # moving nodes, the first pressed 1 cm into the seabed
        y = tuple(q.at[:, 3:].add(0.3 * jnp.sin(jnp.arange(q.shape[0]))[:, None])
                  .at[0, 2].set(-80.01) for q in y)
        t = 1.3
    exact = band_of(lambda v: jax.jvp(lambda z: vector_field(t, z, scene), (y,), (v,))[1], y)[:3]
    approx = stiff_band(t, y, scene).bands()  # W in mass form, as 6×6 blocks
    for a, w in zip(exact, approx):
        a, w = np.asarray(a), np.asarray(w)
        scale = np.abs(a).max()
        np.testing.assert_allclose(w[:, :, 3:], a[:, :, 3:], atol=1e-12 * scale)  # ∂/∂v
        tol = 1e-12 if terms == "stiff only" else 1e-4  # the statics residual
        np.testing.assert_allclose(w[:, :, :3], a[:, :, :3], atol=tol * scale)  # ∂/∂r


@pytest.mark.parametrize("terms", ["all", "stiff only"])
def test_time_column_against_the_vector_fields_time_derivative(terms):
    """W's time column (the linear element in steady water: the end nodes'
    couplings times the ends' velocity and acceleration) against ∂f/∂t of the
    whole vector field (forward mode in t). Without drag and added mass: exact.
    With them: the tangent dependence of the added mass and of the drag on the
    end's position is left out, as in W's position columns. Only the
    accelerations of the two nodes next to the ends are not zero."""
    from moorjax.dynamics.vector_field import pack, stiff_linearisation, vector_field
    from moorjax.statics import solve_line_statics

    scene = case_b_scene(n=8)
    if terms == "stiff only":
        scene = eqx.tree_at(lambda s: (s.lines[0].line_type.drag, s.lines[0].line_type.added_mass),
                            scene, (None, None), is_leaf=lambda x: x is None)
    y = pack(tuple(solve_line_statics(ln, scene.env).state() for ln in scene.lines))
    y = tuple(q.at[:, 3:].add(0.3 * jnp.sin(jnp.arange(q.shape[0]))[:, None]) for q in y)
    t = 1.3
    exact = jax.jvp(lambda s: vector_field(s, y, scene), (t,), (1.0,))[1]
    band, time = stiff_linearisation(t, y, scene)
    assert band is not None and time is not None
    for a, w in zip(exact, time):
        a, w = np.asarray(a), np.asarray(w)
        scale = np.abs(a).max()
        assert scale > 0  # the fairlead moves
        np.testing.assert_array_equal(w[:, :3], 0.0)
        np.testing.assert_array_equal(w[1:-1], 0.0)
        tol = 1e-12 if terms == "stiff only" else 0.05
        print(terms, "largest difference / largest ∂f/∂t", np.abs(w - a).max() / scale)
        np.testing.assert_allclose(w, a, atol=tol * scale)


def test_no_time_column_where_the_water_moves():
    """Waves or a current that changes in time make the equations depend on t
    at every node: W then has no time column and the stepper differences the
    vector field in t."""
    from moorjax.dynamics.vector_field import pack, stiff_linearisation
    from moorjax.model.environment import TimeProfileCurrent, UniformCurrent
    from moorjax.model.waves import AiryWaves, IrregularWave
    from moorjax.statics import solve_line_statics

    scene = case_b_scene(n=6)
    y = pack(tuple(solve_line_statics(ln, scene.env).state() for ln in scene.lines))
    steady = eqx.tree_at(lambda s: s.env.current, scene, UniformCurrent([0.5, 0.0, 0.0]),
                         is_leaf=lambda x: x is None)
    assert steady.env.steady and stiff_linearisation(0.0, y, steady)[1] is not None
    tidal = eqx.tree_at(lambda s: s.env.current, scene,
                        TimeProfileCurrent([0.0, 10.0], [-100.0, 0.0],
                                           [[[0.0, 0, 0], [0.2, 0, 0]], [[0.0, 0, 0], [0.4, 0, 0]]]),
                        is_leaf=lambda x: x is None)
    waves = eqx.tree_at(lambda s: s.env.waves, scene,
                        AiryWaves(IrregularWave(0.6, 1.0, 0.0), scene.env.depth),
                        is_leaf=lambda x: x is None)
    for moving in (tidal, waves):
        assert not moving.env.steady
        band, time = stiff_linearisation(0.0, y, moving)
        assert band is not None and time is None


def test_auto_picks_the_method_by_scene():
    from moorjax.dynamics.settings import plan, resolve_solver
    from moorjax.element import HermiteElement

    scene = case_b_scene(n=4)
    assert resolve_solver("auto", scene) == "ros34pw2"
    assert resolve_solver("auto") == "kvaerno5"  # no scene to look at
    hermite = eqx.tree_at(lambda s: s.lines[0].element, scene, HermiteElement())
    assert resolve_solver("auto", hermite) == "kvaerno5"
    assert resolve_solver("kvaerno3", scene) == "kvaerno3"
    p = plan(1.0, scene=scene, solver="auto")  # auto is the default
    assert p.name == "ros34pw2" and isinstance(p.solver, RosenbrockW)
    assert plan(1.0, scene=scene).name == "ros34pw2"
    # at the tolerances as given (the controller measures segment chords too)
    assert float(p.controller.rtol) == 1e-5 and float(p.controller.atol) == 1e-4
    assert p.controller.segments == (4,)
    p = plan(1.0, scene=scene, solver="ros34pw2")  # named: the tolerances as given
    assert float(p.controller.rtol) == 1e-5 and float(p.controller.atol) == 1e-4
    k = plan(1.0, scene=scene, solver="kvaerno5")
    assert k.name == "kvaerno5" and float(k.controller.rtol) == 1e-5
    assert plan(1.0, scene=hermite).name == "kvaerno5"
