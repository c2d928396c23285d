"""The persistent compilation cache (moorjax._cache)."""

import os
import subprocess
import sys

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
