"""The overview figure of ``moorjax plot``: tensions, and profiles when the run
has node positions."""

from __future__ import annotations

from ._history import plot_tensions
from ._mpl import pyplot
from ._profile import plot_profiles


def plot_run(ds, *, times=None, line=None):
    """Tension histories above line profiles at ``times`` (profiles only when
    the dataset has ``node_position``)."""
    plt = pyplot()
    if "node_position" not in ds:
        return plot_tensions(ds)
    fig, (a, b) = plt.subplots(2, 1, figsize=(8, 7), layout="constrained")
    plot_tensions(ds, ax=a)
    plot_profiles(ds, times, line=line, ax=b)
    return fig
