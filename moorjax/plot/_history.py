"""Tension histories of a run."""

from __future__ import annotations

import numpy as np

from ._mpl import pyplot


def plot_tensions(ds, *, lines=None, ends=("a", "b"), ax=None):
    """End tensions [kN] against time [s], one curve per line and end.

    Args:
        ds: a run's dataset (``tension_a``, ``tension_b``: time × line [N]).
        lines: line ids to show (default all).
        ends: ``"a"`` and/or ``"b"``.
        ax: an existing matplotlib ``Axes`` (default: a new figure).
    """
    plt = pyplot()
    fig, ax = (plt.subplots(figsize=(8, 4), layout="constrained") if ax is None
               else (ax.figure, ax))
    ids = list(ds["line"].values) if lines is None else list(lines)
    t = ds["time"].values
    for lid in ids:
        for end in ends:
            y = ds[f"tension_{end}"].sel(line=lid).values / 1e3
            if np.all(np.isnan(y)):
                continue
            ax.plot(t, y, lw=1.2, ls="-" if end == "b" else "--",
                    label=f"line {lid}, end {end.upper()}")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tension [kN]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    ax.set_title("end tensions")
    return fig
