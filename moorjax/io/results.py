"""Writing and reading simulation outputs: netCDF (``.nc``) and CSV (``.csv``).

* netCDF: the dataset of :func:`moorjax.io.dataset.to_dataset` as it is
  (compressed; units and descriptions as attributes).
* CSV: one header row of column names, then one comment row with their units,
  then one row per output time (15 significant digits, shortest form)::

      t,L1_tension_a,L1_tension_b,P2_Fx,P2_Fy,P2_Fz
      # units: s,N,N,N,N,N
      0.05,50561.2966240148,49983.9401225721,-49102.7172961372,0,-9317.4201234455

  Readers that skip ``#`` lines (``numpy.loadtxt``/``genfromtxt``, pandas with
  ``comment="#"``, ``moorjax fit --target``) see the columns of earlier versions.
  Node positions do not fit a flat table and are only in netCDF, except
  for the lines whose deck ``LineOutputs`` ask for them (columns
  ``L<id>_Node<i>_px``, ``L<id>_Seg<i>_Te``, ...: :mod:`moorjax.io.line_outputs`).
  With a deck, free points and free bodies add their global pose
  (``P<id>_x``..., ``B<id>_x``... ``B<id>_yaw``).

:func:`check_output` validates a path before any work is done.
"""

from __future__ import annotations

import os

import numpy as np

from .line_outputs import csv_line_columns
from .table import read_table

SUFFIXES = (".nc", ".csv")


def check_output(path, suffixes=SUFFIXES, option="--out") -> str:
    """Raise ``ValueError`` if ``path`` cannot be written as one of ``suffixes``
    (unknown suffix, a directory, a missing or read-only folder); returns it."""
    path = str(path)
    if os.path.isdir(path):
        raise ValueError(f"{option} {path}: is a directory; give a file name")
    ext = os.path.splitext(path)[1].lower()
    if ext not in suffixes:
        raise ValueError(f"{option} {path}: unknown file type {ext or '(none)'!r}; "
                         f"expected {' or '.join(suffixes)}")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise ValueError(f"{option} {path}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        raise ValueError(f"{option} {path}: not writable (permission denied)")
    return path


def csv_columns(ds):
    """[(name, unit, values)] of the CSV columns of a simulation dataset."""
    cols = [("t", "s", ds["time"].values)]
    for lid in ds["line"].values:
        for end in ("a", "b"):
            cols.append((f"L{lid}_tension_{end}", "N", ds[f"tension_{end}"].sel(line=lid).values))
    if "point_force" in ds:
        for pid in ds["point"].values:
            for i, c in enumerate("xyz"):
                cols.append((f"P{pid}_F{c}", "N", ds["point_force"].sel(point=pid).values[:, i]))
    if "body_force" in ds:
        for bid in ds["body"].values:
            for var, sym, unit in (("body_force", "F", "N"), ("body_moment", "M", "N*m")):
                for i, c in enumerate("xyz"):
                    cols.append((f"B{bid}_{sym}{c}", unit, ds[var].sel(body=bid).values[:, i]))
    if "free_pose" in ds:
        for label in ds["free"].values:
            dofs = 3 if str(label).startswith("P") else 6
            for i, name in enumerate(("x", "y", "z", "roll", "pitch", "yaw")[:dofs]):
                cols.append((f"{label}_{name}", "m" if i < 3 else "rad",
                             ds["free_pose"].sel(free=label).values[:, i]))
    return cols + csv_line_columns(ds)


def write_csv(ds, path) -> None:
    cols = csv_columns(ds)
    with open(path, "w") as f:
        f.write(",".join(c[0] for c in cols) + "\n")
        f.write("# units: " + ",".join(c[1] for c in cols) + "\n")
        np.savetxt(f, np.column_stack([c[2] for c in cols]), delimiter=",", fmt="%.15g")


def write_netcdf(ds, path) -> None:
    enc = {name: {"zlib": True, "complevel": 4} for name in ds.data_vars}
    tmp = f"{path}.tmp"
    ds.to_netcdf(tmp, encoding=enc)
    os.replace(tmp, path)


def write_results(ds, path, nodes=True) -> None:
    """Write a simulation dataset to ``path`` (``.nc`` or ``.csv``; ``nodes=False``
    leaves node positions and segment tensions out of netCDF)."""
    if not nodes:
        ds = ds.drop_vars([v for v in ("node_position", "segment_tension") if v in ds])
        if "line_outputs" in ds and "p" in "".join(map(str, ds["line_outputs"].values)):
            import warnings

            warnings.warn("the deck's LineOutputs p (node positions) are not written without nodes",
                          stacklevel=2)
    if str(path).lower().endswith(".nc"):
        write_netcdf(ds, path)
    else:
        write_csv(ds, path)


def read_results(path):
    """A simulation output (``.nc``, or a ``.csv`` of ``moorjax simulate``'s
    columns) as an ``xarray.Dataset``; CSV gives ``tension_a``/``tension_b``
    (and ``point_force``) only."""
    import xarray as xr

    path = str(path)
    if path.lower().endswith(".nc"):
        with xr.open_dataset(path) as ds:
            return ds.load()
    cols = read_table(path, "t,L<id>_tension_b,...").by_column()
    ids = []
    for name in cols:
        if name.startswith("L") and name.endswith("_tension_b"):
            ids.append(name[1:-len("_tension_b")])
    if not ids:
        raise ValueError(f"{path}: no L<id>_tension_b columns; is it an output of moorjax simulate?")
    ts = cols["t"]
    data = {}
    for end in ("a", "b"):
        data[f"tension_{end}"] = (("time", "line"),
                                  np.column_stack([cols.get(f"L{i}_tension_{end}", np.full(len(ts), np.nan))
                                                   for i in ids]),
                                  dict(units="N", long_name=f"tension at end {end.upper()}"))
    coords = dict(time=("time", ts, dict(units="s", long_name="time")),
                  line=("line", [int(i) if i.isdigit() else i for i in ids]))
    return xr.Dataset(data, coords=coords, attrs=dict(source=path))
