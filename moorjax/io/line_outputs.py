"""MoorDyn's per-line outputs (the ``LineOutputs`` column of ``LINES``).

A deck asks for per-line channels with a string of flag characters (``-``:
none). moorjax writes these into the simulation dataset
(:func:`moorjax.io.dataset.to_dataset`) for the lines that ask, NaN for the
others, and the CSV writer adds their columns (MoorDyn's channel names behind
the line's id: ``L1_Node0_px``, ``L1_Seg1_Te``):

====  ==============================  =========================  ======
flag  quantity (MoorDyn)              dataset variable           units
====  ==============================  =========================  ======
p     node positions                  ``node_position``          m
v     node velocities                 ``node_velocity``          m/s
U     water velocity at each node     ``node_water_velocity``    m/s
t     segment tension (elastic)       ``segment_elastic_tension``  N
c     segment internal damping force  ``segment_damping_force``  N
s     segment strain                  ``segment_strain``         1
d     segment strain rate             ``segment_strain_rate``    1/s
====  ==============================  =========================  ======

MoorDyn's other flags — ``D`` (hydrodynamic drag force at each node), ``K``
(curvature), ``V`` (VIV lift force), ``b`` (seabed contact force) — are not
written: the deck reader warns naming them. The water velocity ``U`` is the
waves' particle velocity plus the current, as the lines' drag sees it. Strain, its rate, the
elastic tension and the damping force are those of the straight segments
between nodes (the linear element's; for the Hermite element, of the chords).

Pure numpy at the edge: evaluated on a finished result, not in the physics.
"""

from __future__ import annotations

import numpy as np

#: flags moorjax writes, in MoorDyn's column order
WRITTEN = "pvUtcsd"
#: MoorDyn's flags moorjax does not write, with MoorDyn's meaning
NOT_WRITTEN = {
    "D": "hydrodynamic drag force at each node",
    "K": "curvature at each node",
    "V": "VIV lift force at each node",
    "b": "seabed contact force at each node",
}


def split_flags(text: str) -> tuple[str, str, str]:
    """(written, MoorDyn's but not written, not MoorDyn flags) characters of a
    ``LineOutputs`` entry (each once, in MoorDyn's order; ``-`` means none)."""
    chars = [] if text == "-" else list(dict.fromkeys(text))
    written = "".join(f for f in WRITTEN if f in chars)
    missing = "".join(f for f in NOT_WRITTEN if f in chars)
    unknown = "".join(c for c in chars if c not in WRITTEN and c not in NOT_WRITTEN and c != "-")
    return written, missing, unknown


def water_velocity(env, r, t):
    """Water velocity (n, 3) [m/s] at points r (n, 3) at time t: waves plus current
    (sampled where the waves' model says, as the line physics does)."""
    import jax.numpy as jnp

    u = jnp.zeros_like(r)
    r_current = r
    if env.waves is not None:
        eta, u_wave, _ = env.waves.kinematics(r, t)
        u = u + u_wave
        r_current = r.at[:, 2].set(env.waves.current_height(r, eta))
    if env.current is not None:
        u = u + env.current.velocity_at(r_current, t)
    return u


def _segments(r, v, length):
    """Unit tangents (k, n, 3), strain (k, n) and strain rate (k, n) [1/s]."""
    dr = r[:, 1:] - r[:, :-1]
    stretched = np.linalg.norm(dr, axis=-1)
    q = dr / np.where(stretched > 0, stretched, 1.0)[..., None]
    strain = stretched / length - 1.0
    rate = None if v is None else np.sum(q * (v[:, 1:] - v[:, :-1]), axis=-1) / length
    return q, strain, rate


def _unstretched_segments(line):
    """Unstretched lengths [m] between neighbouring nodes: L/n, or a graded
    Hermite line's element lengths (n,)."""
    if getattr(line.element, "mesh", None) is None:
        return float(line.segment_length)
    mesh = np.asarray(line.element.mesh, dtype=float)
    return float(line.length) * mesh / mesh.sum()


def line_output_variables(res, scene, flags: dict) -> dict:
    """Dataset variables ``{name: (dims, data, units, long_name)}`` of the
    requested flags; ``flags`` maps a line's index in the scene to its written
    flags. Needs the run's nodes (``save_nodes``)."""
    import jax

    if res.positions is None:
        return {}
    lines = scene.lines
    k = len(np.asarray(res.ts))
    n_max = max(ln.n_segments for ln in lines)
    want = set("".join(flags.values()))
    out = {}

    def node_var():
        return np.full((k, len(lines), n_max + 1, 3), np.nan)

    def seg_var(*axis):
        return np.full((k, len(lines), n_max) + axis, np.nan)

    arrays = dict(v=node_var(), U=node_var(), t=seg_var(), c=seg_var(3), s=seg_var(), d=seg_var())
    needs_v = {"v", "c", "d"}
    have_v = res.velocities is not None
    for j, line in enumerate(lines):
        f = flags.get(j, "")
        if not f:
            continue
        n = line.n_segments
        r = np.asarray(res.positions[j])
        v = np.asarray(res.velocities[j]) if have_v else None
        q, strain, rate = _segments(r, v, _unstretched_segments(line))
        lt = line.line_type
        if "v" in f and have_v:
            arrays["v"][:, j, : n + 1] = v
        if "U" in f:
            arrays["U"][:, j, : n + 1] = np.asarray(jax.vmap(
                lambda rr, t: water_velocity(scene.env, rr, t))(r, np.asarray(res.ts)))
        if "t" in f:
            arrays["t"][:, j, :n] = np.asarray(jax.vmap(lt.axial.tension)(strain))
        if "c" in f and have_v:
            arrays["c"][:, j, :n] = (float(lt.damping) * rate)[..., None] * q
        if "s" in f:
            arrays["s"][:, j, :n] = strain
        if "d" in f and have_v:
            arrays["d"][:, j, :n] = rate
    meta = dict(
        v=("node_velocity", ("time", "line", "node", "axis"), "m/s", "node velocity"),
        U=("node_water_velocity", ("time", "line", "node", "axis"), "m/s",
           "water velocity at the node (waves and current)"),
        t=("segment_elastic_tension", ("time", "line", "segment"), "N",
           "elastic tension of the segment (without internal damping)"),
        c=("segment_damping_force", ("time", "line", "segment", "axis"), "N",
           "internal damping force of the segment (BA times strain rate, along it)"),
        s=("segment_strain", ("time", "line", "segment"), "1", "segment strain"),
        d=("segment_strain_rate", ("time", "line", "segment"), "1/s", "segment strain rate"),
    )
    for flag, (name, dims, units, long_name) in meta.items():
        if flag in want and (flag not in needs_v or have_v):
            out[name] = (dims, arrays[flag], units, long_name)
    return out


#: CSV column pattern per flag: (variable, per node or segment, components, suffix, unit)
CSV_LAYOUT = {
    "p": ("node_position", "node", "xyz", "p", "m"),
    "v": ("node_velocity", "node", "xyz", "v", "m/s"),
    "U": ("node_water_velocity", "node", "xyz", "U", "m/s"),
    "t": ("segment_elastic_tension", "segment", None, "Te", "N"),
    "c": ("segment_damping_force", "segment", "xyz", "c", "N"),
    "s": ("segment_strain", "segment", None, "St", "1"),
    "d": ("segment_strain_rate", "segment", None, "dSt", "1/s"),
}


def csv_line_columns(ds) -> list:
    """[(name, unit, values)] of the ``LineOutputs`` columns of a dataset
    (MoorDyn's channel names: ``L<id>_Node<i>_px``, ``L<id>_Seg<i>_Te`` with
    segments numbered from 1)."""
    if "line_outputs" not in ds:
        return []
    cols = []
    for j, lid in enumerate(ds["line"].values):
        flags = str(ds["line_outputs"].values[j])
        n = int(ds["n_segments"].values[j])
        for flag in flags:
            var, where, comps, suffix, unit = CSV_LAYOUT[flag]
            if var not in ds:
                continue
            data = ds[var].values[:, j]
            count = n + 1 if where == "node" else n
            for i in range(count):
                label = f"L{lid}_Node{i}" if where == "node" else f"L{lid}_Seg{i + 1}"
                if comps is None:
                    cols.append((f"{label}_{suffix}", unit, data[:, i]))
                else:
                    for c, comp in enumerate(comps):
                        cols.append((f"{label}_{suffix}{comp}", unit, data[:, i, c]))
    return cols
