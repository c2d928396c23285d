"""matplotlib, imported on first use with a clear message when it is missing."""

from __future__ import annotations


def pyplot(headless: bool = False):
    """``matplotlib.pyplot`` (with ``headless``, on the file-only Agg backend, as
    the command line uses it)."""
    try:
        import matplotlib

        if headless:
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise ImportError(
            "plotting needs matplotlib: pip install \"moorjax[plot]\" (or pip install matplotlib)"
        ) from None
    return plt
