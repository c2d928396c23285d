"""The persistent compilation cache (moorjax._cache)."""

import os
import subprocess
import sys

import pytest

from moorjax import _cache

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_cache_dir_resolution(monkeypatch, tmp_path):
    monkeypatch.delenv("MOORJAX_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert _cache.cache_dir() == str(tmp_path / "xdg" / "moorjax" / "jax")
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert _cache.cache_dir() == str(tmp_path / "home" / ".cache" / "moorjax" / "jax")
    monkeypatch.setenv("MOORJAX_CACHE_DIR", str(tmp_path / "mine"))
    assert _cache.cache_dir() == str(tmp_path / "mine" / "jax")


def test_switch(monkeypatch):
    for off in ("0", "false", "OFF", "no"):
        monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", off)
        assert not _cache.enabled()
    monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", "1")
    assert _cache.enabled()
    monkeypatch.delenv("MOORJAX_COMPILATION_CACHE")
    assert _cache.enabled()


def _cache_dir_after_import(env):
    code = "import moorjax, jax; print(jax.config.jax_compilation_cache_dir or '')"
    env = dict(os.environ, PYTHONPATH=ROOT, **env)
    env.pop("JAX_COMPILATION_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True)
    return out.stdout.strip().splitlines()[-1] if out.stdout.strip() else ""


def test_import_turns_the_cache_on_and_off(tmp_path):
    on = _cache_dir_after_import({"MOORJAX_CACHE_DIR": str(tmp_path), "MOORJAX_COMPILATION_CACHE": "1"})
    assert on == str(tmp_path / "jax") and os.path.isdir(on)
    off = _cache_dir_after_import({"MOORJAX_CACHE_DIR": str(tmp_path / "x"),
                                   "MOORJAX_COMPILATION_CACHE": "0"})
    assert off == ""


# -- the integration is kept in the persistent cache ---------------------------

def _small_run():
    import equinox as eqx

    import moorjax as mj
    from moorjax.dynamics.initial import equilibrium_state
    from moorjax.dynamics.settings import plan
    from moorjax.dynamics.vector_field import pack
    from moorjax.examples import example_path
    from moorjax.io import build_scene, read_deck

    scene = build_scene(read_deck(example_path("oc3_catenary")), segments=4)
    scene = eqx.tree_at(lambda s: s.lines[0].end_b, scene,
                        mj.SinePath((-5.2, 0.0, -70.0), (1.0, 0.0, 0.0), 10.0))
    return scene, pack(equilibrium_state(scene, 0.0).state), plan(1.0, scene=scene)


def test_integration_compiles_without_host_callbacks():
    """JAX never caches a program with host callbacks: the compiled integration of
    host-checked settings has none (diffrax's input checks, which plan() makes on
    the host, compile to NaN selects), so a new process loads it from the cache."""
    import equinox as eqx
    import jax

    from moorjax.dynamics.integrate import integrate

    scene, y0, p = _small_run()
    assert p.host_checked
    text = eqx.filter_jit(integrate).lower(scene, y0, p).as_text()
    assert "callback" not in text
    # witness: the same lowering shows a runtime check that stays a host callback
    f = jax.jit(lambda x: eqx.error_if(x, x < 0, "negative"))
    assert "callback" in f.lower(1.0).as_text()


def test_checks_switch_back_after_the_trace():
    import equinox as eqx
    import jax.numpy as jnp

    from equinox import _errors

    before = _errors.EQX_ON_ERROR
    with _cache.host_checked_inputs():
        assert _errors.EQX_ON_ERROR == ("nan" if before == "raise" else before)
    assert _errors.EQX_ON_ERROR == before
    # a user's own check outside moorjax's integration still raises
    f = eqx.filter_jit(lambda x: eqx.error_if(x, x < 0, "negative"))
    try:
        f(jnp.asarray(-1.0))
    except Exception as exc:  # EquinoxRuntimeError / JaxRuntimeError
        assert "negative" in str(exc)
    else:
        raise AssertionError("error_if did not raise")


def test_traced_output_times_keep_diffrax_checks():
    import jax

    from moorjax.dynamics.settings import plan

    flags = []

    def build(ts):
        flags.append(plan(ts=ts).host_checked)
        return ts

    jax.jit(build)(jax.numpy.linspace(0.1, 1.0, 4))
    assert flags == [False]
    assert plan(1.0).host_checked


def test_first_step_must_be_positive():
    import pytest

    from moorjax.dynamics.settings import plan

    for bad in (-0.01, 0.0, float("nan")):
        with pytest.raises(ValueError, match="dt0"):
            plan(1.0, dt0=bad)


# -- programs stored by structure (StoredProgram) --------------------------------

def _program_fixture():
    import equinox as eqx
    import jax.numpy as jnp

    class Spring(eqx.Module):
        k: object  # [N/m]
        n: int = eqx.field(static=True)

    traces = []

    def force(spring, x, *, scale=1.0):
        traces.append(1)  # runs at trace time only
        return {"f": -spring.k * x[: spring.n] * scale, "n": spring.n}

    return Spring, traces, force, jnp


def test_stored_program_loads_without_tracing(monkeypatch, tmp_path):
    import jax

    monkeypatch.setattr(_cache, "TRUSTED", _cache.TRUSTED + (__name__.split(".")[0],))
    monkeypatch.setenv("MOORJAX_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", "1")
    Spring, traces, force, jnp = _program_fixture()
    x = jnp.arange(4.0)
    first = _cache.StoredProgram(force)
    out = first(Spring(jnp.asarray(2.0), 3), x)
    assert traces == [1] and out["n"] == 3
    np_out = jax.device_get(out["f"])
    assert list(np_out) == [-0.0, -2.0, -4.0]
    assert len([p for p in os.listdir(tmp_path / "programs") if p.endswith(".hlo")]) == 1
    # "a new process": a fresh wrapper finds the program on disk and never traces
    again = _cache.StoredProgram(force)
    out = again(Spring(jnp.asarray(3.0), 3), x)  # other values, same structure
    assert traces == [1] and list(jax.device_get(out["f"])) == [-0.0, -3.0, -6.0]
    # another structure (static field, static keyword, shape) is another program
    again(Spring(jnp.asarray(3.0), 2), x)
    again(Spring(jnp.asarray(3.0), 3), x, scale=2.0)
    again(Spring(jnp.asarray(3.0), 3), jnp.arange(5.0))
    assert traces == [1, 1, 1, 1]
    # traced arguments (under the caller's transform) use the plain jit
    g = jax.grad(lambda k: again(Spring(k, 3), x)["f"].sum())(jnp.asarray(1.0))
    assert float(g) == -3.0


def test_compile_ahead_serves_the_next_call(monkeypatch, tmp_path):
    """compile_ahead traces now (shapes only) and compiles on a thread; the next
    call of that structure uses that program: no second trace, same answer."""
    import jax

    monkeypatch.setattr(_cache, "TRUSTED", _cache.TRUSTED + (__name__.split(".")[0],))
    monkeypatch.setenv("MOORJAX_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", "1")
    Spring, traces, force, jnp = _program_fixture()
    program = _cache.StoredProgram(force)
    spec = jax.ShapeDtypeStruct((4,), jnp.zeros(()).dtype)
    assert program.compile_ahead(Spring(jnp.asarray(2.0), 3), spec)
    assert traces == [1] and len(program._ahead) == 1
    out = program(Spring(jnp.asarray(5.0), 3), jnp.arange(4.0))
    assert traces == [1] and not program._ahead
    assert list(jax.device_get(out["f"])) == [-0.0, -5.0, -10.0] and out["n"] == 3
    # prepared for one shape, called with another: that call compiles its own
    assert program.compile_ahead(Spring(jnp.asarray(2.0), 3), jax.ShapeDtypeStruct((6,), spec.dtype))
    out = program(Spring(jnp.asarray(1.0), 3), jnp.arange(5.0))
    assert list(jax.device_get(out["f"])) == [-0.0, -1.0, -2.0] and not program._ahead
    # clear_programs lets the compiled programs go (the files stay)
    assert program._programs
    _cache.clear_programs()
    assert not program._programs and not program._ahead
    # switched off: nothing prepared, the call compiles as before
    monkeypatch.setenv("MOORJAX_COMPILE_AHEAD", "0")
    assert not program.compile_ahead(Spring(jnp.asarray(2.0), 2), spec) and not program._ahead
    monkeypatch.delenv("MOORJAX_COMPILE_AHEAD")
    # nothing is prepared where no stored program would serve the call
    monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", "0")
    assert not _cache.StoredProgram(force).compile_ahead(Spring(jnp.asarray(2.0), 3), spec)


def test_a_repeated_call_reads_no_package_metadata(monkeypatch, tmp_path):
    """A stored program's key holds the packages' versions and the arguments'
    structure; both are read once per process, not on every call (reading the
    installed distributions cost about 12 ms per call: a 20 s run of reference
    case B integrates in about 20 ms)."""
    from importlib import metadata

    monkeypatch.setattr(_cache, "TRUSTED", _cache.TRUSTED + (__name__.split(".")[0],))
    monkeypatch.setenv("MOORJAX_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", "1")
    Spring, traces, force, jnp = _program_fixture()
    program = _cache.StoredProgram(force)
    program(Spring(jnp.asarray(2.0), 3), jnp.arange(4.0))
    reads, described = [], []
    monkeypatch.setattr(metadata, "version", lambda dist: reads.append(dist) or "0")
    real = _cache._describe
    monkeypatch.setattr(_cache, "_describe", lambda *a: described.append(1) or real(*a))
    for k in range(3):
        out = program(Spring(jnp.asarray(float(k)), 3), jnp.arange(4.0))
        assert float(out["f"][1]) == -float(k)
    assert reads == [] and described == [] and traces == [1]


def test_equal_static_values_of_other_types_are_other_programs(monkeypatch, tmp_path):
    """Keys are kept per argument structure (computing one cost 0.4 ms a call);
    static values that are equal but of other types (1 == 1.0) are other
    structures, as their texts are: each is traced, neither reuses the other."""
    monkeypatch.setattr(_cache, "TRUSTED", _cache.TRUSTED + (__name__.split(".")[0],))
    monkeypatch.setenv("MOORJAX_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", "1")
    Spring, traces, force, jnp = _program_fixture()
    program = _cache.StoredProgram(force)
    x = jnp.arange(4.0)
    keys = set()
    for scale in (2, 2.0, 2, 2.0):
        program(Spring(jnp.asarray(1.0), 3), x, scale=scale)
        keys.update(program._keys.values())
    assert traces == [1, 1] and len(keys) == 2 and len(program._programs) == 2


def test_code_outside_moorjax_is_never_loaded(monkeypatch, tmp_path):
    """A user's own class (its code is not in the key) is traced every time."""
    monkeypatch.setenv("MOORJAX_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", "1")
    Spring, traces, force, jnp = _program_fixture()
    out = _cache.StoredProgram(force)(Spring(jnp.asarray(2.0), 3), jnp.arange(4.0))
    assert float(out["f"][1]) == -2.0
    assert not (tmp_path / "programs").exists()


def test_stored_program_off_and_unstorable(monkeypatch, tmp_path):
    import jax

    monkeypatch.setattr(_cache, "TRUSTED", _cache.TRUSTED + (__name__.split(".")[0],))
    monkeypatch.setenv("MOORJAX_CACHE_DIR", str(tmp_path))
    Spring, traces, force, jnp = _program_fixture()
    monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", "0")
    _cache.StoredProgram(force)(Spring(jnp.asarray(2.0), 3), jnp.arange(4.0))
    assert not (tmp_path / "programs").exists()
    monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", "1")

    def noisy(x):
        jax.debug.callback(lambda v: None, x)  # host callbacks cannot be exported
        return 2 * x

    assert float(_cache.StoredProgram(noisy)(jnp.asarray(1.5))) == 3.0
    assert any(p.endswith(".none") for p in os.listdir(tmp_path / "programs"))
    assert float(_cache.StoredProgram(noisy)(jnp.asarray(2.5))) == 5.0


_RUN = """
import json, sys, jax.monitoring
traced = []
jax.monitoring.register_event_duration_secs_listener(
    lambda event, duration, **kw: traced.append(kw.get("fun_name"))
    if event.endswith("jaxpr_trace_duration") else None)
sys.path.insert(0, {root!r})
sys.path.insert(0, {tests!r})
from test_speed_cache import _small_run
from moorjax.dynamics import simulate
scene, y0, p = _small_run()
res = simulate(scene, 1.0)
print(json.dumps(dict(traced=traced, tension=float(res.tension_b[-1, 0]))))
"""


@pytest.mark.slow
def test_a_new_process_neither_traces_nor_compiles_the_run(tmp_path):
    """The same structure in a second process: the statics and the integration
    are loaded from disk (no tracing), and the result is the same."""
    import json

    env = dict(os.environ, PYTHONPATH=ROOT, MOORJAX_CACHE_DIR=str(tmp_path),
               MOORJAX_COMPILATION_CACHE="1")
    code = _RUN.format(root=ROOT, tests=os.path.join(ROOT, "tests"))
    runs = [json.loads(subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                                      text=True, check=True).stdout.strip().splitlines()[-1])
            for _ in range(2)]
    assert {"integrate", "_solve_core"} & set(runs[1]["traced"]) == set()
    assert "flat" in runs[0]["traced"] and "flat" not in runs[1]["traced"]
    assert runs[0]["tension"] == runs[1]["tension"]


def test_an_impossible_line_stops_before_anything_compiles(monkeypatch, tmp_path):
    """simulate checks the geometry before it hands the integration's compile
    to a background thread: a line that cannot reach its ends raises at once."""
    import importlib

    import equinox as eqx
    import jax.numpy as jnp

    from moorjax.dynamics import simulate
    from moorjax.examples import example
    from moorjax.io import build_scene, read_deck

    monkeypatch.setenv("MOORJAX_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", "1")
    scene = build_scene(read_deck(example("oc3_catenary").deck))
    far = eqx.tree_at(lambda s: s.lines[0].length, scene, jnp.asarray(10.0))
    program = importlib.import_module("moorjax.dynamics.simulate")._integrate
    with pytest.raises(ValueError, match="impossible geometry"):
        simulate(far, 1.0)
    assert not program._ahead


def _programs_built(fn):
    """Names of the XLA programs lowered while ``fn()`` runs (after clearing JAX's
    in-memory caches, so that programs built earlier in the process count too)."""
    import jax

    jax.clear_caches()
    built = []

    def listen(event, duration, **kw):
        if event.endswith("jaxpr_to_mlir_module_duration"):
            built.append(kw.get("fun_name"))

    jax.monitoring.register_event_duration_secs_listener(listen)
    try:
        out = fn()
    finally:
        jax.monitoring.unregister_event_duration_listener(listen)
    return out, built


def test_building_a_scene_and_checking_it_run_no_eager_operations():
    """Each eager jnp operation on concrete values is a small XLA program of its
    own, compiled (or loaded) once per process: a deck's scene is built without
    any, and its geometry check (a tabulated fairlead motion looked up at t0)
    and the start's assembly are one small program each."""
    from moorjax.dynamics.initial import check_geometry
    from moorjax.examples import example
    from moorjax.io import build_scene, read_deck
    from moorjax.io.build import read_deck_motion

    ex = example("oc3_catenary")
    deck = read_deck(ex.deck)
    motion = read_deck_motion(ex.motion, deck)
    scene, built = _programs_built(lambda: build_scene(deck, motion=motion))
    assert built == []
    _, built = _programs_built(lambda: check_geometry(scene, 0.0))
    assert built == ["jit(_end_positions)"]


def test_a_body_scene_is_built_and_checked_with_few_programs():
    """A free body's constructor checks its mass matrix and equinox reads its
    hydrostatic stiffness: one small program each (before: 117 eager operations
    for the three-chain buoy deck); its geometry check attaches the lines at
    rest in one more."""
    from moorjax.dynamics.initial import check_geometry
    from moorjax.io import build_scene, read_deck

    deck = read_deck(os.path.join(ROOT, "tests", "data", "free_body_buoy.dat"))
    scene, built = _programs_built(lambda: build_scene(deck))
    assert sorted(built) == ["jit(_hydrostatic)", "jit(_rest_mass_matrix)"], built
    _, built = _programs_built(lambda: check_geometry(scene, 0.0))
    assert sorted(set(built)) == ["jit(_attached_at_rest)", "jit(_end_positions)"], built


def test_settings_planned_while_tracing_keep_no_tracers():
    """``plan`` shares the solver and controller of equal settings across calls;
    one planned under the caller's ``jit`` (``simulate`` inside a traced
    function) must not leave that trace's tracers in them for later calls."""
    import jax

    from moorjax.dynamics import settings

    for cached in (settings._norm, settings._solver, settings._adaptive):
        cached.cache_clear()
    kw = dict(solver="ros34pw2", rtol=3e-4, atol=3e-3)
    inside = jax.jit(lambda x: settings.plan(1.0, **kw).controller.rtol * x)(2.0)
    later = settings.plan(1.0, **kw)
    leaves = jax.tree_util.tree_leaves((later.solver, later.controller))
    assert not any(isinstance(x, jax.core.Tracer) for x in leaves)
    assert settings._adaptive.cache_info().hits == 1  # the traced plan's controller, shared
    assert float(inside) == 2.0 * float(later.controller.rtol) == 6e-4


def test_a_repeated_run_dispatches_only_its_integration(monkeypatch, tmp_path):
    """A second ``simulate`` of the same structure from a given start runs one XLA
    program, the integration: the settings' times and the packed start go to it
    as NumPy arrays and its success is read on the host. Each eager operation
    (``jnp.concatenate``, ``result == successful``, a ``device_put`` per time)
    cost 10–60 µs of host time per call (case B integrates 20 s in about 8 ms)."""
    import jax

    from moorjax.dynamics import simulate
    from moorjax.examples import example
    from moorjax.io import build_scene, read_deck
    from moorjax.statics.fem import solve_line_statics

    monkeypatch.setenv("MOORJAX_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", "1")
    scene = build_scene(read_deck(example("oc3_catenary").deck), segments=6)
    init = tuple(solve_line_statics(ln, scene.env, 0.0).state() for ln in scene.lines)
    first = simulate(scene, 0.2, init=init, solver="ros34pw2")
    puts = []
    real_put = jax.device_put
    monkeypatch.setattr(jax, "device_put", lambda *a, **k: puts.append(a) or real_put(*a, **k))
    again, built = _programs_built(lambda: simulate(scene, 0.2, init=init, solver="ros34pw2"))
    assert built == ["jit(call)"], built
    assert puts == []
    assert int(again.num_steps) == int(first.num_steps)
    assert (again.tension_b == first.tension_b).all()
