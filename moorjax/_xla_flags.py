"""XLA:CPU settings moorjax asks for: flags before JAX starts its backend, and
per-program compiler options (:data:`PRESETS`, end of this module).

A line's time step is a loop of a few hundred small operations (3×3 block
products, band solves, Morison loads on ten to a hundred nodes); on a CPU, XLA
runs each of them as its own task, and its default *concurrency-optimised*
schedule orders them breadth first so that independent ones may run side by
side. For kernels this small the side-by-side execution never pays: the
runtime's bookkeeping costs more than the work. With the memory-minimising
depth-first schedule instead (``--xla_cpu_enable_concurrency_optimized_scheduler=false``)
the same programs, with the same step counts and the same numbers, run
10–30 % faster per step (``benchmarks/README.md``, session 29).

XLA reads ``XLA_FLAGS`` once, when JAX first computes something (not at
``import jax``), so :func:`prefer_sequential_schedule` adds the flag at
``import moorjax`` only while no backend has started; it changes nothing

- when the user's ``XLA_FLAGS`` already set that flag (either value),
- when JAX has already computed something (its flags are fixed by then),
- with ``MOORJAX_XLA_TUNING=0`` (also ``false``/``off``/``no``) in the environment.

The flag only affects XLA:CPU; GPU and TPU backends ignore it. It is part of
JAX's persistent compilation-cache key, so executables compiled with and without
it are kept apart.

The schedule only orders the tasks: XLA:CPU's executor still hands a task to
another thread of its pool whenever the program's dependency graph allows two
at once (it keeps to one thread only where every buffer is under 512 bytes,
an option it reads from no flag). A line's W in mass form (3×3 blocks for the
masses and the two force derivatives instead of 6×6 blocks,
:mod:`moorjax.linalg.mass_form`) gives the graph such branches, and a step of
case A, N = 40, went from 73 to 100 µs on two threads. So
:func:`prefer_one_intra_op_thread` sets ``PJRT_NPROC=1`` (read by XLA when the
CPU client starts: the size of its task pools) under the same conditions as
the flag, and only where no GPU or TPU plugin is installed. Ensembles keep
their parallelism: each CPU device (``--cpu-devices``) runs on its own thread
(200 members, two devices: 5.49 s with the pools at two threads, 5.42 s at
one; ``benchmarks/README.md``, session 32).
"""

from __future__ import annotations

import os
import re

from ._cache import _switched_on

#: the XLA:CPU flag and the value moorjax prefers
FLAG = "xla_cpu_enable_concurrency_optimized_scheduler"
VALUE = "false"


def wanted() -> bool:
    """Whether moorjax may add its XLA flags (``MOORJAX_XLA_TUNING``, default on)."""
    return _switched_on("MOORJAX_XLA_TUNING")


def _backend_started() -> bool:
    try:
        from jax._src import xla_bridge
    except ImportError:  # pragma: no cover - a future JAX layout: assume started, touch nothing
        return True
    started = getattr(xla_bridge, "backends_are_initialized", None)
    return True if started is None else bool(started())


def set_flag(name: str, value, *, keep_user: bool) -> bool:
    """Put ``--name=value`` into ``XLA_FLAGS`` while no JAX backend has started
    (XLA reads the variable when the first one starts); the user's other flags
    are kept.

    Args:
        name: the XLA flag, without the dashes.
        value: its value (written with ``str``).
        keep_user: where ``XLA_FLAGS`` already sets the flag, keep that value
            (True) or replace it (False).

    Returns:
        True when ``XLA_FLAGS`` was changed by this call.
    """
    if _backend_started():
        return False
    flags = os.environ.get("XLA_FLAGS", "")
    given = re.compile(rf"--{re.escape(name)}(=\S*)?(?=\s|$)")
    if given.search(flags):
        if keep_user:
            return False
        flags = given.sub("", flags)
    os.environ["XLA_FLAGS"] = f"{flags.strip()} --{name}={value}".strip()
    return True


def prefer_sequential_schedule() -> bool:
    """Add ``--xla_cpu_enable_concurrency_optimized_scheduler=false`` to
    ``XLA_FLAGS`` where that is still possible and wanted (module docstring).

    Returns:
        True when the flag was added by this call.
    """
    return wanted() and set_flag(FLAG, VALUE, keep_user=True)


#: the environment variable XLA:CPU sizes its task pools by, and moorjax's value
NPROC = "PJRT_NPROC"


def _accelerator_plugin() -> bool:
    """Whether a JAX GPU or TPU plugin is installed (its client may size its
    own pools by the same variable: leave those alone)."""
    import importlib.util

    names = ("jax_cuda12_plugin", "jax_cuda13_plugin", "jax_rocm60_plugin", "jax_rocm7_plugin",
             "libtpu", "jax_tpu_plugin")
    return any(importlib.util.find_spec(n) is not None for n in names)


def prefer_one_intra_op_thread() -> bool:
    """Set ``PJRT_NPROC=1`` where that is still possible and wanted (module
    docstring): not once a JAX backend has started, not over the user's value,
    not with ``MOORJAX_XLA_TUNING=0``, not with ``JAX_PLATFORMS`` naming
    anything but ``cpu`` or with an accelerator plugin installed.

    Returns:
        True when the variable was set by this call.
    """
    if not wanted() or NPROC in os.environ or _backend_started():
        return False
    platforms = os.environ.get("JAX_PLATFORMS", "").strip().lower()
    if platforms and platforms != "cpu":
        return False
    if not platforms and _accelerator_plugin():
        return False
    os.environ[NPROC] = "1"
    _ours[NPROC] = "1"
    return True


_ours = {}  # the environment values moorjax itself set (never a user's)


def pool_for_devices(n_devices: int) -> bool:
    """Give XLA:CPU's task pool ``n_devices + 1`` threads when ``n_devices`` CPU
    devices run at once (an ensemble's, :func:`moorjax.ensemble.use_cpu_cores`),
    where moorjax set ``PJRT_NPROC`` itself (:func:`prefer_one_intra_op_thread`)
    and no JAX backend has started.

    Each device runs its programs on that pool, and jaxlib 0.10's batched LAPACK
    kernels (Hermite lines, bodies) block a pool thread until chunks they queue
    on the same pool are done. One program orders its batched calls
    (:mod:`moorjax.linalg.ordering`), but the devices' programs run side by side:
    with as many threads as devices, every thread can wait in such a kernel and
    the process hangs (seen: ``moorjax ensemble --element hermite`` on two CPU
    devices, both pool threads in ``jax::ParallelBatchMap``). One thread more
    than devices always leaves one to run the chunks.

    Returns:
        True when ``PJRT_NPROC`` was changed by this call.
    """
    if (n_devices < 2 or _ours.get(NPROC) is None or os.environ.get(NPROC) != _ours[NPROC]
            or _backend_started()):
        return False
    os.environ[NPROC] = _ours[NPROC] = str(int(n_devices) + 1)
    return True


#: Per-program XLA:CPU options (``jax.jit``'s ``compiler_options``) by what a
#: program is compiled for. XLA:CPU's MLIR fusion emitters cost compile time and
#: buy nothing measurable in moorjax's programs of small kernels: without them
#: the integration of ``oc3_catenary`` compiles in 5.0 instead of 7.1 s (N = 20)
#: and case A's (N = 40) in 5.3 instead of 8.1 s, at the same cost per step
#: (ROS34PW2 and Kvaerno5 on cases A and B). A static solve runs once per
#: structure and process, so it is also compiled without XLA's optimisation
#: passes: 5.7 -> 2.4 s for a line's statics, 1 -> 2.7 ms to run. Measured in
#: ``benchmarks/README.md``, session 34. Options change rounding, not results
#: beyond it. Per program, not in ``XLA_FLAGS``: the user's own programs keep
#: XLA's defaults, and an option a jaxlib does not know fails the compile with
#: an error (:func:`reject_options`) where an unknown flag would end the process.
#:
#: ``"members"`` is ``"runs"`` for a program vmapped over an ensemble's members:
#: there XLA:CPU (jaxlib 0.10) hands the batched reductions and small products
#: ((members, nodes, 3) sums over the last axis, the band's block products) to
#: YNNPACK library calls, 22 ``__ynn_fusion`` thunks per step of ``oc3_catenary``
#: at N = 20, which cost more than XLA's own loops at these sizes; an empty
#: ``xla_cpu_experimental_ynn_fusion_type`` keeps them in XLA. 50 members on one
#: device, 20 s: 1.12 -> 0.92 s (27.7 -> 22.9 µs per member and step); single
#: runs have no such fusions and keep ``"runs"`` (``benchmarks/README.md``,
#: session 41).
PRESETS = {
    "runs": (("xla_cpu_use_fusion_emitters", False),),
    "members": (("xla_cpu_use_fusion_emitters", False), ("xla_cpu_experimental_ynn_fusion_type", "")),
    "once": (("xla_cpu_use_fusion_emitters", False), ("xla_backend_optimization_level", 0)),
}

_rejected = []  # the error of a jaxlib that did not take the options, once seen


def compiler_options(preset: str) -> dict | None:
    """The ``compiler_options`` of a program compiled for ``preset`` (a key of
    :data:`PRESETS`), or ``None`` (XLA's defaults) with ``MOORJAX_XLA_TUNING=0``,
    or ``MOORJAX_XLA_OPTIONS=0`` (these options alone, for an A/B), on a backend
    other than the CPU (these are XLA:CPU's options) or once a jaxlib has
    refused them. Starts JAX's backend: call it when compiling."""
    import jax

    if (_rejected or not wanted() or not _switched_on("MOORJAX_XLA_OPTIONS")
            or jax.default_backend() != "cpu"):
        return None
    return dict(PRESETS[preset])


def reject_options(exc: Exception) -> bool:
    """Whether ``exc`` is XLA refusing an option of :data:`PRESETS` (an older or
    newer jaxlib): if so, no program gets options from now on, and the caller
    compiles again without them."""
    if _rejected or "No such compile option" not in str(exc):
        return False
    _rejected.append(str(exc))
    return True
