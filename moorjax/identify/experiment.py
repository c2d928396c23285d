"""Experiments: a scene (with its prescribed motion), measured end tensions, weights.

An :class:`Experiment` holds everything one test run of a lab campaign gives: the
scene (the line as built, the fairlead motion as its end condition), the times
of the measurements, the measured tension histories of one or more channels
(``L<id>_tension_a`` / ``L<id>_tension_b``, the columns ``moorjax simulate``
writes), optional weights and a time window. Files are read by
:func:`read_target` and :func:`load_experiment`.

The misfit of one experiment is dimensionless::

    J_e = Σ_i w_i·(T_i(θ) − T̂_i)² / (s_e²·Σ_i w_i)

with s_e the standard deviation of the measured tensions inside the window (or a
given ``scale`` [N]): a relative mean-square error, comparable between
experiments of different amplitude.
"""

from __future__ import annotations

import re
from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from ..io.table import read_table
from ..model.ends import MovingClampedEnd, TabulatedPath

_CHANNEL_RE = re.compile(r"^L(?P<id>[^_]+)_tension_(?P<end>[ab])$", re.IGNORECASE)


class Experiment(eqx.Module):
    """One experiment (build it with :func:`experiment`).

    Attributes:
        scene: the :class:`~moorjax.Scene`, motions included.
        ts: (k,) measurement times [s], increasing, > 0.
        data: (k, m) measured tensions [N] (columns: ``channels``).
        sqrt_weight: (k, m) √(w_i/(s²·Σw)): the misfit is Σ (sqrt_weight·(T − T̂))².
        channels: m pairs (line index, "a"/"b").
        names: the channel names ``L<id>_tension_<end>``.
        name: a label for messages.
    """

    scene: object
    ts: Array
    data: Array
    sqrt_weight: Array
    channels: tuple = eqx.field(static=True)
    names: tuple = eqx.field(static=True)
    name: str = eqx.field(static=True)

    @property
    def n_samples(self) -> int:
        return int(np.count_nonzero(np.asarray(self.sqrt_weight)))


def _channel(scene, name):
    m = _CHANNEL_RE.match(name.strip())
    if m is None:
        raise ValueError(
            f"channel {name!r} is not a tension column; expected L<id>_tension_a or L<id>_tension_b"
        )
    labels = [ln.label for ln in scene.lines]
    if m["id"] not in labels:
        raise ValueError(f"channel {name!r}: the scene has no line {m['id']}; lines: {', '.join(labels)}")
    return labels.index(m["id"]), m["end"].lower(), f"L{m['id']}_tension_{m['end'].lower()}"


def experiment(scene, ts, tensions, *, channels=None, weights=None, window=None,
               scale=None, name="experiment", t0=0.0) -> Experiment:
    """Build and check an :class:`Experiment`.

    Args:
        scene: the scene, its prescribed motions included.
        ts: (k,) times of the measurements [s], strictly increasing, > t0.
        tensions: measured tensions [N]: a (k,) or (k, m) array whose columns are
            ``channels``, or a mapping ``{"L1_tension_b": (k,) array, ...}``.
        channels: channel names (``L<id>_tension_a|b``) of the array's columns;
            default: end B of every line.
        weights: optional non-negative weights: a scalar, (m,) per channel, (k, m),
            or (k,) with a (k,) ``tensions`` array.
        window: optional ``(t_start, t_end)`` [s]: only samples inside count.
        scale: normalising tension [N] (default: std of the data in the window).
        name: a label used in messages.
        t0: start of the simulation [s] (static equilibrium there).
    """
    ts = np.asarray(ts, dtype=float)
    if ts.ndim != 1 or ts.size < 2:
        raise ValueError(f"{name}: measurement times must be a 1-D array of at least 2 times [s]")
    if not np.all(np.isfinite(ts)) or np.any(np.diff(ts) <= 0):
        raise ValueError(f"{name}: measurement times [s] must be finite and strictly increasing")
    if ts[0] <= t0:
        raise ValueError(
            f"{name}: first measurement time {ts[0]} s must be after the start t0 = {t0} s "
            "(drop the rows at t <= t0: the static equilibrium there is not simulated)"
        )
    one_channel = False
    if isinstance(tensions, dict):
        names = list(tensions)
        data = np.column_stack([np.asarray(tensions[c], dtype=float) for c in names])
    else:
        data = np.asarray(tensions, dtype=float)
        one_channel = data.ndim == 1
        if one_channel:
            data = data[:, None]
        names = list(channels) if channels is not None else [f"L{ln.label}_tension_b" for ln in scene.lines]
    if data.ndim != 2 or data.shape[0] != ts.size or data.shape[1] != len(names):
        raise ValueError(
            f"{name}: tensions have shape {data.shape}; expected ({ts.size}, {len(names)}) "
            f"(one row per time, one column per channel {', '.join(names)})"
        )
    parsed = [_channel(scene, c) for c in names]
    if len({(i, e) for i, e, _ in parsed}) != len(parsed):
        raise ValueError(f"{name}: a channel is given twice: {', '.join(names)}")
    bad = ~np.isfinite(data)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise ValueError(f"{name}: measured {names[j]} at t = {ts[i]} s is {data[i, j]}; expected a finite tension [N]")
    _check_motion_span(scene, ts, name)

    w = np.ones_like(data) if weights is None else np.asarray(weights, dtype=float)
    if weights is not None:
        if one_channel and w.shape == (ts.size,):
            w = w[:, None]  # one weight per sample of a 1-D history
        try:
            w = np.broadcast_to(w, data.shape).copy()
        except ValueError:
            raise ValueError(
                f"{name}: weights have shape {w.shape}; expected a scalar, ({data.shape[1]},) "
                f"per channel or {data.shape} (one per sample and channel)"
            ) from None
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ValueError(f"{name}: weights must be finite and >= 0")
    if window is not None:
        lo, hi = (float(x) for x in window)
        if not lo < hi:
            raise ValueError(f"{name}: window ({lo}, {hi}) s must have start < end")
        if hi < ts[0] or lo > ts[-1]:
            raise ValueError(
                f"{name}: window ({lo}, {hi}) s lies outside the measurements ({ts[0]}, {ts[-1]}) s"
            )
        w = w * ((ts >= lo) & (ts <= hi))[:, None]
    if not np.any(w > 0):
        raise ValueError(f"{name}: no sample has a positive weight inside the window")
    inside = w > 0
    s = float(np.std(data[inside])) if scale is None else float(scale)
    if not (np.isfinite(s) and s > 0):
        raise ValueError(
            f"{name}: normalising scale {s} N must be > 0 (constant measured tensions: give scale=)"
        )
    sqrt_w = np.sqrt(w / (s * s * np.sum(w)))
    return Experiment(
        scene=scene, ts=jnp.asarray(ts), data=jnp.asarray(data), sqrt_weight=jnp.asarray(sqrt_w),
        channels=tuple((i, e) for i, e, _ in parsed), names=tuple(c for _, _, c in parsed),
        name=str(name),
    )


def _check_motion_span(scene, ts, name):
    """Measurements must lie within the time span of every tabulated motion."""
    for line in scene.lines:
        for end_name, end in (("A", line.end_a), ("B", line.end_b)):
            if isinstance(end, MovingClampedEnd):
                end = end.path  # a clamp carried along a table
            if not isinstance(end, TabulatedPath):
                continue
            t = np.asarray(end.t)
            dt = float(np.min(np.diff(t))) if t.size > 1 else 0.0
            if ts[-1] > t[-1] + 0.5 * dt or ts[0] < t[0] - 0.5 * dt:
                raise ValueError(
                    f"{name}: the measurements span t = {ts[0]:g} to {ts[-1]:g} s but the motion of "
                    f"line {line.label} end {end_name} spans t = {t[0]:g} to {t[-1]:g} s; the "
                    "target and the motion must cover the same time span"
                )


def read_target(path) -> dict[str, np.ndarray]:
    """Read a measured-tension CSV: a header row then numbers (``t`` [s] first).

    Returns ``{column: values}`` (column names as in the file, ``t`` as "t").
    Raises :class:`~moorjax.io.InputError` (a ``ValueError``) naming
    ``file:line`` for an empty file, a missing ``t`` column, ragged rows,
    non-numeric or non-finite cells, fewer than 2 rows or times that are not
    strictly increasing (:mod:`moorjax.io.table`).
    """
    return read_table(path, "t,L<id>_tension_b,...").by_column()


def target_channels(columns, scene, line=None, path="target") -> list[str]:
    """The tension columns of a target file that belong to the scene (optionally one line)."""
    labels = [ln.label for ln in scene.lines]
    wanted = labels if line is None else [str(line)]
    if line is not None and str(line) not in labels:
        raise ValueError(f"--line {line}: the deck has no line {line}; lines: {', '.join(labels)}")
    found = []
    for c in columns:
        m = _CHANNEL_RE.match(c)
        if m and m["id"] in wanted:
            found.append(c)
    if not found:
        need = " or ".join(f"L{i}_tension_a/L{i}_tension_b" for i in wanted)
        raise ValueError(
            f"{path}: no tension column for line(s) {', '.join(wanted)}; expected {need} "
            f"(the columns of `moorjax simulate` output); found columns: {', '.join(columns)}"
        )
    return found


def load_experiment(deck, motion, target, *, segments=None, line=None, window=None,
                    name=None, element=None) -> Experiment:
    """An experiment from files: a MoorDyn deck, a motion CSV and a target CSV.

    Args:
        deck: path of the deck (or a parsed :class:`moorjax.io.Deck`).
        motion: path of the motion CSV (``t, P<id>_x, ...``) of the coupled points.
        target: path of the measured tensions (``t, L<id>_tension_b, ...``, e.g. the
            output of ``moorjax simulate``); ``P<id>_F*`` columns are ignored.
        segments: segment count override.
        line: only use (and fit) line ``line``'s channels.
        window: ``(t_start, t_end)`` [s] of the samples that count.
        element: the lines' discretisation (default: the linear element).
    """
    from ..io import build_scene, coupled_point_ids, read_deck, read_motion

    d = read_deck(deck) if isinstance(deck, (str, Path)) else deck
    mot = read_motion(motion, coupled_point_ids(d))
    scene = build_scene(d, segments=segments, motion=mot, element=element)
    cols = read_target(target)
    chans = target_channels([c for c in cols if c != "t"], scene, line, str(target))
    t = cols["t"]
    keep = t > 0.0
    t_motion = np.asarray(mot.t)
    # the files describe one run: the target must cover the motion's span (its
    # first sample may come one output interval after the motion starts; use
    # `window` to fit part of it)
    tol = float(np.max(np.diff(t))) + float(np.max(np.diff(t_motion)))
    if abs(t[-1] - t_motion[-1]) > tol or abs(t[0] - t_motion[0]) > tol:
        raise ValueError(
            f"{target}: the target spans t = {t[0]:g} to {t[-1]:g} s but the motion {motion} spans "
            f"t = {t_motion[0]:g} to {t_motion[-1]:g} s; they must cover the same time span "
            "(use the window option to fit part of a run)"
        )
    return experiment(
        scene, t[keep], {c: cols[c][keep] for c in chans}, window=window,
        name=name or Path(str(target)).name,
    )
