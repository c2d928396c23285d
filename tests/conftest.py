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

import jax
import pytest

from moorjax import _cache


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    yield
    _cache.clear_programs()
    jax.clear_caches()
    gc.collect()
