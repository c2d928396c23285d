"""moorjax: differentiable mooring-line dynamics on JAX.

Importing moorjax enables JAX's float64 mode (``jax_enable_x64``): mooring
simulation needs it (positions ~100 m resolved to µm, tensions ~1 MN with
Newton tolerances of ~1e-8 relative). Import moorjax before creating arrays that
should be float64.

Units are SI throughout; z is up with z = 0 at the free surface.
"""

__version__ = "0.1.0"

import jax as _jax

_jax.config.update("jax_enable_x64", True)

from ._cache import enable_compilation_cache as _enable_cache  # noqa: E402

_enable_cache(_jax)

from ._xla_flags import prefer_one_intra_op_thread as _prefer_one_thread  # noqa: E402
from ._xla_flags import prefer_sequential_schedule as _prefer_sequential  # noqa: E402

_prefer_sequential()
_prefer_one_thread()

from .model import *  # noqa: E402,F401,F403
from .model import __all__ as _model_all  # noqa: E402,F401
