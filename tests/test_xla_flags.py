"""moorjax's XLA:CPU settings (moorjax._xla_flags): the schedule flag, added at
import while JAX has not started, never over the user's choice, changes no
result; the per-program compiler options are taken at the top level only, are
dropped where XLA does not know them, and change results by rounding only."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from moorjax import _cache, _xla_flags

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FLAG = f"--{_xla_flags.FLAG}"


def _env(**extra):
    env = {k: v for k, v in os.environ.items()
           if k not in ("XLA_FLAGS", "MOORJAX_XLA_TUNING", "MOORJAX_XLA_OPTIONS", "PJRT_NPROC",
                        "JAX_PLATFORMS")}
    env.update(PYTHONPATH=ROOT, MOORJAX_COMPILATION_CACHE="0", **extra)
    return env


def _variable_after(name, code, **extra):
    """The environment variable ``name`` in a fresh process after ``code``."""
    show = f"\nimport json, os; print(json.dumps(os.environ.get({name!r})))"
    out = subprocess.run([sys.executable, "-c", code + show], env=_env(**extra), capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _flags_after(code, **extra):
    return _variable_after("XLA_FLAGS", code, **extra)


def test_import_adds_the_flag_and_keeps_the_users_flags():
    assert _flags_after("import moorjax") == f"{FLAG}=false"
    kept = "--xla_force_host_platform_device_count=2"
    assert _flags_after("import moorjax", XLA_FLAGS=kept) == f"{kept} {FLAG}=false"


def test_the_users_choice_and_the_switch_win():
    assert _flags_after("import moorjax", XLA_FLAGS=f"{FLAG}=true") == f"{FLAG}=true"
    for off in ("0", "false", "OFF", "no"):
        assert _flags_after("import moorjax", MOORJAX_XLA_TUNING=off) is None


def test_nothing_is_added_once_jax_has_computed():
    # XLA has read its flags by then: adding one would only mislead
    assert _flags_after("import jax.numpy as jnp; jnp.ones(2).block_until_ready(); import moorjax") is None


def test_wanted_reads_the_switch(monkeypatch):
    monkeypatch.delenv("MOORJAX_XLA_TUNING", raising=False)
    assert _xla_flags.wanted()
    monkeypatch.setenv("MOORJAX_XLA_TUNING", " Off ")
    assert not _xla_flags.wanted()
    assert not _xla_flags.prefer_sequential_schedule()


_RUN = """
import json, sys
sys.path.insert(0, {tests!r})
from test_speed_cache import _small_run
from moorjax.dynamics import simulate
scene, y0, p = _small_run()
res = simulate(scene, 1.0)
print(json.dumps(dict(steps=int(res.num_steps), tension=[float(x) for x in res.tension_b[:, 0]])))
"""


def test_the_schedule_changes_no_number():
    """An implicit run of a moving catenary with and without the flag: the same
    steps and the same tensions to the last bit (the flag orders XLA's work, it
    does not change it)."""
    # the per-program options (which MOORJAX_XLA_TUNING=0 also drops) held off in both
    runs = [_small_run_in_a_process(MOORJAX_XLA_TUNING=v, MOORJAX_XLA_OPTIONS="0") for v in ("1", "0")]
    assert runs[0]["steps"] == runs[1]["steps"] > 0
    assert runs[0]["tension"] == runs[1]["tension"]


def _small_run_in_a_process(**extra):
    code = _RUN.format(tests=os.path.join(ROOT, "tests"))
    out = subprocess.run([sys.executable, "-c", code], env=_env(**extra), capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_compiler_options_change_numbers_by_rounding_only():
    """The same run compiled with moorjax's per-program options (the default)
    and with XLA's defaults: the statics and the steps differ by rounding, so
    the tensions agree to far below the run's tolerance (rtol 1e-5)."""
    runs = [_small_run_in_a_process(MOORJAX_XLA_OPTIONS=v) for v in ("1", "0")]
    a, b = (np.asarray(r["tension"]) for r in runs)
    assert a.shape == b.shape and runs[0]["steps"] > 0
    np.testing.assert_allclose(a, b, rtol=1e-7)


def test_compiler_option_presets_and_their_switches(monkeypatch):
    for name in ("MOORJAX_XLA_TUNING", "MOORJAX_XLA_OPTIONS"):
        monkeypatch.delenv(name, raising=False)
    assert _xla_flags.compiler_options("runs") == {"xla_cpu_use_fusion_emitters": False}
    assert _xla_flags.compiler_options("once") == {"xla_cpu_use_fusion_emitters": False,
                                                   "xla_backend_optimization_level": 0}
    assert _xla_flags.compiler_options("members") == {"xla_cpu_use_fusion_emitters": False,
                                                      "xla_cpu_experimental_ynn_fusion_type": ""}
    for name in ("MOORJAX_XLA_TUNING", "MOORJAX_XLA_OPTIONS"):
        monkeypatch.setenv(name, "off")
        assert _xla_flags.compiler_options("runs") is None
        monkeypatch.delenv(name)


def _spring():
    import jax.numpy as jnp

    seen = []  # the options a call would take, recorded while tracing

    def force(k, x):
        seen.append(program.compiler_options())
        return -k * x

    program = _cache.StoredProgram(force, compile_for="once")
    return program, seen, jnp


@pytest.mark.parametrize("stored", ["1", "0"])
def test_a_program_takes_its_options_at_the_top_level_only(monkeypatch, tmp_path, stored):
    """Called directly, a program compiles with its preset, stored on disk or
    not; called under the caller's ``jit``, ``grad`` or ``vmap`` it is inlined
    into the caller's program (a nested ``jit`` may not carry options)."""
    import jax

    monkeypatch.setattr(_cache, "TRUSTED", _cache.TRUSTED + (__name__.split(".")[0],))
    monkeypatch.setenv("MOORJAX_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("MOORJAX_COMPILATION_CACHE", stored)
    monkeypatch.delenv("MOORJAX_XLA_OPTIONS", raising=False)
    monkeypatch.delenv("MOORJAX_XLA_TUNING", raising=False)
    program, seen, jnp = _spring()
    x = jnp.arange(3.0)
    assert list(jax.device_get(program(jnp.asarray(2.0), x))) == [-0.0, -2.0, -4.0]
    assert program.compiler_options() == _xla_flags.compiler_options("once")
    assert float(jax.jit(lambda k: program(k, x).sum())(jnp.asarray(1.0))) == -3.0
    assert float(jax.jit(lambda: program(jnp.asarray(1.0), x).sum())()) == -3.0  # constants only
    assert float(jax.grad(lambda k: program(k, x).sum())(jnp.asarray(1.0))) == -3.0
    assert jax.vmap(lambda k: program(k, x))(jnp.ones(2)).shape == (2, 3)
    assert seen and all(s is None for s in seen)  # never asked for inside a trace


def test_an_option_xla_does_not_know_is_dropped(monkeypatch, tmp_path):
    """A jaxlib that does not know an option refuses the compile with an error
    (an unknown flag in ``XLA_FLAGS`` would end the process): the call is made
    again without options, and no program takes them from then on."""
    import jax

    monkeypatch.setattr(_cache, "TRUSTED", _cache.TRUSTED + (__name__.split(".")[0],))
    monkeypatch.setenv("MOORJAX_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("MOORJAX_XLA_OPTIONS", raising=False)
    monkeypatch.delenv("MOORJAX_XLA_TUNING", raising=False)
    monkeypatch.setitem(_xla_flags.PRESETS, "once", (("xla_cpu_no_such_option", True),))
    monkeypatch.setattr(_xla_flags, "_rejected", [])
    program, _, jnp = _spring()
    assert program.compiler_options() == {"xla_cpu_no_such_option": True}
    assert list(jax.device_get(program(jnp.asarray(2.0), jnp.arange(3.0)))) == [-0.0, -2.0, -4.0]
    assert _xla_flags._rejected and program.compiler_options() is None
    # an error that is not about options is the caller's
    with pytest.raises(TypeError):
        program(jnp.asarray(2.0))


def test_set_flag_keeps_or_replaces_a_value_and_the_other_flags():
    """``set_flag`` (also behind ``use_cpu_cores`` on a JAX without
    ``jax_num_cpu_devices``): keep_user=False replaces the user's value of that
    flag only (not a flag whose name it begins), keep_user=True leaves it."""
    count = "xla_force_host_platform_device_count"
    given = f"--{count}=3 --{count}_x=7 --a=1"
    code = ("import os; from moorjax import _xla_flags as X; "
            f"os.environ['XLA_FLAGS'] = {given!r}; "
            f"assert X.set_flag({count!r}, 2, keep_user=False); "
            f"assert not X.set_flag({count!r}, 5, keep_user=True); "
            "assert X.set_flag('b', 'x', keep_user=True)")
    assert _flags_after(code, MOORJAX_XLA_TUNING="0") == f"--{count}_x=7 --a=1 --{count}=2 --b=x"


def _nproc_after(code, **extra):
    return _variable_after("PJRT_NPROC", code, **extra)


def test_one_intra_op_thread_unless_the_user_or_a_platform_says_otherwise():
    """``PJRT_NPROC=1`` at import (XLA:CPU's task pools of one thread), never
    over the user's value, not with the switch off, not once JAX has computed,
    and not where JAX is told to use another platform."""
    assert _nproc_after("import moorjax") == "1"
    assert _nproc_after("import moorjax", PJRT_NPROC="2") == "2"
    assert _nproc_after("import moorjax", MOORJAX_XLA_TUNING="off") is None
    assert _nproc_after("import moorjax", JAX_PLATFORMS="cuda") is None
    assert _nproc_after("import moorjax", JAX_PLATFORMS="cpu") == "1"
    assert _nproc_after("import jax.numpy as jnp; jnp.ones(2).block_until_ready(); import moorjax") is None


def test_batched_programs_keep_small_reductions_out_of_library_calls():
    """An ensemble's programs are compiled for ``"members"``: vmapped, XLA:CPU
    (jaxlib 0.10) hands some of their reductions and block products to YNNPACK
    library calls, slower at these sizes (``moorjax._xla_flags``, PRESETS). The
    batched integration of 10 members at N = 20 holds such calls when compiled
    for ``"runs"`` and none when compiled for ``"members"``."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    from moorjax.dynamics.simulate import plan
    from moorjax.ensemble import run as ens_run
    from moorjax.examples import example_path
    from moorjax.io import build_scene, read_deck

    assert ens_run._batched_integrate.compile_for == "members"
    assert ens_run._batched_equilibrium.compile_for == "members"
    options = {name: _xla_flags.compiler_options(name) for name in ("runs", "members")}
    if None in options.values():
        pytest.skip("moorjax's XLA options are switched off here")
    n_members, segments = 10, 20
    scene = build_scene(read_deck(example_path("oc3_catenary")), segments=segments)
    stacked = jax.tree_util.tree_map(lambda x: jnp.stack([x] * n_members), scene)
    stacked = eqx.tree_at(lambda s: s.lines[0].line_type.drag.cd_normal, stacked,
                          jnp.linspace(1.2, 2.0, n_members))
    y0 = (jax.ShapeDtypeStruct((n_members, segments - 1, 6), jnp.float64),)
    settings = plan(0.5, scene=scene)
    fusions = {}
    for name, opts in options.items():
        program = jax.jit(lambda s, y: ens_run._vmapped_integrate(s, y, settings), compiler_options=opts)
        try:
            text = program.lower(stacked, y0).compile().as_text()
        except Exception as exc:  # another jaxlib: moorjax then drops its options (reject_options)
            if "No such compile option" in str(exc):
                pytest.skip(f"this jaxlib does not take the options: {exc}")
            raise
        assert "fusion" in text
        fusions[name] = text.count("__ynn_fusion")
    assert fusions["members"] == 0, fusions
    print("library fusions:", fusions)
