"""The 3-D layout of a scene at static equilibrium."""

from __future__ import annotations

import numpy as np

from ._mpl import pyplot


def plot_statics(scene, solutions=None, *, ax=None):
    """Every line of ``scene`` at its static equilibrium in 3-D, with the seabed
    plane, anchors (end A) and fairleads (end B).

    Args:
        scene: a :class:`moorjax.Scene`.
        solutions: the lines' :class:`~moorjax.statics.fem.LineStatics` (default:
            solved here with :func:`moorjax.statics.solve_line_statics`).
    """
    plt = pyplot()
    if solutions is None:
        from ..statics import solve_line_statics

        solutions = [solve_line_statics(ln, scene.env) for ln in scene.lines]
    if ax is None:
        fig = plt.figure(figsize=(8, 6), layout="constrained")
        ax = fig.add_subplot(projection="3d")
    fig = ax.figure
    pts = []
    for line, st in zip(scene.lines, solutions):
        r = np.asarray(st.positions)
        pts.append(r)
        ax.plot(r[:, 0], r[:, 1], r[:, 2], lw=1.5,
                label=f"line {line.label}: T_B {float(st.tension_b) / 1e3:.1f} kN")
        ax.scatter(*r[0], marker="v", color="k", s=20)
        ax.scatter(*r[-1], marker="o", color="tab:red", s=20)
    allp = np.concatenate(pts)
    depth = float(scene.env.depth)
    lo, hi = allp[:, :2].min(axis=0), allp[:, :2].max(axis=0)
    pad = 0.1 * max(float(np.max(hi - lo)), 1.0)
    gx, gy = np.meshgrid([lo[0] - pad, hi[0] + pad], [lo[1] - pad, hi[1] + pad])
    ax.plot_surface(gx, gy, np.full_like(gx, -depth), color="saddlebrown", alpha=0.25)
    ax.plot_surface(gx, gy, np.zeros_like(gx), color="tab:blue", alpha=0.08)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title("static equilibrium (▼ end A, ● end B)")
    ax.legend(fontsize="small")
    return fig
