"""moorjax's XLA:CPU schedule flag (moorjax._xla_flags): added at import while
JAX has not started, never over the user's choice, and it changes no result."""

import json
import os
import subprocess
import sys

from moorjax import _xla_flags

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FLAG = f"--{_xla_flags.FLAG}"


def _env(**extra):
    env = {k: v for k, v in os.environ.items()
           if k not in ("XLA_FLAGS", "MOORJAX_XLA_TUNING", "PJRT_NPROC", "JAX_PLATFORMS")}
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
    code = _RUN.format(tests=os.path.join(ROOT, "tests"))
    runs = [json.loads(subprocess.run([sys.executable, "-c", code], env=_env(MOORJAX_XLA_TUNING=v),
                                      capture_output=True, text=True, check=True)
                       .stdout.strip().splitlines()[-1]) for v in ("1", "0")]
    assert runs[0]["steps"] == runs[1]["steps"] > 0
    assert runs[0]["tension"] == runs[1]["tension"]


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
