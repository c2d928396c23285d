"""Ensembles: many scenes of one structure as one vmapped, compiled computation.

``simulate_ensemble`` stacks the members (see :mod:`moorjax.ensemble.batch`),
finds each member's static equilibrium (one ``vmap`` of
:func:`moorjax.dynamics.equilibrium_state`, bodies included), and integrates all
of them with one ``vmap`` of :func:`moorjax.dynamics.integrate`, the function
:func:`moorjax.dynamics.simulate` runs. Results come back as a :class:`~moorjax.dynamics.SimulationResult` whose
arrays have a leading member axis.

Failure isolation: every member has its own step size, Newton iterations and
diffrax result code. A member whose state turns non-finite stops at once with
``dt_min_reached``; its outputs are non-finite but no other member's are
touched (vmapped arithmetic is elementwise along the member axis). ``status``
summarises each member.

Devices: with ``devices`` (default: all local devices) the member axis is
sharded with ``jax.sharding`` (``NamedSharding`` over a 1-D mesh named
``"member"``); each device integrates its share of the members in its own time
loop (``shard_map``, :func:`_per_device`), and the statics and
the integration are stored by structure and sharding like a single run's
(:class:`moorjax._cache.StoredProgram`), so a new process neither traces nor
compiles them. On CPU, :func:`moorjax.ensemble.use_cpu_cores` makes one device
per core (``moorjax ensemble`` does). On several hosts,
call ``jax.distributed.initialize()`` on every process first: ``jax.devices()``
then lists the devices of all hosts and the same code shards across them
(each process must build the same member list).

Compilation: the compiled function depends only on the structure (segment
counts, force terms, solver, tolerances' *types*, member count per call), so a
second call with other parameter values does not recompile; :data:`TRACES`
counts traces (used by the tests).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from .._cache import StoredProgram
from ..dynamics.initial import (check_geometry, equilibrium_state, lines_at_rest, resolution_offsets,
                               start_layout)
from ..dynamics.integrate import (SUCCESS_CODE, SimulationResult, integrate, result_codes,
                                  result_names, storable_run)
from ..dynamics.settings import plan
from ..dynamics.vector_field import pack
from . import batch as _batch

#: number of times the batched integrator has been traced (compiled) so far
TRACES = {"ensemble": 0, "statics": 0}

STATUS_OK = "ok"

#: default members per device in one integration call (see simulate_ensemble)
PER_DEVICE = 50


def _vmapped_integrate(scenes, y0, settings, devices=1):
    TRACES["ensemble"] += 1  # runs at trace time only
    run = eqx.filter_vmap(integrate, in_axes=(0, 0, None))
    return run(scenes, y0, settings) if devices == 1 else _per_device(run, devices)(scenes, y0, settings)


def _per_device(run, devices):
    """``run(scenes, y0, settings)`` on each device's share of the members
    (``shard_map`` over the ``"member"`` axis of ``devices`` devices): every
    device steps its own members in its own time loop.

    Left to XLA's partitioner, the vmapped time loop is one loop over all
    devices: its condition (any member not yet at its end) is reduced across the
    devices at every step, and each device waits for the others there. Per
    device, 100 members of ``oc3_catenary`` (N = 20, 20 s) on two CPU devices
    run in 0.91–0.97 s instead of 1.07–1.09 s, with identical results
    (``benchmarks/README.md``, session 41). The mesh is abstract: the devices
    are those the arguments are placed on."""
    mesh = jax.sharding.AbstractMesh((devices,), ("member",))
    out_static = {}

    def local(dynamic, static):
        out = run(*eqx.combine(dynamic, static))
        arrays, out_static["value"] = eqx.partition(out, eqx.is_array)
        return arrays

    def call(scenes, y0, settings):
        (sd, yd, pd), static = eqx.partition((scenes, y0, settings), eqx.is_array)
        spec = PartitionSpec("member")
        arrays = jax.shard_map(lambda a, b, c: local((a, b, c), static), mesh=mesh,
                               in_specs=(spec, spec, PartitionSpec()), out_specs=spec,
                               check_vma=False)(sd, yd, pd)
        return eqx.combine(arrays, out_static["value"])

    return call


#: the batched integration, stored by structure like ``simulate``'s (a new process
#: running an ensemble of the same structure and member count loads it)
_batched_integrate = StoredProgram(_vmapped_integrate, sharded=True, compile_for="members",
                                 storable=lambda scenes, y0, settings, devices=1: storable_run(
                                     scenes, y0, settings))


def _traced_equilibrium(scene, t0):
    TRACES["statics"] += 1
    eq = equilibrium_state(scene, t0)
    return eq.state, eq.lines_converged, eq.converged, resolution_offsets(scene, eq, t0)


def _vmapped_equilibrium(scenes, t0):
    return eqx.filter_vmap(_traced_equilibrium, in_axes=(0, None))(scenes, t0)


#: the batched statics, stored by structure too (tracing it costs about 2.5 s)
_batched_equilibrium = StoredProgram(_vmapped_equilibrium, sharded=True, compile_for="members")


def equilibrium(scenes, t0: float = 0.0):
    """Static equilibrium of every member (vmapped): (stacked initial states, converged).

    The states are ``simulate``'s ``init`` (line states, then each body at rest
    at its pose), stacked; ``converged`` is (members, lines) bool, each line's
    entry also False when the member's bodies did not reach their balance.
    Geometry errors (an end below the seabed, a line too short for its ends)
    are raised for the first offending member of a list before anything runs.
    Grounded lines of equal Hermite elements are checked as a single start
    checks them (:func:`moorjax.statics.hermite.check_resolution`), all members
    at once: one :class:`~moorjax.statics.hermite.UnresolvedTouchdownWarning`
    per line names the members whose touchdown it does not resolve.
    """
    if isinstance(scenes, (list, tuple)):
        _check_members(scenes, t0)
        scenes = _batch.stack(scenes, name="scene")
    state, ok, off = _equilibrium(scenes, t0)
    warn_unresolved(scenes, off)
    return state, ok


def _equilibrium(scenes, t0):
    """(states, converged (members, lines), touchdown offsets (members, lines, 2) or None)."""
    state, lines_ok, ok, off = _batched_equilibrium(scenes, float(t0))
    return state, lines_ok & ok[:, None], None if off is None else np.asarray(off)


def warn_unresolved(scenes, off, members=None):
    """One :class:`~moorjax.statics.hermite.UnresolvedTouchdownWarning` per
    line whose touchdown offsets ``off`` ((members, lines, 2), from the batched
    statics) exceed :data:`~moorjax.statics.hermite.RESOLUTION_TOL` in some
    members (of the first ``members``; default all), naming them."""
    from ..statics.hermite import (FINE_SEGMENTS, RESOLUTION_ADVICE, RESOLUTION_TOL,
                                   UnresolvedTouchdownWarning)

    if off is None:
        return
    off = off[:members] if members is not None else off
    worst = np.nanmax(np.where(np.isfinite(off), off, -np.inf), axis=2)  # (members, lines)
    for j, line in enumerate(scenes.lines):
        bad = np.flatnonzero(worst[:, j] > RESOLUTION_TOL)
        if not bad.size:
            continue
        shown = bad.tolist() if bad.size <= 20 else bad[:20].tolist() + ["..."]
        n = line.n_segments
        warnings.warn(
            f"line {line.label}: {n} equal Hermite elements do not resolve its touchdown in "
            f"{bad.size} of {off.shape[0]} ensemble members {shown}: their static end tensions differ "
            f"by up to {100 * worst[bad, j].max():.3g} % from the linear element's at {FINE_SEGMENTS * n} "
            f"segments. {RESOLUTION_ADVICE}", UnresolvedTouchdownWarning, stacklevel=3)


def _pool_may_starve(scene, settings, n_devices) -> bool:
    """Whether ``n_devices`` CPU devices running this ensemble at once could
    starve XLA:CPU's task pool: the programs may call batched LAPACK kernels
    (anything but linear-element lines with a band under ROS34PW2 or an
    explicit solver) and the pool (``PJRT_NPROC`` as the process started, else
    the cores) has no more threads than devices
    (:func:`moorjax._xla_flags.pool_for_devices`)."""
    import os

    from ..dynamics.settings import factorises_nothing_dense
    from ..dynamics.vector_field import has_stiff_band, inertial_ends

    if n_devices < 2 or jax.default_backend() != "cpu":
        return False
    try:
        pool = int(os.environ.get("PJRT_NPROC") or os.cpu_count() or 1)
    except ValueError:
        pool = os.cpu_count() or 1
    if pool > n_devices:
        return False
    plain = (has_stiff_band(scene) and not inertial_ends(scene)
             and factorises_nothing_dense(settings.solver))
    return not plain


def _check_members(scenes, t0):
    """Each member's geometry (a ``ValueError`` naming the first bad one), then one
    :class:`~moorjax.statics.hermite.PiledLineWarning` per Hermite line piled on
    the bed in some members (bodies at rest), naming them."""
    from ..statics.hermite import PILED_ADVICE, PiledLineWarning, piled_path

    piled = {}
    for i, s in enumerate(scenes):
        try:
            check_geometry(s, t0)
        except ValueError as exc:
            raise ValueError(f"ensemble member {i}: {exc}") from None
        for j, line in enumerate(lines_at_rest(s)):
            found = piled_path(line, s.env, t0)
            if found is not None:
                piled.setdefault(j, []).append((i, found[0] - found[1]))
    for j, members in piled.items():
        bad = [i for i, _ in members]
        shown = bad if len(bad) <= 20 else bad[:20] + ["..."]
        warnings.warn(
            f"line {scenes[0].lines[j].label}: in {len(bad)} of {len(scenes)} ensemble members {shown} "
            f"its unstretched length exceeds its path along the seabed (by up to "
            f"{max(e for _, e in members):.4g} m: the horizontal distance of its ends plus their heights "
            f"above the bed, bodies at rest), so {PILED_ADVICE}", PiledLineWarning, stacklevel=3)


def _shard(tree, spec):
    """``tree``'s arrays placed with ``spec``. An array on one device is split on
    the host: ``device_put`` would slice it on its device by a small compiled
    program per leaf shape (each traced and read from the cache in a new process)."""
    def put(x):
        if not isinstance(x, jax.Array):
            return x
        if len(x.sharding.device_set) == 1 and not x.weak_type:
            return jax.device_put(np.asarray(x), spec)
        return jax.device_put(x, spec)

    return jax.tree_util.tree_map(put, tree)


def _pad(tree, n_total):
    """Repeat the last member so the batch has n_total members."""
    n = _batch.size(tree)
    if n == n_total:
        return tree
    index = np.concatenate([np.arange(n), np.full(n_total - n, n - 1)])
    return _batch.take(tree, index)


def status(res: SimulationResult) -> np.ndarray:
    """Per-member outcome: ``"ok"`` or the reason (diffrax message or non-finite output)."""
    codes = result_codes(res.result)
    names = result_names()
    finite = np.all(np.isfinite(np.asarray(res.tension_b)).reshape(codes.shape[0], -1), axis=1)
    out = []
    for code, fin in zip(codes, finite):
        if code != SUCCESS_CODE:
            out.append(names.get(int(code), f"diffrax result {int(code)}"))
        elif not fin:
            out.append("non-finite output")
        else:
            out.append(STATUS_OK)
    return np.asarray(out, dtype=object)


def simulate_ensemble(
    scenes,
    duration=None,
    *,
    init=None,
    devices: Sequence | str | None = "all",
    members_per_call: int | None = None,
    **settings,
) -> SimulationResult:
    """Integrate many scenes of one structure at once.

    Args:
        scenes: a sequence of :class:`moorjax.Scene` (stacked here, with a clear
            error naming the first field whose structure differs), or an already
            stacked scene (every array leaf with a leading member axis, e.g. from
            :func:`moorjax.ensemble.stack`).
        duration, settings: as :func:`moorjax.dynamics.simulate` (``solver``,
            ``rtol``, ``atol``, ``atol_velocity``, ``dt``, ``dt_out``, ``ts``,
            ``save_nodes``, ...; ``throw`` and ``progress`` are not available).
        init: stacked tuple of :class:`LineState` and body states (default:
            each member's static equilibrium at ``t0``, bodies included, vmapped
            (:func:`equilibrium`); a member whose statics fails is warned about
            and reported failed, the others run).
        devices: ``"all"`` (default) shards members over all local devices when
            there are several (at most one device per member); a list of
            devices; or ``None`` for the default device only. On CPU see
            :func:`moorjax.ensemble.use_cpu_cores`.
        members_per_call: members integrated per compiled call (default
            :data:`PER_DEVICE` per device; rounded up to a multiple of the
            devices). More members run as several calls of the same program,
            the last padded: too large a batch costs more per member, too small
            one more per call (case A, N = 20, 20 s, 1000 members on 2 CPU
            devices: 35.9 / 27.6 / 38.2 s in calls of 25 / 50 / 100 members per
            device). The statics run for all members at once.

    Returns:
        a :class:`SimulationResult` with a leading member axis on every array
        (``result`` per member; see :func:`status`).
    """
    for bad in ("throw", "progress"):
        if bad in settings:
            raise ValueError(f"simulate_ensemble does not take {bad!r}; inspect status(result)")
    if members_per_call is not None and int(members_per_call) < 1:
        raise ValueError(f"members_per_call = {members_per_call} must be >= 1")
    if isinstance(scenes, (list, tuple)):
        _check_members(scenes, settings.get("t0", 0.0))
        first = scenes[0]
        scenes = _batch.stack(scenes, name="scene")
    else:
        first = _batch.member(scenes, 0)
    n = _batch.size(scenes)
    p = plan(duration, scene=first, **settings)
    if devices == "all":
        devices = jax.local_devices()
    # no more devices than members: a device's share synchronises with the others'
    # at every step of the loops (measured, case A with one member: 8.2 ms per
    # simulated second on one device, 27.6 padded to two)
    devices = list(devices)[:n] if devices else []
    if len(devices) > 1 and _pool_may_starve(first, p, len(devices)):
        warnings.warn(
            f"this ensemble may call batched LAPACK kernels (Hermite lines, bodies, points, bending or "
            f"an implicit solver other than ROS34PW2) and XLA:CPU's task pool has no more threads than "
            f"its {len(devices)} devices, with which jaxlib 0.10 can hang: it runs on one device. "
            "Call moorjax.ensemble.use_cpu_cores() before JAX starts (or set PJRT_NPROC above the "
            "device count) to use them all", stacklevel=2)
        devices = devices[:1]
    n_dev = max(len(devices), 1)
    # members per integration call: a multiple of the devices, the last call padded
    # with copies of the last member (one compiled program for every call)
    per_call = min(n, int(members_per_call) if members_per_call else PER_DEVICE * n_dev)
    per_call = -(-per_call // n_dev) * n_dev
    calls = -(-n // per_call)
    n_run = calls * per_call
    spec = None
    if len(devices) > 1:
        spec = NamedSharding(Mesh(np.asarray(devices), ("member",)), PartitionSpec("member"))
    scenes = _pad(scenes, n_run)

    def placed(tree):
        return tree if spec is None else _shard(tree, spec)

    def block(tree, k):
        return tree if calls == 1 else _batch.take(tree, np.arange(k * per_call, (k + 1) * per_call))

    blocks = [placed(block(scenes, k)) for k in range(calls)]  # each placed once
    if init is None:
        # the statics compile and run while the integration compiles
        layout = jax.tree_util.tree_map(
            lambda x: jax.ShapeDtypeStruct((per_call,) + x.shape, x.dtype, sharding=spec),
            start_layout(first))
        _batched_integrate.compile_ahead(blocks[0], layout, p, devices=n_dev)
        init, ok, off = _equilibrium(blocks[0] if calls == 1 else placed(scenes), p.t0)
        warn_unresolved(scenes, off, n)
        failed = np.flatnonzero(~np.all(np.asarray(ok), axis=1))
        failed = failed[failed < n]  # not the repeated last member's copies
        if failed.size:
            # such a member must not stop the others: it starts from NaN, so it
            # stops at its first step and its status says it failed
            warnings.warn(
                f"ensemble members {failed.tolist()}: static equilibrium did not converge "
                "(check their parameters and geometry); they are reported as failed"
            )
            bad = jnp.zeros(n_run, dtype=bool).at[failed].set(True)
            init = jax.tree_util.tree_map(
                lambda x: jnp.where(bad.reshape((n_run,) + (1,) * (x.ndim - 1)), jnp.nan, x), init
            )
    y0 = _pad(pack(init), n_run)
    if calls > 1 and spec is not None:  # blocks are cut on one device, then sharded
        y0 = jax.device_put(y0, devices[0])
    parts = [_batched_integrate(b, placed(block(y0, k)), p, devices=n_dev) for k, b in enumerate(blocks)]
    res = parts[0] if calls == 1 else jax.tree_util.tree_map(_joined, *parts)
    return _batch.first(res, n, n_run)


def _joined(*parts):
    """The calls' outputs along the member axis (equal non-array fields kept)."""
    first = parts[0]
    if isinstance(first, jax.Array) and first.ndim:
        return jnp.concatenate([jax.device_put(x, jax.devices()[0]) for x in parts])
    return first
