"""``moorjax plot`` and ``moorjax plot-statics``."""

from __future__ import annotations

import os
import sys


def add_parsers(subparsers):
    from .._cli_common import HelpFormatter, positive_int

    p = subparsers.add_parser(
        "plot", help="plot a run: tension histories and line profiles (with the seabed)",
        description="Plot a run written by moorjax simulate: tension histories, and line "
                    "profiles at chosen times when the run has node positions (.nc).",
        formatter_class=HelpFormatter,
        epilog="example:\n  moorjax plot run.nc --times 0,2.5,5 --out run.png --animate run.gif",
    )
    p.add_argument("run", help="output of moorjax simulate (.nc or .csv)")
    p.add_argument("--out", default=None,
                   help="figure file (.png, .pdf, .svg; default: RUN with .png)")
    p.add_argument("--times", metavar="T1,T2,...", help="profile times [s] (default: 5 spread over the run)")
    p.add_argument("--line", help="line id of the profiles (default: the first line)")
    p.add_argument("--animate", metavar="OUT.gif|OUT.mp4",
                   help="also write an animation of the line profile (mp4 needs ffmpeg)")
    p.add_argument("--fps", type=positive_int, default=20, help="animation frames per second")
    p.set_defaults(func=cmd_plot)

    s = subparsers.add_parser(
        "plot-statics", help="plot a deck's 3-D layout at static equilibrium",
        description="Plot every line of a deck at static equilibrium in 3-D, with the seabed.",
        formatter_class=HelpFormatter,
        epilog="example:\n  moorjax plot-statics example:oc3_catenary --out layout.png",
    )
    s.add_argument("deck", help="MoorDyn v2 deck, or example:NAME")
    s.add_argument("--segments", type=positive_int,
                   help="override every line's segment count (default: the deck's)")
    s.add_argument("--out", required=True, help="figure file (.png, .pdf, .svg)")
    s.set_defaults(func=cmd_plot_statics)


FIGURES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")


def _figure_path(path, option="--out"):
    from ..io.results import check_output

    return check_output(path, FIGURES, option)


def _label(text):
    return int(text) if text is not None and text.isdigit() else text


def cmd_plot(args) -> int:
    from ..io.results import check_output, read_results
    from ._mpl import pyplot
    from ._profile import animate
    from ._summary import plot_run

    if not os.path.isfile(args.run):
        raise ValueError(f"{args.run}: no such file")
    out = args.out or os.path.splitext(args.run)[0] + ".png"
    _figure_path(out)
    if args.animate:
        check_output(args.animate, (".gif", ".mp4"), "--animate")
    times = None
    if args.times:
        try:
            times = [float(x) for x in args.times.split(",")]
        except ValueError:
            raise ValueError(f"--times {args.times!r}: expected numbers in s, e.g. 0,2.5,5") from None
    pyplot(headless=True)  # a clear message now if matplotlib is missing
    ds = read_results(args.run)
    line = _label(args.line)
    if line is not None and line not in list(ds["line"].values):
        raise ValueError(f"--line {args.line}: the run has lines {', '.join(map(str, ds['line'].values))}")
    if args.animate and "node_position" not in ds:
        raise ValueError(f"--animate: {args.run} has no node positions (use a .nc run without --no-nodes)")
    fig = plot_run(ds, times=times, line=line)
    fig.savefig(out, dpi=120)
    print(f"wrote {out}", file=sys.stderr)
    if args.animate:
        animate(ds, args.animate, line=line, fps=args.fps)
        print(f"wrote {args.animate}", file=sys.stderr)
    return 0


def cmd_plot_statics(args) -> int:
    import jax

    from .._cli_load import load
    from ..statics import solve_line_statics
    from ._layout import plot_statics
    from ._mpl import pyplot

    _figure_path(args.out)
    pyplot(headless=True)
    _, scene, _ = load(args)
    sols = []
    for line in scene.lines:
        st = jax.device_get(solve_line_statics(line, scene.env, throw=False))
        if not bool(st.converged):
            raise RuntimeError(f"line {line.label}: static solve did not converge")
        sols.append(st)
    fig = plot_statics(scene, sols)
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}", file=sys.stderr)
    return 0
