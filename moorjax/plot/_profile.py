"""Line profiles (node positions) at chosen times, with the seabed and the free
surface, and their animation."""

from __future__ import annotations

import os

import numpy as np

from ._mpl import pyplot


def _need_nodes(ds):
    if "node_position" not in ds:
        raise ValueError("the run has no node positions: write it as .nc without --no-nodes "
                         "(or simulate(..., save_nodes=True))")


def _horizontal(ds, lid):
    """Horizontal coordinate [m] of each node: along the line's anchor->fairlead
    direction at the first time, measured from end A."""
    r = ds["node_position"].sel(line=lid).values  # time, node, axis
    a, b = r[0, 0], r[0, int(ds["n_segments"].sel(line=lid))]
    d = (b - a)[:2]
    d = d / max(np.linalg.norm(d), 1e-12)
    return (r[..., 0] - a[0]) * d[0] + (r[..., 1] - a[1]) * d[1], r[..., 2]


def _frame(ax, ds):
    depth = float(ds.attrs.get("water_depth", np.nan))
    ax.axhline(0.0, color="tab:blue", lw=0.8, alpha=0.6, label="free surface")
    if np.isfinite(depth):
        ax.axhline(-depth, color="saddlebrown", lw=2.0, label="seabed")
    ax.set_xlabel("horizontal distance from end A [m]")
    ax.set_ylabel("z [m]")
    ax.grid(alpha=0.3)


def plot_profiles(ds, times=None, *, line=None, ax=None):
    """Profiles of one line (default the first) at ``times`` [s] (default: five
    times spread over the run), in its vertical plane, with the seabed."""
    _need_nodes(ds)
    plt = pyplot()
    fig, ax = (plt.subplots(figsize=(8, 4), layout="constrained") if ax is None
               else (ax.figure, ax))
    lid = ds["line"].values[0] if line is None else line
    t = ds["time"].values
    times = np.linspace(t[0], t[-1], 5) if times is None else np.atleast_1d(times)
    x, z = _horizontal(ds, lid)
    for tt in times:
        i = int(np.argmin(np.abs(t - tt)))
        ax.plot(x[i], z[i], lw=1.2, label=f"t = {t[i]:.4g} s")
    _frame(ax, ds)
    ax.legend(fontsize="small")
    ax.set_title(f"line {lid} profiles")
    return fig


def animate(ds, path, *, line=None, fps=20, max_frames=300):
    """Write an animation of a line's profile to ``path`` (``.gif`` with Pillow,
    ``.mp4`` with ffmpeg); at most ``max_frames`` frames spread over the run."""
    _need_nodes(ds)
    plt = pyplot()
    from matplotlib import animation

    ext = os.path.splitext(str(path))[1].lower()
    if ext == ".gif":
        writer = animation.PillowWriter(fps=fps)
    elif ext == ".mp4":
        if not animation.FFMpegWriter.isAvailable():
            raise ValueError(f"--animate {path}: mp4 needs ffmpeg on the PATH; write .gif instead")
        writer = animation.FFMpegWriter(fps=fps)
    else:
        raise ValueError(f"--animate {path}: expected a .gif or .mp4 file")
    lid = ds["line"].values[0] if line is None else line
    t = ds["time"].values
    x, z = _horizontal(ds, lid)
    frames = np.unique(np.linspace(0, len(t) - 1, min(len(t), max_frames)).astype(int))
    fig, ax = plt.subplots(figsize=(8, 4), layout="constrained")
    _frame(ax, ds)
    pad = 0.05 * (np.nanmax(x) - np.nanmin(x) + 1.0)
    ax.set_xlim(np.nanmin(x) - pad, np.nanmax(x) + pad)
    depth = float(ds.attrs.get("water_depth", -np.nanmin(z)))
    ax.set_ylim(-depth * 1.05, max(0.0, np.nanmax(z)) + 0.05 * depth)
    (curve,) = ax.plot([], [], lw=1.5, color="k")
    title = ax.set_title("")

    def draw(i):
        curve.set_data(x[i], z[i])
        title.set_text(f"line {lid}, t = {t[i]:.3f} s")
        return curve, title

    anim = animation.FuncAnimation(fig, draw, frames=frames, blit=False)
    anim.save(str(path), writer=writer)
    plt.close(fig)
    return str(path)
