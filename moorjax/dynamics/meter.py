"""A progress meter that also counts steps and rejected steps while a run goes.

diffrax calls a progress meter once per step attempt with the fraction of the
time span reached so far (the start of the next step). A rejected step does not
advance it, so counting the calls and the calls that did not advance gives the
attempted and the rejected steps live, without a host round trip per step: the
counts are carried on the device in the meter's state and printed only when the
progress has grown by ``minimum_increase`` (and at the end), as
``"12.00% 1234 56"`` lines on stdout (progress, steps, rejected), which the
command line's progress bar reads (:mod:`moorjax._progress`).

For single runs (the command line); ensembles and gradients use no meter.
"""

from __future__ import annotations

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array


class StepMeterState(eqx.Module):
    shown: Array  # progress at the last printout
    last: Array  # progress at the previous call
    steps: Array  # step attempts so far
    rejected: Array  # attempts that did not advance the time


def _print(progress, steps, rejected):
    print(f"{100 * float(progress):.2f}% {int(steps)} {int(rejected)}", flush=True)


class StepMeter(diffrax.AbstractProgressMeter):
    """Text progress with live step and rejection counts (see the module doc)."""

    minimum_increase: float = 0.01

    def init(self) -> StepMeterState:
        zero = jnp.asarray(0.0)
        jax.debug.callback(_print, zero, 0, 0, ordered=True)
        return StepMeterState(zero, zero, jnp.asarray(0), jnp.asarray(0))

    def step(self, state: StepMeterState, progress) -> StepMeterState:
        progress = jnp.asarray(progress, dtype=state.last.dtype)
        steps = state.steps + 1
        rejected = state.rejected + (progress <= state.last).astype(state.rejected.dtype)
        show = (progress - state.shown >= self.minimum_increase) | (progress >= 1.0)

        def _show(_):
            jax.debug.callback(_print, progress, steps, rejected, ordered=True)
            return progress

        shown = jax.lax.cond(show, _show, lambda _: state.shown, None)
        return StepMeterState(shown, progress, steps, rejected)

    def close(self, state: StepMeterState):
        def _show(_):
            jax.debug.callback(_print, state.last, state.steps, state.rejected, ordered=True)
            return None

        jax.lax.cond(state.last > state.shown, _show, lambda _: None, None)
