"""Suite-wide fixtures.

Every test module compiles its own XLA programs; kept for the whole session they
pile up (each compiled CPU executable holds memory maps). Late in a full run the
XLA compiler then crashed the interpreter (segfault/abort inside
``backend_compile_and_load``, in whichever test compiled next), while each test
passed in a fresh process. Dropping JAX's caches and moorjax's stored programs
held in memory (``moorjax._cache.clear_programs``: a program compiled ahead is
kept by moorjax itself) after each module keeps the process bounded; tests
within a module still share their compilations.
"""

import gc
import os

# The suite is compile-bound: most of its time is XLA compiling programs that
# then run for well under a second. Without XLA:CPU's fusion emitters and with
# the backend optimisation level at 0, a sample of four test files took 273 s
# instead of 498 s (-n 2, empty compilation cache), and case A's 20 s run
# compiles in 9.8 s instead of 20.1 s but runs in 1.3 s instead of 0.6 s: a
# good trade for tests, not for users, so only the tests set it (subprocesses
# of the CLI tests inherit it). MOORJAX_TEST_XLA_DEFAULTS=1 keeps XLA's
# defaults; flags already in XLA_FLAGS win.
if os.environ.get("MOORJAX_TEST_XLA_DEFAULTS") != "1":
    _flags = os.environ.get("XLA_FLAGS", "")
    _fast = [f for f in ("--xla_cpu_use_fusion_emitters=false", "--xla_backend_optimization_level=0")
             if f.split("=")[0] not in _flags]
    os.environ["XLA_FLAGS"] = " ".join([_flags, *_fast]).strip()

import jax  # noqa: E402  (after XLA_FLAGS: read when the backend starts)
import pytest  # noqa: E402

from moorjax import _cache  # noqa: E402


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    yield
    _cache.clear_programs()
    jax.clear_caches()
    gc.collect()
