"""A simulation result as an ``xarray.Dataset`` with units and descriptions.

:func:`to_dataset` turns a :class:`~moorjax.dynamics.SimulationResult` into one
self-describing dataset (CF-style ``units`` / ``long_name`` attributes):

========================  ===============================  =====
variable                  dimensions                       units
========================  ===============================  =====
``tension_a/_b``          time, line                       N
``force_a/_b``            time, line, axis                 N
``position_a/_b``         time, line, axis                 m
``node_position``         time, line, node, axis           m
``segment_tension``       time, line, segment              N
``point_force``           time, point, axis                N
``body_force/_moment``    time, body, axis                 N, N m
``body_position``         time, body, axis                 m
``body_pose``             time, body, dof                  m, rad
``n_segments``            line                             1
``unstretched_length``    line                             m
``free_pose``             time, free, dof                  m, rad
``line_outputs``          line                             —
========================  ===============================  =====

With a deck: ``free_pose`` is the global pose of its free points and free
bodies (reference point, MoorDyn's roll, pitch, yaw; labels ``P<id>``/``B<id>``),
and the ``LineOutputs`` each line asks for (``line_outputs``: the flags
written) add the variables of :mod:`moorjax.io.line_outputs` (NaN for lines
that did not ask).

Node and segment variables exist when the run saved nodes
(``simulate(..., save_nodes=True)``); lines with fewer segments than the
longest are padded with NaN. Point and coupled-body variables need the deck
(``deck=``). The times are the result's own ``ts``: nothing is added or dropped.

xarray is imported when this is called, not when moorjax is.
"""

from __future__ import annotations

import json

import numpy as np

AXIS = ("x", "y", "z")
DOF = ("x", "y", "z", "roll", "pitch", "yaw")


def _var(dims, data, units, long_name, **extra):
    return (dims, np.asarray(data, dtype=float), dict(units=units, long_name=long_name, **extra))


def _end_positions(scene, res, ts, name):
    """(k, n_lines, 3) positions of end A / B [m] (NaN where not a function of t alone)."""
    import jax

    from ..model.ends import BodyEnd

    out = np.full((len(ts), len(scene.lines), 3), np.nan)
    for j, line in enumerate(scene.lines):
        if res.positions is not None:
            out[:, j] = np.asarray(res.positions[j])[:, 0 if name == "a" else -1]
            continue
        end = getattr(line, f"end_{name}")
        if not isinstance(end, BodyEnd):
            out[:, j] = np.asarray(jax.vmap(end.position)(ts))
    return out


def body_loads(deck, scene, motion, res, body_id) -> np.ndarray:
    """(k, 6) force [N] and moment about the body's reference point [N·m] (global
    axes) of the lines on a coupled body, at the output times."""
    import jax

    from .build import body_reference_end

    ts = np.asarray(res.ts)
    ref = np.asarray(jax.vmap(body_reference_end(deck, body_id, motion).position)(ts))
    out = np.zeros((len(ts), 6))
    for j, dl in enumerate(deck.lines):
        for name, pid, force in (("a", dl.point_a, res.force_a), ("b", dl.point_b, res.force_b)):
            if deck.points[pid].body != body_id:
                continue
            end = getattr(scene.lines[j], f"end_{name}")
            r = np.asarray(jax.vmap(end.position)(ts))
            f = np.asarray(force[:, j])
            out[:, :3] += f
            out[:, 3:] += np.cross(r - ref, f)
    return out


def _label(text):
    return int(text) if str(text).isdigit() else str(text)


def _add_line_outputs(data, coords, res, scene, deck):
    """The deck's ``LineOutputs`` (:mod:`moorjax.io.line_outputs`)."""
    import warnings

    from .line_outputs import line_output_variables, split_flags

    flags = {j: split_flags(dl.outputs)[0] for j, dl in enumerate(deck.lines)}
    if not any(flags.values()):
        return
    if res.positions is None:
        warnings.warn("the deck's LineOutputs need the run's nodes; they are not written "
                      "(run without --no-nodes / with save_nodes=True)", stacklevel=3)
        return
    data["line_outputs"] = (("line",), np.array([flags.get(j, "") for j in range(len(scene.lines))]),
                            dict(long_name="LineOutputs flags written (MoorDyn's letters)"))
    if "segment" not in coords:
        n_max = max(ln.n_segments for ln in scene.lines)
        coords["segment"] = ("segment", np.arange(n_max), dict(long_name="segment index (0 at end A)"))
    for name, (dims, arr, units, long_name) in line_output_variables(res, scene, flags).items():
        data[name] = _var(dims, arr, units, long_name)


def to_dataset(res, scene, *, deck=None, motion=None, attrs=None):
    """The result of :func:`moorjax.dynamics.simulate` on ``scene`` as an
    ``xarray.Dataset`` (see the module notes for its variables).

    Args:
        res: a :class:`SimulationResult` (on the host or device).
        scene: the scene that was simulated (line labels, lengths, ends).
        deck: the :class:`~moorjax.io.Deck` the scene came from, to add the
            total force on each coupled point and the loads on coupled bodies.
        motion: the :class:`~moorjax.io.Motion` that drove it (body positions).
        attrs: extra global attributes (strings or numbers; dicts become JSON).
    """
    import jax
    import xarray as xr

    from .. import __version__
    from .build import body_reference_end, coupled_body_ids, coupled_point_ids

    res = jax.device_get(res)
    ts = np.asarray(res.ts, dtype=float)
    k = len(ts)
    lines = scene.lines
    coords = dict(
        time=("time", ts, dict(units="s", long_name="time", standard_name="time", axis="T")),
        line=("line", [_label(ln.label) for ln in lines], dict(long_name="line id")),
        axis=("axis", list(AXIS), dict(long_name="global axis (z up, z = 0 at the free surface)")),
    )
    data = dict(
        tension_a=_var(("time", "line"), res.tension_a, "N",
                       "tension at end A (magnitude of the line's force on its end A point)"),
        tension_b=_var(("time", "line"), res.tension_b, "N",
                       "tension at end B (magnitude of the line's force on its end B point)"),
        force_a=_var(("time", "line", "axis"), res.force_a, "N", "force of the line on its end A point"),
        force_b=_var(("time", "line", "axis"), res.force_b, "N", "force of the line on its end B point"),
        position_a=_var(("time", "line", "axis"), _end_positions(scene, res, ts, "a"), "m",
                        "position of end A"),
        position_b=_var(("time", "line", "axis"), _end_positions(scene, res, ts, "b"), "m",
                        "position of end B"),
        n_segments=(("line",), np.array([ln.n_segments for ln in lines]),
                    dict(units="1", long_name="number of segments")),
        unstretched_length=_var(("line",), [float(ln.length) for ln in lines], "m",
                                "unstretched line length"),
    )
    if res.positions is not None:
        n_max = max(ln.n_segments for ln in lines)
        nodes = np.full((k, len(lines), n_max + 1, 3), np.nan)
        ten = np.full((k, len(lines), n_max), np.nan)
        for j, ln in enumerate(lines):
            nodes[:, j, : ln.n_segments + 1] = np.asarray(res.positions[j])
            ten[:, j, : ln.n_segments] = np.asarray(res.segment_tensions[j])
        coords["node"] = ("node", np.arange(n_max + 1), dict(long_name="node index (0 = end A)"))
        coords["segment"] = ("segment", np.arange(n_max), dict(long_name="segment index (0 at end A)"))
        data["node_position"] = _var(("time", "line", "node", "axis"), nodes, "m",
                                     "node position (NaN beyond a line's last node)")
        data["segment_tension"] = _var(("time", "line", "segment"), ten, "N",
                                       "segment tension (elastic and internal damping)")
    if deck is not None:
        pids = coupled_point_ids(deck)
        if pids:
            total = np.zeros((k, len(pids), 3))
            for i, pid in enumerate(pids):
                for j, dl in enumerate(deck.lines):
                    if dl.point_a == pid:
                        total[:, i] += np.asarray(res.force_a)[:, j]
                    if dl.point_b == pid:
                        total[:, i] += np.asarray(res.force_b)[:, j]
            coords["point"] = ("point", pids, dict(long_name="coupled point id (deck)"))
            data["point_force"] = _var(("time", "point", "axis"), total, "N",
                                       "total force of the lines on the coupled point")
        bids = coupled_body_ids(deck)
        if bids:
            loads = np.stack([body_loads(deck, scene, motion, res, b) for b in bids], axis=1)
            pos = np.stack([np.asarray(jax.vmap(body_reference_end(deck, b, motion).position)(ts))
                            for b in bids], axis=1)
            coords["body"] = ("body", bids, dict(long_name="coupled body id (deck)"))
            data["body_force"] = _var(("time", "body", "axis"), loads[..., :3], "N",
                                      "force of the lines on the body (global axes)")
            data["body_moment"] = _var(("time", "body", "axis"), loads[..., 3:], "N m",
                                       "moment of the lines about the body's reference point")
            data["body_position"] = _var(("time", "body", "axis"), pos, "m",
                                         "position of the body's reference point")
        if res.body_pose is not None:
            from ..body.submerged import SubmergedBody

            pose = np.array(res.body_pose, dtype=float)
            for i, b in enumerate(scene.bodies):
                pose[:, i, :3] += np.asarray(b.origin)
                if isinstance(b, SubmergedBody):
                    pose[:, i, 3:] += np.asarray(b.orientation)
            coords["free"] = ("free", [str(b.label) for b in scene.bodies],
                              dict(long_name="free point (P<id>) or free body (B<id>) of the deck"))
            coords["dof"] = ("dof", list(DOF), dict(long_name="degree of freedom"))
            data["free_pose"] = _var(("time", "free", "dof"), pose, "m, m, m, rad, rad, rad",
                                     "global pose: reference point x, y, z and MoorDyn's roll, "
                                     "pitch, yaw (R = Rx Ry Rz)")
        _add_line_outputs(data, coords, res, scene, deck)
    elif res.body_pose is not None:
        coords["body"] = ("body", np.arange(len(scene.bodies)),
                          dict(long_name="body index in the scene",
                               labels=", ".join(str(b.label) for b in scene.bodies)))
        coords["dof"] = ("dof", list(DOF), dict(long_name="degree of freedom"))
        data["body_pose"] = _var(("time", "body", "dof"), res.body_pose, "m, m, m, rad, rad, rad",
                                 "body displacement from its equilibrium (surge, sway, heave, "
                                 "roll, pitch, yaw)")
        data["body_velocity"] = _var(("time", "body", "dof"), res.body_velocity,
                                     "m/s, m/s, m/s, rad/s, rad/s, rad/s", "body velocity")
    glob = dict(
        title="moorjax simulation",
        Conventions="CF-1.8",
        source=f"moorjax {__version__}",
        moorjax_version=__version__,
        water_depth=float(scene.env.depth),
        water_depth_units="m",
        steps=int(res.num_steps),
        rejected_steps=int(res.num_rejected_steps),
    )
    for key, val in (attrs or {}).items():
        if val is None:
            continue
        glob[key] = json.dumps(val) if isinstance(val, (dict, list, tuple)) else val
    return xr.Dataset(data, coords=coords, attrs=glob)
