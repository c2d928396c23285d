"""An ensemble run (:func:`moorjax.ensemble.store.run_chunked`) as one
``xarray.Dataset`` with a ``member`` dimension.

Variables: each varied parameter (member), ``status`` (member; ``ok`` or why it
failed), ``steps`` and ``rejected_steps`` (member), the statistics
``tension_a_max``, ``tension_b_mean``, ... (member, line) [N] and, when
histories were kept, ``tension_a``/``tension_b`` (member, time, line) [N].
"""

from __future__ import annotations

import json

import numpy as np

from ..ensemble.store import SUMMARY_STATS


def ensemble_dataset(data, table, names, line_ids, attrs=None):
    """The dataset of ``run_chunked``'s arrays ``data``; ``table`` lists each
    member's ``{name: value}`` of the varied ``names``."""
    import xarray as xr

    from .. import __version__

    n = len(table)
    coords = dict(
        member=("member", np.arange(n), dict(long_name="ensemble member")),
        line=("line", [int(i) if str(i).isdigit() else str(i) for i in line_ids],
              dict(long_name="line id")),
    )
    vars_ = {}
    for name in names:
        vars_[name] = (("member",), np.array([float(row[name]) for row in table]),
                       dict(long_name=f"varied parameter {name} (SI units, see the deck)"))
    vars_["status"] = (("member",), np.asarray(data["status"]).astype(str),
                       dict(long_name="'ok' or why the member failed"))
    vars_["steps"] = (("member",), np.asarray(data["num_steps"]), dict(units="1", long_name="solver steps"))
    vars_["rejected_steps"] = (("member",), np.asarray(data["num_rejected_steps"]),
                               dict(units="1", long_name="rejected solver steps"))
    for end in ("tension_a", "tension_b"):
        for st in SUMMARY_STATS:
            vars_[f"{end}_{st}"] = (("member", "line"), np.asarray(data[f"stat_{end}_{st}"]),
                                    dict(units="N", long_name=f"{st} of the {end.replace('_', ' at end ')}"))
    if "ts" in data:
        coords["time"] = ("time", np.asarray(data["ts"]), dict(units="s", long_name="time", axis="T"))
        for end in ("tension_a", "tension_b"):
            vars_[end] = (("member", "time", "line"), np.asarray(data[end]),
                          dict(units="N", long_name=end.replace("_", " at end ")))
    glob = dict(title="moorjax ensemble", Conventions="CF-1.8", source=f"moorjax {__version__}",
                moorjax_version=__version__)
    for key, val in (attrs or {}).items():
        if val is not None:
            glob[key] = json.dumps(val) if isinstance(val, (dict, list, tuple)) else val
    return xr.Dataset(vars_, coords=coords, attrs=glob)
