"""The stage-state Newton test of the implicit methods (moorjax.dynamics.newton)."""

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import moorjax  # noqa: F401  (float64)
from moorjax.dynamics.newton import StageChord, VeryChord, stage_arguments
from moorjax.dynamics.solvers import make_solver


def _stiff_problem():
    """ẋ = v, v̇ = −k x − c v (k = 1e4, c = 50): a stiff damped oscillator, (1, 6) state."""
    k, c = 1e4, 50.0

    def vf(t, y, args):
        r, v = y[:, :3], y[:, 3:]
        return jnp.concatenate([v, -k * r - c * v], axis=-1)

    y0 = jnp.array([[1e-2, -2e-2, 3e-2, 0.0, 0.0, 0.0]])
    return diffrax.ODETerm(vf), y0


def _solve(root_finder, dt=None):
    term, y0 = _stiff_problem()
    solver = diffrax.Kvaerno5(root_finder=root_finder)
    if dt is None:
        ctrl = diffrax.PIDController(rtol=1e-6, atol=1e-8)
    else:
        ctrl = diffrax.ConstantStepSize()
    return diffrax.diffeqsolve(term, solver, 0.0, 0.5, dt or 1e-3, y0, stepsize_controller=ctrl,
                               max_steps=100_000, throw=False)


def test_diffrax_passes_the_stage_layout():
    """Pins diffrax's f-space stage arguments (stage_index, γ, vf, prod, t_i, ŷ_i,
    args, h) that StageChord reads: if a diffrax release changes them, this fails."""
    seen = []

    class Spy(StageChord):
        def step(self, fn, y, args, options, state, tags):
            stage = stage_arguments(args)
            seen.append(None if stage is None else (stage[0].shape == y.shape, args[1], args[7]))
            return super().step(fn, y, args, options, state, tags)

    sol = _solve(diffrax.with_stepsize_controller_tols(Spy)())
    assert sol.result == diffrax.RESULTS.successful
    assert seen and all(s is not None and s[0] for s in seen)


def test_explicit_start_is_the_identity_without_a_jacobian(monkeypatch):
    """diffrax asks the root finder for an iteration matrix twice per step: before
    its stage loop (for an ESDIRK method the explicit first stage's, zero
    diagonal: the identity) and in its second stage (the step's own).
    ``explicit_start`` tells them apart by diffrax's calling lambda; the first is
    factored from the identity relation, without a derivative of the vector
    field (a vector field with a sine: the sine appears in the step's program
    once less), and gives what the old start (I − 0·J from the
    relation) gave: the same run."""
    from moorjax.dynamics import newton

    calls = []

    class Spy(StageChord):
        def init(self, fn, y, args, options, f_struct, aux_struct, tags):
            if "init_state" not in options:
                calls.append(newton.explicit_start(fn))
            return super().init(fn, y, args, options, f_struct, aux_struct, tags)

    def vf(t, y, args):  # a stiff pendulum
        r, v = y[:, :3], y[:, 3:]
        return jnp.concatenate([v, -1e4 * jnp.sin(r) - 50.0 * v], axis=-1)

    y0 = jnp.array([[1e-2, -2e-2, 3e-2, 0.0, 0.0, 0.0]])
    solver = diffrax.Kvaerno5(root_finder=diffrax.with_stepsize_controller_tols(Spy)())

    def run(y):
        return diffrax.diffeqsolve(diffrax.ODETerm(vf), solver, 0.0, 0.5, 1e-3, y,
                                   stepsize_controller=diffrax.PIDController(rtol=1e-6, atol=1e-8),
                                   max_steps=100_000, throw=False)

    new = run(y0)
    sines_new = str(jax.make_jaxpr(lambda y: run(y).ys)(y0)).count(" sin ")
    assert calls.count(True) >= 1 and calls.count(False) >= 1, calls
    monkeypatch.setattr(newton, "explicit_start", lambda fn: False)  # the start from the relation
    jax.clear_caches()  # diffrax's jitted loop traced anew
    old = run(y0)
    sines_old = str(jax.make_jaxpr(lambda y: run(y).ys)(y0)).count(" sin ")
    assert 0 < sines_new < sines_old, (sines_new, sines_old)
    assert new.result == old.result == diffrax.RESULTS.successful
    assert int(new.stats["num_steps"]) == int(old.stats["num_steps"])
    np.testing.assert_allclose(np.asarray(new.ys), np.asarray(old.ys), rtol=1e-12, atol=1e-15)


def test_stage_chord_accuracy_matches_very_chord():
    """Same answer as diffrax's f-space test (both within the controller's tolerance)."""
    a = _solve(diffrax.with_stepsize_controller_tols(VeryChord)())
    b = _solve(diffrax.with_stepsize_controller_tols(StageChord)())
    assert a.result == b.result == diffrax.RESULTS.successful
    scale = float(jnp.max(jnp.abs(a.ys)))
    assert np.max(np.abs(np.asarray(a.ys - b.ys))) < 1e-4 * max(scale, 1e-3) + 1e-7


@pytest.mark.parametrize("refresh", [None, 0.25])
def test_stage_chord_at_fixed_steps(refresh):
    """Fixed steps of half the damping time scale 1/c, 5 oscillator time scales:
    Newton converges (also with the matrix rebuilt on slow contraction) and the
    state follows the adaptive solution."""
    sol = _solve(StageChord(rtol=1e-6, atol=1e-8, refresh_rate=refresh), dt=1e-2)
    ref = _solve(diffrax.with_stepsize_controller_tols(VeryChord)())
    assert sol.result == diffrax.RESULTS.successful
    assert np.all(np.isfinite(np.asarray(sol.ys)))
    assert np.max(np.abs(np.asarray(sol.ys - ref.ys))) < 1e-3


@pytest.mark.parametrize("name", ["kvaerno3", "kvaerno5"])
def test_make_solver_takes_the_chord_class(name):
    assert isinstance(make_solver(name, newton=StageChord).root_finder, StageChord)
    assert isinstance(make_solver(name, newton=VeryChord).root_finder, VeryChord)


def test_other_layouts_fall_back():
    assert stage_arguments((1, 2, 3)) is None
    assert stage_arguments(None) is None


def test_refresh_under_vmap_matches_single_runs():
    """Ensembles: the rebuild (taken when any member is slow) gives each member
    the answer of its own run, within the tolerance."""
    import jax

    def run(c):
        def vf(t, y, args):
            r, v = y[:, :3], y[:, 3:]
            return jnp.concatenate([v, -1e4 * r - c * v * (1.0 + 1e2 * r**2)], axis=-1)

        y0 = jnp.array([[1e-1, -2e-1, 3e-1, 0.0, 0.0, 0.0]])
        chord = diffrax.with_stepsize_controller_tols(StageChord)(refresh_rate=0.5)
        solver = diffrax.Kvaerno5(root_finder=chord)
        sol = diffrax.diffeqsolve(diffrax.ODETerm(vf), solver, 0.0, 0.2, 1e-3, y0,
                                  stepsize_controller=diffrax.PIDController(rtol=1e-6, atol=1e-8),
                                  max_steps=100_000, throw=False)
        return sol.ys[-1], sol.result

    cs = jnp.array([5.0, 50.0, 500.0])
    ys, results = jax.vmap(run)(cs)
    assert bool(jnp.all(results == diffrax.RESULTS.successful))
    for i, c in enumerate(cs):
        y, _ = run(c)
        assert np.max(np.abs(np.asarray(ys[i] - y))) < 1e-5
