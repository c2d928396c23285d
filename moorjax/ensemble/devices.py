"""The host's cores as JAX devices, so that an ensemble runs on all of them.

On CPU, JAX shows one device however many cores there are, and XLA:CPU runs a
vmapped ensemble's small per-step kernels on one core. Split into several CPU
devices, :func:`moorjax.ensemble.simulate_ensemble` shards the members over them
(``devices="all"``) and each device's share runs on its own core. Measured on a
2-core machine (case A, N = 40, Heun at 3.125 ms, 100 members, 10 s simulated):
5.26 ms per simulated second and member on one device, 2.42 on two, identical
results (``benchmarks/README.md``, session 23).

JAX fixes its devices when it first computes something, so :func:`use_cpu_cores`
must run before that: right after the imports. ``moorjax ensemble`` calls it
(``--cpu-devices``). It changes nothing where the user has already chosen a
count (``jax_num_cpu_devices`` or ``XLA_FLAGS=--xla_force_host_platform_device_count``).
"""

from __future__ import annotations

import os
import re

import jax

_FLAG = "xla_force_host_platform_device_count"


def available_cores() -> int:
    """Cores this process may run on (its CPU affinity where the OS says, else all)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # not Linux
        return os.cpu_count() or 1


def use_cpu_cores(n: int | None = None, lapack: bool = True) -> int:
    """Ask JAX for ``n`` CPU devices (default: one per available core).

    Args:
        n: number of CPU devices, ≥ 1; ``None`` for :func:`available_cores`.
        lapack: the ensembles to run may call batched LAPACK kernels (Hermite
            lines, bodies, free points, bending, implicit solvers other than
            ROS34PW2 on linear-element lines): with several devices XLA:CPU's
            task pool then gets one thread more than devices, without which
            jaxlib 0.10 can hang (:func:`moorjax._xla_flags.pool_for_devices`).
            ``False`` keeps the pool at its size, which runs ensembles of
            linear-element lines faster (200 members of ``oc3_catenary``: 4.1
            against 4.7 s); ``moorjax ensemble`` decides from the deck.

    Returns:
        the number of CPU devices JAX will use: ``n``, unless JAX has already
        computed something (its devices are then fixed and their count is
        returned). Without ``n``, a count the user set before
        (``jax_num_cpu_devices``, or ``XLA_FLAGS`` with
        ``--xla_force_host_platform_device_count``) is kept.
    """
    if n is not None and int(n) < 1:
        raise ValueError(f"use_cpu_cores: n = {n} must be >= 1")
    if n is None:
        chosen = _chosen()
        if chosen:
            from .._xla_flags import pool_for_devices

            if lapack:
                pool_for_devices(chosen)
            return chosen
        n = available_cores()
    from .._xla_flags import pool_for_devices

    try:
        jax.config.update("jax_num_cpu_devices", int(n))
    except RuntimeError:  # JAX has computed something: its devices are fixed
        return _current()
    except AttributeError:  # a JAX older than the option: the XLA flag, read when JAX starts
        n = _flagged(int(n))
    if lapack:
        pool_for_devices(int(n))  # batched LAPACK kernels on several devices (see there)
    return int(n)


def _flagged(n: int) -> int:
    from .._xla_flags import set_flag

    return n if set_flag(_FLAG, n, keep_user=False) else _current()


def _chosen() -> int:
    """The CPU device count set before (config or XLA_FLAGS), else 0."""
    chosen = getattr(jax.config, "jax_num_cpu_devices", -1)
    if chosen > 0:
        return chosen
    flag = re.search(rf"--{_FLAG}=(\d+)", os.environ.get("XLA_FLAGS", ""))
    return int(flag.group(1)) if flag else 0


def _current() -> int:
    try:
        return len(jax.devices("cpu"))
    except RuntimeError:  # no CPU backend (e.g. restricted platforms)
        return 0
