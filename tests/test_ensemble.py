"""Ensembles: vmapped runs equal single runs, failures stay isolated, no recompiles,
sharding, chunked storage with resume, structure errors, the CLI."""

import json
import os
import subprocess
import sys
import textwrap

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import moorjax as mj
from moorjax.cli import main
from moorjax.dynamics import simulate
from moorjax.dynamics.vector_field import _line_rate, pack, vector_field
from moorjax.model.grouping import line_groups
from moorjax.ensemble import StructureMismatchError, simulate_ensemble, stack, status
from moorjax.ensemble.run import TRACES
from moorjax.ensemble.store import load, run_chunked
from scenes import case_b_line_type, case_b_scene

pytestmark = pytest.mark.slow  # long physics/compile checks: CI runs them, `-m "not slow"` skips

# tight tolerances: members differ from single runs only by roundoff-driven Newton
# termination decisions, whose effect is of the order of the Newton tolerance
SETTINGS = dict(solver="kvaerno3", rtol=1e-10, atol=1e-10, dt_out=0.1)
DURATION = 2.0


def scene(cd=1.6, ea=1.5e8, amp=1.0, n=6, drag=True):
    return case_b_scene(n, mj.SinePath([0, 0, -5.0], [amp, 0, 0], 8.0), case_b_line_type(ea, cd, drag))


MEMBERS = [scene(1.2, 1.4e8, 0.5), scene(1.6, 1.5e8, 1.0), scene(2.0, 1.7e8, 1.5)]


@pytest.fixture(scope="module")
def batch_result():
    return simulate_ensemble(MEMBERS, DURATION, **SETTINGS)


def test_vmapped_ensemble_equals_members_run_one_by_one(batch_result):
    res = batch_result
    assert res.tension_b.shape == (3, 21, 1)  # t = 0, 0.1, … 2 s
    assert list(status(res)) == ["ok"] * 3
    for i, s in enumerate(MEMBERS):
        single = simulate(s, DURATION, **SETTINGS)
        for field in ("tension_a", "tension_b", "force_b"):
            a, b = np.asarray(getattr(res, field)[i]), np.asarray(getattr(single, field))
            np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-10 * np.abs(b).max())
        assert int(res.num_steps[i]) == int(single.num_steps)
    # members really differ (amplitude 0.5 m vs 1.5 m)
    assert np.ptp(res.tension_b[2]) > 2 * np.ptp(res.tension_b[0])


def test_new_parameter_values_do_not_recompile(batch_result):
    before = dict(TRACES)
    other = [scene(1.0, 1.3e8, 0.7), scene(1.1, 1.6e8, 1.2), scene(1.9, 1.5e8, 0.3)]
    res = simulate_ensemble(other, DURATION, **SETTINGS)
    assert TRACES == before, "a second call with other values retraced"
    assert list(status(res)) == ["ok"] * 3


def test_failing_member_is_reported_and_leaves_others_intact(batch_result):
    bad = eqx.tree_at(lambda s: s.lines[0].line_type.drag.cd_normal, MEMBERS[1], jnp.nan)
    with pytest.warns(UserWarning, match=r"members \[1\]: static equilibrium"):
        res = simulate_ensemble([MEMBERS[0], bad, MEMBERS[2]], DURATION, **SETTINGS)
    st = status(res)
    assert st[0] == "ok" and st[2] == "ok"
    assert st[1] != "ok"  # e.g. dt_min_reached: it stopped at once
    assert int(res.num_steps[1]) < 50
    for i in (0, 2):
        np.testing.assert_allclose(np.asarray(res.tension_b[i]),
                                   np.asarray(batch_result.tension_b[i]), rtol=1e-10)


def test_structure_mismatch_names_the_field():
    with pytest.raises(StructureMismatchError, match="n_segments: 6 vs 8"):
        stack([scene(), scene(n=8)])
    with pytest.raises(StructureMismatchError, match="drag"):
        simulate_ensemble([scene(), scene(drag=False)], 1.0)
    fixed = eqx.tree_at(lambda s: s.lines[0].end_b, scene(), mj.FixedEnd([0, 0, -5.0]))
    with pytest.raises(StructureMismatchError, match="end_b: SinePath vs FixedEnd"):
        stack([scene(), fixed])


def test_quick_structure_check_agrees_with_the_field_walk():
    """stack and run_chunked compare members by tree definition and leaf shapes
    first; over every pair of these variants (segments, a term present or not,
    end types, a leaf's shape or dtype, values only) it must find a difference
    exactly where the field-by-field walk does, and stacking on the host must
    give jnp.stack's arrays."""
    from moorjax.ensemble import batch

    base = scene()
    variants = [
        base, scene(2.0, 1.6e8, 1.3), scene(n=8), scene(drag=False),
        eqx.tree_at(lambda s: s.lines[0].end_b, base, mj.FixedEnd([0, 0, -5.0])),
        eqx.tree_at(lambda s: s.lines[0].end_b, base, mj.FixedEnd([0, 0, -6.0])),
        eqx.tree_at(lambda s: s.lines[0].line_type.diameter, base, jnp.asarray([0.1, 0.2])),
        eqx.tree_at(lambda s: s.lines[0].line_type.diameter, base, jnp.asarray(1)),
        (1.0, None, [2, jnp.zeros(3)]), (2, None, [2, jnp.ones(3)]), (1.0, 0.0, [2, jnp.zeros(3)]),
        (1.0, None, [3, jnp.zeros(3)]), (1.0, None, [True, jnp.zeros(3)]),
    ]
    for i, a in enumerate(variants):
        for j, b in enumerate(variants):
            walk = batch._difference(a, b, "m")
            assert batch._alike(a, b) == (walk is None), (i, j, walk)
            assert batch.structure_difference(a, b, "m") == walk
    members = [scene(1.2, 1.4e8, 0.5), scene(1.6, 1.5e8, 1.0)]
    host = stack(members)
    device = jax.tree_util.tree_map(lambda *xs: jnp.stack([jnp.asarray(x) for x in xs]), *members)
    for x, y in zip(jax.tree_util.tree_leaves(host), jax.tree_util.tree_leaves(device)):
        assert x.dtype == y.dtype and x.weak_type == y.weak_type and np.array_equal(x, y)
    weak = stack([(1.0, np.float32(2.0)), (3.0, np.float32(4.0))])
    assert weak[0].weak_type and weak[1].dtype == np.float32


def test_chunked_run_matches_and_resumes(tmp_path, batch_result):
    out = str(tmp_path / "ens")
    calls = []
    data = run_chunked(MEMBERS, out, DURATION, chunk_size=2, histories=True,
                       on_chunk=lambda k, n: calls.append(k), **SETTINGS)
    assert calls == [0, 1]
    np.testing.assert_allclose(data["tension_b"], np.asarray(batch_result.tension_b), rtol=1e-10)
    np.testing.assert_allclose(data["stat_tension_b_max"],
                               np.asarray(batch_result.tension_b).max(axis=1), rtol=1e-12)
    assert list(data["status"]) == ["ok"] * 3
    # a crash lost chunk 1: the rerun computes only that chunk
    os.remove(os.path.join(out, "chunks", "chunk_00001.npz"))
    calls.clear()
    again = run_chunked(MEMBERS, out, DURATION, chunk_size=2, histories=True,
                        on_chunk=lambda k, n: calls.append(k), **SETTINGS)
    assert calls == [1]
    np.testing.assert_allclose(again["tension_b"], data["tension_b"], rtol=1e-12)
    np.testing.assert_allclose(load(out)["tension_b"], data["tension_b"], rtol=1e-12)
    # a different ensemble is refused, not mixed in
    with pytest.raises(ValueError, match="different ensemble"):
        run_chunked(MEMBERS[:2], out, DURATION, chunk_size=2, **SETTINGS)


def test_a_chunk_that_fails_to_start_keeps_the_chunk_before_it(tmp_path):
    """run_chunked dispatches chunk k before writing chunk k-1: when chunk k
    is refused (a member's end below the seabed), chunk k-1, already run, must
    still be written, so that a rerun resumes after it."""
    from moorjax.model.parameters import set_parameter

    out = str(tmp_path / "ens")
    bad = set_parameter(scene(), "depth", 2.0)
    with pytest.raises(ValueError, match="ensemble member 1: .*below the seabed"):
        run_chunked(MEMBERS + [bad], out, DURATION, chunk_size=2, **SETTINGS)
    assert os.path.exists(os.path.join(out, "chunks", "chunk_00000.npz"))
    assert not os.path.exists(os.path.join(out, "chunks", "chunk_00001.npz"))
    assert list(np.load(os.path.join(out, "chunks", "chunk_00000.npz"))["status"]) == ["ok"] * 2


def test_lines_of_equal_structure_are_grouped():
    lt = case_b_line_type()
    env = mj.Environment(80.0, seabed=mj.Seabed(3e6, 3e5))
    lines = []
    for k in range(4):
        c, s = np.cos(np.pi / 2 * k), np.sin(np.pi / 2 * k)
        lines.append(mj.Line(lt, 110.0 + k, 6, mj.FixedEnd([-80.5 * c, -80.5 * s, -80]),
                             mj.FixedEnd([2 * c, 2 * s, -5.0]), label=str(k + 1)))
    lines.append(mj.Line(lt, 110.0, 4, mj.FixedEnd([-80.5, 0, -80]), mj.FixedEnd([0, 0, -5.0]),
                         label="9"))
    sc = mj.Scene(lines, env)
    assert line_groups(sc.lines) == [[0, 1, 2, 3], [4]]
    y = tuple(q.at[:, 3:].set(0.2) for q in pack([ln.straight_state() for ln in lines]))
    out = vector_field(0.3, y, sc)
    for ln, q, o in zip(lines, y, out):
        ref = _line_rate(ln, q, env, 0.3)
        np.testing.assert_allclose(np.asarray(o), np.asarray(ref), rtol=1e-12,
                                   atol=1e-12 * float(np.abs(ref).max()))


SHARDED = textwrap.dedent(
    """
    import os, sys, json
    os.environ["XLA_FLAGS"] = "--xla_force_host_platform_device_count=4"
    import jax, numpy as np
    sys.path.insert(0, sys.argv[1])
    import test_ensemble as t
    from moorjax.ensemble import simulate_ensemble
    assert len(jax.local_devices()) == 4, jax.local_devices()
    members = t.MEMBERS + [t.scene(1.4, 1.45e8, 0.8), t.scene(1.8, 1.55e8, 1.2)]  # 5: padded to 8
    fast = dict(solver="heun", dt=2e-3, dt_out=0.1)  # sharding, not the solver, is under test
    a = simulate_ensemble(members, t.DURATION, devices="all", **fast)
    shards = len(a.tension_b.sharding.device_set) if hasattr(a.tension_b, "sharding") else 1
    b = simulate_ensemble(members, t.DURATION, devices=None, **fast)
    c = simulate_ensemble(members, t.DURATION, devices="all", members_per_call=4, **fast)  # 2 calls
    # adaptive steps: each device runs its own members' time loop (shard_map);
    # every member takes the steps it takes alone
    d = simulate_ensemble(members, t.DURATION, devices="all", dt_out=0.1)
    e = simulate_ensemble(members, t.DURATION, devices=None, dt_out=0.1)
    print(json.dumps(dict(shape=list(a.tension_b.shape), devices=shards,
        diff=float(np.max(np.abs(np.asarray(a.tension_b) - np.asarray(b.tension_b)))),
        diff_calls=float(np.max(np.abs(np.asarray(c.tension_b) - np.asarray(b.tension_b)))),
        diff_adaptive=float(np.max(np.abs(np.asarray(d.tension_b) - np.asarray(e.tension_b)))),
        steps=[np.asarray(d.num_steps).tolist(), np.asarray(e.num_steps).tolist()],
        scale=float(np.max(np.abs(np.asarray(b.tension_b)))))))
    """
)


def test_sharded_over_four_cpu_devices_equals_unsharded():
    here = os.path.dirname(os.path.abspath(__file__))
    proc = subprocess.run([sys.executable, "-c", SHARDED, here], capture_output=True, text=True,
                          timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["shape"] == [5, 21, 1]
    assert out["devices"] == 4
    assert out["diff"] <= 1e-10 * out["scale"]
    assert out["diff_calls"] <= 1e-10 * out["scale"]
    assert out["diff_adaptive"] <= 1e-10 * out["scale"]
    assert out["steps"][0] == out["steps"][1] and len(set(out["steps"][0])) > 1, out["steps"]


def test_cli_ensemble_summary_and_bad_vary(tmp_path, capsys):
    out = tmp_path / "sweep"
    rc = main(["ensemble", "example:taut_polyester", "--duration", "1", "--segments", "6",
               "--vary", "Cd=1.2,2.0", "--vary", "L1.EA=1.4e8,1.6e8", "--out", str(out),
               "--histories", "--solver", "kvaerno3"])
    assert rc == 0
    rows = (out / "summary.csv").read_text().strip().splitlines()
    assert rows[0].split(",")[:5] == ["member", "Cd", "L1.EA", "status", "steps"]
    assert "L1_tension_b_max" in rows[0] and "L1_tension_a_std" in rows[0]
    assert len(rows) == 5 and all(",ok," in r for r in rows[1:])
    tmax = [float(r.split(",")[rows[0].split(",").index("L1_tension_b_max")]) for r in rows[1:]]
    assert tmax[1] > tmax[0]  # stiffer line, higher static tension
    assert len(list((out / "histories").iterdir())) == 4
    # the same as one dataset with a member dimension (units as attributes)
    import xarray as xr

    ds = xr.open_dataset(out / "ensemble.nc")
    assert ds.sizes["member"] == 4 and list(ds["Cd"].values) == [1.2, 1.2, 2.0, 2.0]
    assert list(ds["status"].values) == ["ok"] * 4
    assert ds["tension_b"].dims == ("member", "time", "line") and ds["tension_b_max"].attrs["units"] == "N"
    np.testing.assert_allclose(ds["tension_b_max"].values[:, 0], [float(v) for v in tmax])
    np.testing.assert_allclose(ds["tension_b_max"].values, ds["tension_b"].max("time").values)
    capsys.readouterr()
    for vary, msg in (("Foo=1", "valid names"), ("Cd=abc", "not a number"),
                      ("EA=-1", "must be finite and > 0"), ("L7.Cd=1", "no line 7"),
                      ("Cd", "NAME=v1")):
        rc = main(["ensemble", "example:taut_polyester", "--duration", "1", "--segments", "6",
                   "--vary", vary, "--out", str(tmp_path / "bad")])
        assert rc == 2
        assert msg in capsys.readouterr().err


CORES = textwrap.dedent(
    """
    import json, os
    import moorjax
    from moorjax.ensemble import available_cores, use_cpu_cores
    out = dict(cores=available_cores(), asked=use_cpu_cores(3), pool=os.environ.get("PJRT_NPROC"))
    try:
        use_cpu_cores(0)
    except ValueError as exc:
        out["zero"] = str(exc)
    import jax
    out["devices"] = len(jax.devices("cpu"))
    jax.numpy.ones(2).block_until_ready()  # JAX has computed: its devices are fixed now
    out["after"] = use_cpu_cores(5)
    out["devices_after"] = len(jax.devices("cpu"))
    print(json.dumps(out))
    """
)


def test_use_cpu_cores_before_and_after_jax_starts():
    env = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", "PJRT_NPROC")}
    proc = subprocess.run([sys.executable, "-c", CORES], capture_output=True, text=True,
                          timeout=300, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["cores"] >= 1
    assert out["asked"] == 3 and out["devices"] == 3
    assert out["pool"] == "4"  # one pool thread more than devices (batched LAPACK kernels)
    assert "must be >= 1" in out["zero"]
    assert out["after"] == 3 and out["devices_after"] == 3  # fixed once JAX has run
    # a count the user set in XLA_FLAGS is kept when none is asked for
    flags = dict(env, XLA_FLAGS="--xla_force_host_platform_device_count=2")
    code = ("import moorjax, jax; from moorjax.ensemble import use_cpu_cores; "
            "print(use_cpu_cores(), len(jax.devices('cpu')))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, env=flags)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.split() == ["2", "2"]


def test_cli_ensemble_shards_over_the_cpu_devices_it_asks_for(tmp_path):
    """A fresh `moorjax ensemble` process splits the CPU as --cpu-devices says and
    gives the one-device results."""
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    runs = {}
    for n in (1, 3):
        out = tmp_path / f"d{n}"
        proc = subprocess.run(
            [sys.executable, "-m", "moorjax", "ensemble", "example:taut_polyester", "--duration", "1",
             "--segments", "6", "--vary", "Cd=1.2,1.6,2.0,2.4", "--out", str(out), "--solver", "heun",
             "--dt", "2e-3", "--cpu-devices", str(n)],
            capture_output=True, text=True, timeout=600, env=env)
        assert proc.returncode == 0, proc.stderr[-3000:]
        assert f"on {n} CPU device(s)" in proc.stderr
        runs[n] = np.array([[float(v) for v in r.split(",")[4:]]
                            for r in (out / "summary.csv").read_text().strip().splitlines()[1:]])
    np.testing.assert_allclose(runs[3], runs[1], rtol=1e-10)


STORED = textwrap.dedent(
    """
    import json, sys
    from moorjax.ensemble import use_cpu_cores
    use_cpu_cores(2)
    import numpy as np
    sys.path.insert(0, sys.argv[1])
    import test_ensemble as t
    from moorjax.ensemble import simulate_ensemble
    from moorjax.ensemble.run import TRACES
    res = simulate_ensemble(t.MEMBERS, t.DURATION, solver="heun", dt=2e-3, dt_out=0.1)
    print(json.dumps(dict(traces=TRACES, devices=len(res.tension_b.sharding.device_set),
                          tension=np.asarray(res.tension_b).ravel().tolist())))
    """
)


def test_a_sharded_ensemble_is_stored_and_loaded_by_a_new_process(tmp_path):
    """Members sharded over two CPU devices: the statics and the integration are
    stored by structure, so a second process traces neither and gets the same."""
    here = os.path.dirname(os.path.abspath(__file__))
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    env.update(MOORJAX_CACHE_DIR=str(tmp_path), MOORJAX_COMPILATION_CACHE="1")
    runs = []
    for _ in range(2):
        proc = subprocess.run([sys.executable, "-c", STORED, here], capture_output=True, text=True,
                              timeout=900, env=env)
        assert proc.returncode == 0, proc.stderr[-3000:]
        runs.append(json.loads(proc.stdout.strip().splitlines()[-1]))
    assert runs[0]["devices"] == runs[1]["devices"] == 2
    assert runs[0]["traces"] == {"ensemble": 1, "statics": 1}
    assert runs[1]["traces"] == {"ensemble": 0, "statics": 0}
    assert runs[1]["tension"] == runs[0]["tension"]
    assert len([p for p in os.listdir(tmp_path / "programs") if p.endswith(".hlo")]) == 2


def test_members_beyond_one_call_run_as_calls_of_one_program():
    """Five members in calls of two (the last padded) equal one call of five, and
    the calls share one compiled program."""
    members = MEMBERS + [scene(1.4, 1.45e8, 0.8), scene(1.8, 1.55e8, 1.2)]
    fast = dict(solver="heun", dt=2e-3, dt_out=0.1)
    whole = simulate_ensemble(members, DURATION, **fast)
    before = TRACES["ensemble"]
    parts = simulate_ensemble(members, DURATION, members_per_call=2, **fast)
    assert TRACES["ensemble"] - before <= 1
    assert parts.tension_b.shape == whole.tension_b.shape == (5, 21, 1)
    np.testing.assert_allclose(np.asarray(parts.tension_b), np.asarray(whole.tension_b),
                               rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(status(parts), status(whole))
    np.testing.assert_array_equal(np.asarray(parts.num_steps), np.asarray(whole.num_steps))
    with pytest.raises(ValueError, match="members_per_call"):
        simulate_ensemble(members, DURATION, members_per_call=0, **fast)


POOL = textwrap.dedent(
    """
    import os, sys
    import moorjax
    from moorjax.ensemble import use_cpu_cores
    print(os.environ.get("PJRT_NPROC"), use_cpu_cores(2, lapack=sys.argv[1] == "1"),
          os.environ.get("PJRT_NPROC"))
    """
)


def test_the_task_pool_outnumbers_the_devices_only_where_lapack_may_run():
    """moorjax sets PJRT_NPROC=1 at import; asking for several devices for
    ensembles that may call batched LAPACK kernels raises it to devices + 1, a
    user's own value is kept, and ensembles of plain linear-element lines keep
    the pool as it is (faster)."""
    env = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", "PJRT_NPROC")}
    for lapack, want in (("1", ["1", "2", "3"]), ("0", ["1", "2", "1"])):
        proc = subprocess.run([sys.executable, "-c", POOL, lapack], capture_output=True, text=True,
                              timeout=300, env=env)
        assert proc.returncode == 0, proc.stderr[-3000:]
        assert proc.stdout.split() == want
    proc = subprocess.run([sys.executable, "-c", POOL, "1"], capture_output=True, text=True,
                          timeout=300, env=dict(env, PJRT_NPROC="2"))
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert proc.stdout.split() == ["2", "2", "2"]


def test_which_decks_may_call_lapack():
    from moorjax.cli import build_parser
    from moorjax.ensemble.cli import _may_call_lapack

    def args(*extra, deck="example:oc3_catenary"):
        return build_parser().parse_args(["ensemble", deck, "--duration", "1", "--vary", "Cd=1",
                                          "--out", "x", *extra])

    here = os.path.dirname(os.path.abspath(__file__))
    assert not _may_call_lapack(args())
    assert not _may_call_lapack(args("--solver", "heun"))
    assert _may_call_lapack(args("--element", "hermite"))
    assert _may_call_lapack(args("--solver", "kvaerno5"))
    assert _may_call_lapack(args(deck=os.path.join(here, "data", "free_body_buoy.dat")))
    assert _may_call_lapack(args(deck="no/such/deck.dat"))


def test_batched_hermite_states_pack_member_by_member():
    """An ensemble's start (Hermite states with a member axis) packs into each
    member's solver array, stacked."""
    import jax.numpy as jnp

    from moorjax.element.hermite_motion import HermiteState

    rng = np.random.default_rng(3)
    parts = {k: jnp.asarray(rng.normal(size=(4, n, 3))) for k, n in (("r", 5), ("v", 5), ("d", 7), ("dv", 7))}
    batched = HermiteState(**parts).packed()
    each = [HermiteState(**{k: v[i] for k, v in parts.items()}).packed() for i in range(4)]
    assert batched.shape == (4, 12, 6)
    np.testing.assert_array_equal(np.asarray(batched), np.stack([np.asarray(e) for e in each]))


def test_cli_hermite_ensemble_on_two_cpu_devices_finishes(tmp_path):
    """`moorjax ensemble --element hermite` on two CPU devices: Hermite lines
    call batched LAPACK kernels, which on jaxlib 0.10 hung the process with as
    many pool threads as devices; member 0 equals its single run."""
    env = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", "PJRT_NPROC")}
    out = tmp_path / "h"
    cmd = [sys.executable, "-m", "moorjax", "ensemble", "example:oc3_catenary", "--element", "hermite",
           "--segments", "4", "--duration", "1", "--vary", "Cd=1.2,1.4,1.6,2.0", "--cpu-devices", "2",
           "--out", str(out), "--quiet"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=900, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "on 2 CPU device(s); 0 failed" in proc.stderr
    import xarray as xr

    ds = xr.open_dataset(out / "ensemble.nc")
    assert list(ds["status"].values) == ["ok"] * 4
    single = subprocess.run(
        [sys.executable, "-m", "moorjax", "ensemble", "example:oc3_catenary", "--element", "hermite",
         "--segments", "4", "--duration", "1", "--vary", "Cd=1.2", "--cpu-devices", "1",
         "--out", str(tmp_path / "one"), "--quiet"], capture_output=True, text=True, timeout=900, env=env)
    assert single.returncode == 0, single.stderr[-3000:]
    one = xr.open_dataset(tmp_path / "one" / "ensemble.nc")
    np.testing.assert_allclose(ds["tension_b_max"].values[0], one["tension_b_max"].values[0], rtol=1e-6)


def test_a_pool_no_wider_than_the_devices_is_detected(monkeypatch):
    """simulate_ensemble runs on one device (with a warning) where several CPU
    devices could starve XLA:CPU's task pool in batched LAPACK kernels."""
    from moorjax.dynamics.settings import plan
    from moorjax.element import HermiteElement
    from moorjax.ensemble.run import _pool_may_starve
    from moorjax.examples import example_path
    from moorjax.io import build_scene, read_deck

    deck = read_deck(example_path("oc3_catenary"))
    linear = build_scene(deck, segments=8)
    hermite = build_scene(deck, segments=4, element=HermiteElement())
    monkeypatch.setenv("PJRT_NPROC", "1")
    assert _pool_may_starve(hermite, plan(1.0, scene=hermite), 2)
    assert _pool_may_starve(linear, plan(1.0, scene=linear, solver="kvaerno5"), 2)
    assert not _pool_may_starve(linear, plan(1.0, scene=linear), 2)
    assert not _pool_may_starve(linear, plan(1.0, scene=linear, solver="heun", dt=1e-3), 2)
    assert not _pool_may_starve(hermite, plan(1.0, scene=hermite), 1)
    monkeypatch.setenv("PJRT_NPROC", "3")
    assert not _pool_may_starve(hermite, plan(1.0, scene=hermite), 2)
