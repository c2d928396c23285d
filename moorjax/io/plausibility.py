"""Plausibility of a finished run: what the model does not cover.

:func:`check_run` looks at a simulation dataset (:mod:`moorjax.io.dataset`) and
returns one message per line and problem, naming the first time it occurs:

* nodes above the free surface z = 0 of a line whose element has no
  free-surface model (the Hermite element: buoyancy, drag and added mass act as
  if the node were submerged; the linear element wets only what is under water);
* segment strain above :data:`moorjax.statics.fem.MAX_STRAIN` (the limit the
  static solver enforces; no axial law here is meant for such stretches).

Without node positions the checks use the ends only (end above the surface,
chord longer than the stretched line allows).
"""

from __future__ import annotations

import numpy as np


def _first(ts, mask):
    """Index of the first time where ``mask`` (k, ...) holds anywhere, or None."""
    hit = mask.reshape(len(ts), -1).any(axis=1)
    return int(np.argmax(hit)) if hit.any() else None


def check_run(ds, dry_ok=None) -> list[str]:
    """Messages about ``ds`` (empty when nothing is out of the model's range).

    ``dry_ok``: per line, whether its element models the free surface (then nodes
    above it are in the model's range); default: none does."""
    from ..statics.fem import MAX_STRAIN

    ts = ds["time"].values
    out = []
    for j, lid in enumerate(ds["line"].values):
        length = float(ds["unstretched_length"].values[j])
        n = int(ds["n_segments"].values[j])
        if "node_position" in ds:
            r = ds["node_position"].values[:, j, : n + 1]
            z = r[..., 2]
            seg = np.linalg.norm(np.diff(r, axis=1), axis=-1)
            strain = seg / (length / n) - 1.0
            what = "segment strain"
        else:
            r = np.stack([ds["position_a"].values[:, j], ds["position_b"].values[:, j]], axis=1)
            z = r[..., 2]
            strain = np.linalg.norm(r[:, 1] - r[:, 0], axis=-1)[:, None] / length - 1.0
            what = "strain of the chord between the ends"
        i = None if dry_ok is not None and dry_ok[j] else _first(ts, z > 0.0)
        if i is not None:
            out.append(
                f"line {lid}: nodes above the free surface from t = {ts[i]:.6g} s (highest "
                f"z = {np.nanmax(z):.4g} m); its element has no free-surface model, so "
                "buoyancy, drag and added mass act there as if submerged")
        i = _first(ts, strain > MAX_STRAIN)
        if i is not None:
            out.append(
                f"line {lid}: {what} {np.nanmax(strain):.3g} exceeds {MAX_STRAIN:g} from "
                f"t = {ts[i]:.6g} s (max tension {np.nanmax(ds['tension_b'].values[:, j]):.4g} N): "
                "beyond what the axial law describes (statics refuses such stretches); check the "
                "motion")
    return out
