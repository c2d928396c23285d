"""What a new user meets (issue 16): bundled examples that move, netCDF and CSV
outputs with units, plots, checks of options before any compile, plausibility
warnings, exit codes, ``--version`` and ``python -m moorjax``, help text,
progress.

Dynamic runs use ``example:taut_polyester`` at 6 segments for 1 s (one compile of
the integrator for the module; each further run costs its static solve).
"""

from __future__ import annotations

import contextlib
import io
import json
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import moorjax
from moorjax import cli
from moorjax.cli import main
from moorjax.examples import EXAMPLES, example
from moorjax.examples.motions import sample
from moorjax.io import read_motion

DECK = "example:taut_polyester"
BASE = ["--duration", "1", "--segments", "6", "--dt-out", "0.1"]
ROOT = Path(__file__).resolve().parents[1]


def run(*argv):
    """(exit code, stdout, stderr) of ``moorjax argv``, warnings as the CLI prints them."""
    out, err = io.StringIO(), io.StringIO()
    def show(message, category, filename, lineno, file=None, line=None):
        sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))

    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = show  # as outside pytest (which records warnings)
        rc = main(list(map(str, argv)))
    return rc, out.getvalue(), err.getvalue()


def write_motion(path, t, x, z):
    """A fairlead path with as many samples as the example's motion file (and
    velocities), so that runs share the module's compilation."""
    assert len(t) == 2401
    h = 1e-6
    vx, vz = (x(t + h) - x(t - h)) / (2 * h), (z(t + h) - z(t - h)) / (2 * h)
    rows = np.column_stack([t, x(t), 0 * t, z(t), vx, 0 * t, vz])
    np.savetxt(path, rows, delimiter=",", header="t,P2_x,P2_y,P2_z,P2_vx,P2_vy,P2_vz", comments="",
               fmt="%.12g")
    return path


@pytest.fixture(scope="module")
def example_run(tmp_path_factory):
    """The bundled example with its own motion, written as netCDF and CSV."""
    d = tmp_path_factory.mktemp("example")
    rc, _, err = run("simulate", DECK, *BASE, "--out", d / "run.nc")
    assert rc == 0, err
    rc, _, err2 = run("simulate", DECK, *BASE, "--out", d / "run.csv")
    assert rc == 0, err2
    return d, err


# ------------------------------------------------------------------ examples


def test_examples_ship_their_motion():
    """Each example's motion file is the deck's sine surge (exact at the samples,
    with the exact velocity) and covers 600 s."""
    for name in EXAMPLES:
        ex = example(name)
        m = read_motion(ex.motion, [ex.point])
        assert m.t[0] == 0.0 and m.t[-1] >= 600.0
        ref = sample(ex, m.t)
        np.testing.assert_allclose(m.positions[ex.point], ref[:, 1:4], atol=1e-8)
        np.testing.assert_allclose(m.velocities[ex.point], ref[:, 4:7], atol=1e-8)
        x = m.positions[ex.point][:, 0]
        assert np.ptp(x) == pytest.approx(2 * ex.amplitude, rel=1e-6)


def test_examples_listing_says_what_each_shows():
    rc, out, _ = run("examples")
    assert rc == 0
    for name in EXAMPLES:
        ex = example(name)
        assert f"example:{name}" in out and ex.shows in out and ex.motion in out


@pytest.mark.slow
def test_example_moves_by_default(example_run):
    """Without --motion the example runs with its surge: the fairlead moves along x
    as the file says, and the tension varies by far more than a held line's."""
    d, _ = example_run
    ds = xr.open_dataset(d / "run.nc")
    ex = example("taut_polyester")
    xb = ds["position_b"].sel(line=1, axis="x").values
    np.testing.assert_allclose(xb, sample(ex, ds["time"].values)[:, 1], atol=1e-4)
    tb = ds["tension_b"].sel(line=1).values
    assert np.ptp(tb) > 0.5 * np.mean(tb)
    assert "motion.csv" in ds.attrs["motion"]


# ------------------------------------------------------------------ outputs


def test_netcdf_structure(example_run):
    d, _ = example_run
    ds = xr.open_dataset(d / "run.nc")
    assert {"time", "line", "node", "segment", "point", "axis"} <= set(ds.dims)
    assert ds.sizes["node"] == 7 and ds.sizes["segment"] == 6
    for name, unit in (("tension_a", "N"), ("tension_b", "N"), ("force_b", "N"),
                       ("node_position", "m"), ("segment_tension", "N"), ("point_force", "N"),
                       ("position_b", "m")):
        assert ds[name].attrs["units"] == unit and ds[name].attrs["long_name"]
    assert ds["time"].attrs["units"] == "s"
    assert ds.attrs["moorjax_version"] == moorjax.__version__
    assert "LINE TYPES" in ds.attrs["deck_text"]
    settings = json.loads(ds.attrs["settings"])
    # the default, auto, is recorded as what ran: ROS34PW2 at the tolerances given
    assert settings["solver"] == "ros34pw2"
    np.testing.assert_allclose([settings["rtol"], settings["atol"], settings["atol_velocity"]],
                               [1e-5, 1e-4, 1e-2], rtol=1e-12)
    # the end nodes are the ends; the fairlead force is the point's force
    np.testing.assert_allclose(ds["node_position"].isel(node=-1).values, ds["position_b"].values)
    np.testing.assert_allclose(ds["point_force"].sel(point=2).values,
                               ds["force_b"].sel(line=1).values)
    np.testing.assert_allclose(np.linalg.norm(ds["force_b"].values, axis=-1), ds["tension_b"].values,
                               rtol=1e-12)
    # segment tensions next to the fairlead approach its tension (end node's own
    # weight and drag are small for this light line)
    np.testing.assert_allclose(ds["segment_tension"].isel(segment=-1).values, ds["tension_b"].values,
                               rtol=0.05)


def test_csv_header_units_and_numbers(example_run):
    """Header row as before, then a ``# units:`` row, then at most 15 significant digits;
    numpy readers that skip comments see the old layout; same numbers as the .nc."""
    d, _ = example_run
    lines = (d / "run.csv").read_text().splitlines()
    assert lines[0] == "t,L1_tension_a,L1_tension_b,P2_Fx,P2_Fy,P2_Fz"
    assert lines[1] == "# units: s,N,N,N,N,N"
    assert all(len(c) <= 22 for c in lines[2].split(","))  # no 5.000000000000000278e-02
    data = np.loadtxt(d / "run.csv", delimiter=",", skiprows=1)
    ds = xr.open_dataset(d / "run.nc")
    np.testing.assert_allclose(data[:, 0], ds["time"].values, atol=1e-12)  # the run's own times
    np.testing.assert_allclose(data[:, 2], ds["tension_b"].sel(line=1).values, rtol=1e-14)
    assert lines[2].split(",")[0] in ("0", "0.1")  # the run's first time, written plainly


def test_python_dataset_and_no_nodes(example_run, tmp_path):
    """In Python, ``to_dataset`` of ``simulate(save_nodes=True)`` equals the CLI's
    file; writing with ``nodes=False`` (what ``--no-nodes`` does) leaves node
    variables out. (--motion none, the held fairlead: tests/test_cli_simulate.py.)"""
    from moorjax.dynamics import simulate
    from moorjax.io import build_scene, read_deck, read_deck_motion, write_results
    from moorjax.io.dataset import to_dataset

    d, _ = example_run
    cli_ds = xr.open_dataset(d / "run.nc")
    ex = example("taut_polyester")
    deck = read_deck(ex.deck)
    motion = read_deck_motion(ex.motion, deck)
    scene = build_scene(deck, segments=6, motion=motion)
    res = simulate(scene, 1.0, dt_out=0.1, save_nodes=True)
    ds = to_dataset(res, scene, deck=deck, motion=motion)
    assert isinstance(ds, xr.Dataset) and ds["node_position"].shape == (len(res.ts), 1, 7, 3)
    for name in ("tension_b", "node_position", "segment_tension", "point_force"):
        np.testing.assert_allclose(ds[name].values, cli_ds[name].values, rtol=1e-12)
    write_results(ds, tmp_path / "slim.nc", nodes=False)
    slim = xr.open_dataset(tmp_path / "slim.nc")
    assert "node_position" not in slim and "segment_tension" not in slim and "tension_b" in slim
    args = cli.build_parser().parse_args(["simulate", DECK, "--duration", "1", "--out", "x.nc",
                                          "--no-nodes"])
    assert args.no_nodes


# ------------------------------------------------------------------ plots


def test_plot_run_csv_and_animation(example_run, tmp_path):
    d, _ = example_run
    png = tmp_path / "run.png"
    rc, _, err = run("plot", d / "run.nc", "--times", "0,0.5,1", "--out", png,
                     "--animate", tmp_path / "run.gif", "--fps", "5")
    assert rc == 0, err
    assert png.stat().st_size > 10_000 and (tmp_path / "run.gif").stat().st_size > 1000
    assert png.read_bytes()[:4] == b"\x89PNG"
    rc, _, err = run("plot", d / "run.csv", "--out", tmp_path / "csv.png")
    assert rc == 0, err
    rc, _, err = run("plot", d / "run.csv", "--animate", tmp_path / "x.gif", "--out", tmp_path / "y.png")
    assert rc == 2 and "no node positions" in err


def test_plot_statics_and_python_functions(tmp_path, example_run):
    import matplotlib

    from moorjax import plot

    rc, _, err = run("plot-statics", "example:oc3_catenary", "--segments", "20",
                     "--out", tmp_path / "layout.png")
    assert rc == 0, err
    assert (tmp_path / "layout.png").stat().st_size > 10_000
    d, _ = example_run
    ds = xr.open_dataset(d / "run.nc")
    for fig in (plot.plot_tensions(ds), plot.plot_profiles(ds, [0.5]), plot.plot_run(ds)):
        assert isinstance(fig, matplotlib.figure.Figure)
    ax = plot.plot_profiles(ds, [0.5]).axes[0]
    assert any(ln.get_label() == "seabed" and ln.get_ydata()[0] == -80.0 for ln in ax.lines)


def test_plot_without_matplotlib_says_how_to_install(example_run, monkeypatch, tmp_path):
    d, _ = example_run
    for name in [m for m in sys.modules if m == "matplotlib" or m.startswith("matplotlib.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import fails
    rc, _, err = run("plot", d / "run.nc", "--out", tmp_path / "x.png")
    assert rc == 2 and 'pip install "moorjax[plot]"' in err and "Traceback" not in err


# ------------------------------------------------------------------ checks first


@pytest.mark.parametrize("out, expect", [
    ("run.txt", "unknown file type"),
    ("missing_dir/run.nc", "does not exist"),
    (".", "is a directory"),
])
def test_bad_out_refused_before_any_work(tmp_path, out, expect):
    start = time.perf_counter()
    rc, _, err = run("simulate", "example:oc3_catenary", "--duration", "600", "--out", tmp_path / out)
    assert rc == 2 and expect in err, err
    assert time.perf_counter() - start < 5.0  # nothing compiled or solved


def test_bad_plot_out_and_fit_out(tmp_path):
    rc, _, err = run("plot-statics", DECK, "--out", tmp_path / "x.nc")
    assert rc == 2 and "unknown file type" in err
    rc, _, err = run("fit", DECK, "--target", tmp_path / "t.csv", "--params", "Cd_normal",
                     "--motion", tmp_path / "m.csv", "--out", tmp_path / "nowhere" / "fit.json")
    assert rc == 2 and "does not exist" in err


def test_motion_starting_late_is_refused(tmp_path):
    """A motion that starts after the run is refused (never a point held still)."""
    m = tmp_path / "late.csv"
    write_motion(m, 0.5 + np.arange(2401) * 0.25, lambda t: 0 * t, lambda t: -5.0 + 0 * t)
    rc, _, err = run("simulate", DECK, *BASE, "--motion", m, "--out", tmp_path / "o.nc")
    assert rc == 2
    assert "late.csv" in err and "covers t = 0.5" in err and "needs" in err


def test_fairlead_above_the_surface(tmp_path):
    """A fairlead lifted from z = -5 m to +1 m: the linear element wets only what is
    under water, so nothing is warned; for an element without a free-surface model
    (``dry_ok`` False) check_run names the line and the first time."""
    from moorjax.io.plausibility import check_run

    m = tmp_path / "lift.csv"
    write_motion(m, np.arange(2401) * 0.25, lambda t: 0 * t, lambda t: -5.0 + 6.0 * np.minimum(t, 1.0))
    rc, _, err = run("simulate", DECK, *BASE, "--motion", m, "--out", tmp_path / "o.nc")
    assert rc == 0, err
    assert "free surface" not in err, err
    ds = xr.open_dataset(tmp_path / "o.nc")
    assert check_run(ds, dry_ok=[True]) == []
    (msg,) = check_run(ds)
    assert msg.startswith("line 1:") and "free surface from t = 0.9 s" in msg, msg


def test_strain_beyond_the_law_is_named():
    """check_run on a dataset whose fairlead ran away: strain, time and line named."""
    from moorjax.io.plausibility import check_run

    t = np.array([0.0, 1.0])
    nodes = np.zeros((2, 1, 3, 3))
    nodes[:, 0, :, 2] = -50.0
    nodes[0, 0, :, 0] = [0.0, 50.0, 100.0]
    nodes[1, 0, :, 0] = [0.0, 50.0, 300.0]  # second segment 250 m long: strain 4
    ds = xr.Dataset(dict(
        node_position=(("time", "line", "node", "axis"), nodes),
        tension_b=(("time", "line"), np.array([[1e5], [2.25e8]])),
        unstretched_length=(("line",), [100.0]), n_segments=(("line",), [2]),
    ), coords=dict(time=t, line=[3]))
    (msg,) = check_run(ds)
    assert "line 3" in msg and "strain 4 exceeds 0.5" in msg and "t = 1 s" in msg


# ------------------------------------------------------------------ conventions


def test_version_and_python_m():
    assert isinstance(moorjax.__version__, str) and moorjax.__version__.count(".") == 2
    with pytest.raises(SystemExit) as info, contextlib.redirect_stdout(io.StringIO()) as out:
        main(["--version"])
    assert info.value.code == 0 and out.getvalue().strip() == f"moorjax {moorjax.__version__}"
    p = subprocess.run([sys.executable, "-m", "moorjax", "--version"], capture_output=True,
                       text=True, cwd=ROOT, timeout=120,
                       env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})
    assert p.returncode == 0 and p.stdout.strip() == f"moorjax {moorjax.__version__}"


@pytest.mark.parametrize("exc, code, words", [
    (ValueError("bad value"), 2, "bad value"),
    (RuntimeError("simulation with kvaerno5 failed at t ≈ 3 s"), 3, "failed at t"),
    (MemoryError(), 4, "out of memory"),
    (RuntimeError("RESOURCE_EXHAUSTED: Out of memory allocating 1e12 bytes"), 4, "out of memory"),
    (OSError(28, "No space left on device", "run.nc"), 4, "No space left"),
    (FileNotFoundError(2, "No such file or directory", "deck.dat"), 2, "deck.dat"),
    (KeyboardInterrupt(), 130, "interrupted"),
])
def test_exit_codes(monkeypatch, exc, code, words):
    def boom(args):
        raise exc
    monkeypatch.setattr(cli, "cmd_statics", boom)
    rc, _, err = run("statics", DECK)
    assert rc == code
    assert words in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err


def test_long_tokens_are_clipped(tmp_path):
    token = "x" * 1_000_000
    rc, _, err = run("statics", tmp_path / token)
    assert rc == 2 and len(err) < 1000 and "more characters" in err
    with pytest.raises(SystemExit), contextlib.redirect_stderr(io.StringIO()) as e:
        main(["statics", DECK, "--segments", token])
    assert len(e.getvalue()) < 1000


def test_help_has_defaults_examples_and_no_markup():
    parser = cli.build_parser()
    top = parser.format_help()
    assert "``" not in top and "exit codes" in top and "moorjax simulate" in top
    subs = parser._subparsers._group_actions[0].choices
    for name, sp in subs.items():
        text = sp.format_help()
        assert "example:\n  moorjax " + name in text, name
    sim = subs["simulate"].format_help()
    for frag in ("(default: auto)", "(default: 1e-05)", "(default: 0.05)", "(default: 0.0)"):
        assert frag in " ".join(sim.split()), frag


def test_fit_json_names_the_optimiser(tmp_path, monkeypatch):
    """The JSON says ``lbfgs``/``adam`` as given, not optax's class name. The fit
    itself is replaced by a stand-in (fits are tested in tests/test_identify.py);
    what runs is the CLI's reading of the files and writing of the JSON."""
    import importlib
    import types

    fit_module = importlib.import_module("moorjax.identify.fit")  # the package exports fit()

    def fake_fit(exp, free, optimizer=None, callback=None, **kw):
        callback(1, {"L1.Cd_normal": 1.5}, 2.0)
        names = [f.name for f in free]
        return types.SimpleNamespace(
            to_json=lambda: dict(params={n: {} for n in names},
                                 settings=dict(optimizer="GradientTransformationExtraArgs")),
            initial={n: 1.6 for n in names}, values={n: 1.5 for n in names}, initial_loss=3.0,
            final_loss=2.0, iterations=1, status="converged", message="")

    monkeypatch.setattr(fit_module, "fit", fake_fit)
    d = tmp_path
    motion = d / "motion.csv"
    rows = sample(example("taut_polyester"), np.linspace(0.0, 1.0, 11))
    np.savetxt(motion, rows, delimiter=",", header="t,P2_x,P2_y,P2_z,P2_vx,P2_vy,P2_vz", comments="")
    (d / "target.csv").write_text("t,L1_tension_b\n# units: s,N\n" +
                                  "".join(f"{t:g},{5e4 + t}\n" for t in np.linspace(0.0, 1.0, 11)))
    for opt in ("lbfgs", "adam"):
        rc, _, err = run("fit", DECK, "--target", d / "target.csv", "--params", "Cd_normal",
                         "--motion", motion, "--segments", "6", "--optimizer", opt,
                         "--out", d / "fit.json")
        assert rc == 0, err
        assert json.loads((d / "fit.json").read_text())["settings"]["optimizer"] == opt


# ------------------------------------------------------------------ progress


class _Tty(io.StringIO):
    def isatty(self):
        return True


def test_progress_only_on_a_terminal():
    from moorjax._progress import Progress, enabled

    assert not enabled(False, io.StringIO()) and not enabled(True, _Tty())
    assert enabled(False, _Tty())
    s = _Tty()
    p = Progress("simulate", True, stream=s)
    with p.meter(0.0, 60.0):
        print("0.00%")
        print("50.00%")
    text = s.getvalue()
    assert "t = 30 / 60 s simulated" in text and "50.0%" in text and text.endswith("\n")


def test_statics_of_a_fairlead_above_the_surface(tmp_path):
    """Linear lines wet only what is under water (no warning); the Hermite element
    has no free-surface model and is warned about."""
    text = Path(example("taut_polyester").deck).read_text()
    deck = tmp_path / "high.dat"
    deck.write_text(text.replace("2  Coupled 0.0 0.0 -5.0", "2  Coupled 0.0 0.0 1.0"))
    rc, out, err = run("statics", deck, "--segments", "6", "--json")
    assert rc == 0, err
    assert "free surface" not in err, err
    rc, out, err = run("statics", deck, "--segments", "6", "--json", "--element", "hermite")
    assert rc == 0, err
    assert "moorjax statics: warning: line 1: nodes above the free surface" in err
    assert "z = 1 m" in err and "HermiteElement has no free-surface model" in err


def test_stats_come_from_one_run(tmp_path, monkeypatch):
    """--stats no longer simulates twice: one call, compile time from JAX's events."""
    import moorjax.dynamics

    calls = []
    real = moorjax.dynamics.simulate

    def counted(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(moorjax.dynamics, "simulate", counted)
    rc, _, err = run("simulate", DECK, *BASE, "--stats", "--out", tmp_path / "s.nc")
    assert rc == 0, err
    stats = json.loads([ln for ln in err.splitlines() if ln.startswith("{")][0])
    assert len(calls) == 1
    assert stats["compile_s"] >= 0 and stats["run_s"] > 0 and stats["steps"] > 0


def test_fit_callback_gets_the_gradient_norm_where_it_asks():
    from moorjax.identify.fit import _takes_grad_norm

    assert _takes_grad_norm(lambda it, values, loss, grad_norm=None: None)
    assert _takes_grad_norm(lambda it, values, loss, **kw: None)
    assert not _takes_grad_norm(lambda it, values, loss: None)


@pytest.mark.parametrize("fast_exit", ["1", "0"])
def test_the_command_ends_with_its_code_and_its_output_delivered(tmp_path, fast_exit):
    """``moorjax.cli.leave`` ends the process without Python's finalisation
    (``os._exit``): what the command printed must still arrive through pipes
    and its exit code must be kept; with
    ``MOORJAX_FAST_EXIT=0`` it exits as before."""
    import os

    env = dict(os.environ, MOORJAX_FAST_EXIT=fast_exit)
    bad = subprocess.run([sys.executable, "-m", "moorjax", "simulate", str(tmp_path / "absent.dat"),
                          "--duration", "1", "--out", str(tmp_path / "x.csv")],
                         capture_output=True, text=True, env=env, timeout=300)
    assert bad.returncode == 2, bad
    assert bad.stderr.strip().endswith("No such file or directory"), bad.stderr
    ok = subprocess.run([sys.executable, "-m", "moorjax", "statics", DECK, "--segments", "6", "--json"],
                        capture_output=True, text=True, env=env, timeout=300)
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)  # complete, parseable output


@pytest.mark.parametrize("fast_exit", ["1", "0"])
def test_a_reader_that_goes_away_ends_the_command_quietly(fast_exit):
    """``moorjax statics deck --json | head -c 10``: the pipe closes before the
    command writes; it ends with 141 (as a shell reports SIGPIPE) and says
    nothing, neither an error line nor Python's complaint at exit."""
    import os

    env = dict(os.environ, MOORJAX_FAST_EXIT=fast_exit)
    proc = subprocess.Popen([sys.executable, "-m", "moorjax", "statics", DECK, "--segments", "6", "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    proc.stdout.close()  # the reader is gone before anything is written
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=300) == cli.EXIT_PIPE
    assert err == ""


@pytest.mark.parametrize("switch", ["1", "0"])
def test_the_command_collects_garbage_less_often(switch):
    """``moorjax.cli.run`` freezes what is imported and raises the young
    generation's threshold (``_fewer_collections``); ``MOORJAX_GC_TUNING=0``
    leaves Python's defaults. In a new process: it changes the process's state."""
    import os

    code = ("import gc; from moorjax import cli; before = gc.get_threshold()[0]; "
            "cli._fewer_collections(); "
            "print(before, gc.get_threshold()[0], gc.get_freeze_count() > 0)")
    env = dict(os.environ, MOORJAX_GC_TUNING=switch)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    before, after, frozen = out.stdout.split()
    if switch == "1":
        assert int(after) == max(int(before), cli.GC_YOUNG) and frozen == "True"
    else:
        assert after == before and frozen == "False"
