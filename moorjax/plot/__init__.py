"""Plots of moorjax results with matplotlib (``pip install "moorjax[plot]"``).

Each function takes an ``xarray.Dataset`` of a run (:func:`moorjax.io.to_dataset`,
or :func:`moorjax.io.results.read_results` of a ``.nc``/``.csv`` file) and
returns a matplotlib ``Figure``; nothing is shown or saved unless asked. The
command line's ``moorjax plot`` and ``moorjax plot-statics`` call them.
"""

from ._history import plot_tensions as plot_tensions
from ._layout import plot_statics as plot_statics
from ._profile import animate as animate
from ._profile import plot_profiles as plot_profiles
from ._summary import plot_run as plot_run
