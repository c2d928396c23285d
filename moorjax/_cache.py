"""JAX's persistent compilation cache, on by default for moorjax.

Compiling a simulation (diffrax's step, the band Newton solver, the statics)
takes seconds; the compiled executables are kept on disk so that a new process
running the same *structure* again (same deck layout, segment counts, solver)
loads them instead of compiling. Values (EA, lengths, motions) are not part of
the key, so changing them reuses the cache.

Where: ``$MOORJAX_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/moorjax``, else
``~/.cache/moorjax`` (a ``jax`` subfolder). A cache directory the user already
gave JAX (``JAX_COMPILATION_CACHE_DIR`` or ``jax.config``) is left as it is.
Switch off with ``MOORJAX_COMPILATION_CACHE=0`` (also ``false``/``off``/``no``).
The folder may be deleted at any time; JAX refills it.
"""

from __future__ import annotations

import contextlib
import os

_OFF = ("0", "false", "off", "no")


def cache_dir() -> str:
    """The folder moorjax keeps compiled executables in [path]."""
    root = os.environ.get("MOORJAX_CACHE_DIR")
    if not root:
        xdg = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        root = os.path.join(xdg, "moorjax")
    return os.path.join(root, "jax")


def enabled() -> bool:
    """Whether the persistent cache is wanted (``MOORJAX_COMPILATION_CACHE``)."""
    return os.environ.get("MOORJAX_COMPILATION_CACHE", "1").strip().lower() not in _OFF


def enable_compilation_cache(jax) -> str | None:
    """Point JAX's persistent compilation cache at :func:`cache_dir` (unless
    switched off or already configured); returns the folder in use, or None."""
    if not enabled():
        return None
    current = jax.config.jax_compilation_cache_dir
    if current:
        return current
    path = cache_dir()
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:  # read-only home, no permission: run without the cache
        return None
    jax.config.update("jax_compilation_cache_dir", path)
    # moorjax compiles many small functions (statics, outputs) besides the big
    # integration: keep them all, not only those over JAX's default 1 s
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    return path


# -- runtime checks without host callbacks -----------------------------------
#
# JAX never writes an executable that contains a host callback to the persistent
# cache. equinox compiles each ``eqx.error_if`` whose predicate is only known at
# run time into a host callback that raises; diffrax's ``diffeqsolve`` places
# three of them on its inputs (``(t1 - t0)·dt0 >= 0``, ``saveat.ts`` increasing
# and within [t0, t1]). moorjax checks exactly these on the host before it
# integrates (``dynamics.settings.plan`` raises ``ValueError`` naming the
# setting), so inside its integration they can never fire. equinox's documented
# switch for what an unresolved check compiles to is ``EQX_ON_ERROR``
# (``raise``/``nan``/``off``, read once at import into ``equinox._errors``);
# :func:`host_checked_inputs` selects ``nan`` (a failed check fills the checked
# value with NaN, no callback) while moorjax traces its integration only, and
# restores the user's choice afterwards. ``tests/test_speed_cache.py`` pins
# that a run is then served from the persistent cache in a new process.

def _equinox_errors():
    try:
        from equinox import _errors
    except ImportError:  # pragma: no cover - a future equinox layout
        return None
    return _errors if isinstance(getattr(_errors, "EQX_ON_ERROR", None), str) else None


@contextlib.contextmanager
def host_checked_inputs():
    """While tracing inside this context, equinox runtime checks compile without
    host callbacks (``EQX_ON_ERROR=nan`` semantics), so the compiled program can
    be kept in JAX's persistent cache. Use it only around code whose checked
    inputs were validated on the host; a user who set ``EQX_ON_ERROR=breakpoint``
    (debugging) keeps it. Nothing changes when equinox's layout differs."""
    errors = _equinox_errors()
    if errors is None or errors.EQX_ON_ERROR != "raise":
        yield
        return
    errors.EQX_ON_ERROR = "nan"
    try:
        yield
    finally:
        errors.EQX_ON_ERROR = "raise"
