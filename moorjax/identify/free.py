"""Free parameters of a fit and their reparametrisation.

The optimiser works on unconstrained numbers u (one per free parameter), mapped
to physical values p by a fixed, smooth, monotone transform chosen from the
parameter's bounds:

- ``lower < p < upper``: ``p = lower + (upper − lower)·sigmoid(u)``;
- ``p > lower`` (positive and non-negative registry parameters: lower = 0):
  ``p = lower + s·exp(u)``, with s = start − lower, so u = 0 at the start and a
  unit step in u is a factor e on p − lower (all parameters are equally scaled,
  whatever their units);
- ``p < upper``: ``p = upper − s·exp(u)``;
- signed, unbounded (end positions, current): ``p = start + s·u``, s = max(|start|, 1).

A bound is never reached, so the fit cannot leave the admissible set (e.g. a
negative drag coefficient).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.parameters import PARAMETERS, check_name, get_parameter, split_name


@dataclass(frozen=True)
class Free:
    """A parameter left free in a fit.

    Args:
        name: a name of :mod:`moorjax.model.parameters` (``Cd_normal``, ``alpha``,
            ``L2.Cd``, ``current_x``, ...).
        start: initial value (SI units); default: its value in the first
            experiment's scene.
        lower, upper: bounds (open); default: 0 below for positive and
            non-negative parameters, none for signed ones.
    """

    name: str
    start: float | None = None
    lower: float | None = None
    upper: float | None = None


def as_free(spec) -> tuple[Free, ...]:
    """Free parameters from names, :class:`Free` objects or ``{name: start}``."""
    if isinstance(spec, (str, Free)):
        spec = [spec]
    if isinstance(spec, dict):
        spec = [v if isinstance(v, Free) else Free(k, v) for k, v in spec.items()]
    out = []
    for s in spec:
        out.append(s if isinstance(s, Free) else Free(str(s).strip()))
    if not out:
        raise ValueError("no free parameters: name at least one (e.g. Cd_normal)")
    names = [f.name for f in out]
    for f in out:
        check_name(f.name)
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ValueError(f"free parameter(s) {', '.join(dup)} given more than once")
    return tuple(out)


@dataclass(frozen=True)
class Transform:
    """Map between unconstrained u (optimiser) and physical values p of the free parameters."""

    names: tuple[str, ...]
    kinds: tuple[str, ...]  # "interval", "lower", "upper", "affine"
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    scale: tuple[float, ...]
    offset: tuple[float, ...]

    def to_physical(self, u):
        u = np.asarray(u, dtype=float)
        return np.array([_forward(k, lo, hi, s, o, x) for k, lo, hi, s, o, x in
                         zip(self.kinds, self.lower, self.upper, self.scale, self.offset, u)])

    def derivative(self, u):
        """dp/du per parameter."""
        u = np.asarray(u, dtype=float)
        return np.array([_slope(k, lo, hi, s, x) for k, lo, hi, s, x in
                         zip(self.kinds, self.lower, self.upper, self.scale, u)])


def _sigmoid(x):
    return 1.0 / (1.0 + math.exp(-x)) if x >= 0 else math.exp(x) / (1.0 + math.exp(x))


def _forward(kind, lo, hi, s, o, u):
    if kind == "interval":
        return lo + (hi - lo) * _sigmoid(u)
    if kind == "lower":
        return lo + s * math.exp(min(u, 700.0))
    if kind == "upper":
        return hi - s * math.exp(min(u, 700.0))
    return o + s * u


def _slope(kind, lo, hi, s, u):
    if kind == "interval":
        q = _sigmoid(u)
        return (hi - lo) * q * (1.0 - q)
    if kind in ("lower", "upper"):
        return (1.0 if kind == "lower" else -1.0) * s * math.exp(min(u, 700.0))
    return s


def make_transform(free: tuple[Free, ...], scene) -> tuple[Transform, np.ndarray]:
    """The transform and the starting u (zeros unless bounded on both sides).

    Raises ``ValueError`` if a start lies outside its bounds, or if a parameter the
    scene does not contain is named (the message says which term is missing).
    """
    kinds, lows, highs, scales, offsets, u0 = [], [], [], [], [], []
    for f in free:
        check_name(f.name, scene)
        base = PARAMETERS[split_name(f.name)[1]]
        current = float(get_parameter(scene, f.name))  # raises if the term is absent
        start = current if f.start is None else float(f.start)
        lo = f.lower if f.lower is not None else (None if base.signed else 0.0)
        hi = f.upper
        unit = f" {base.unit}" if base.unit != "-" else ""
        if not np.isfinite(start):
            raise ValueError(f"start value of {f.name} = {start}{unit} is not finite")
        if lo is not None and hi is not None and not lo < hi:
            raise ValueError(f"{f.name}: lower bound {lo}{unit} must be below upper bound {hi}{unit}")
        if (lo is not None and not start > lo) or (hi is not None and not start < hi):
            where = f"({'-inf' if lo is None else lo}, {'inf' if hi is None else hi})"
            hint = (" (a parameter that must stay >= 0 cannot start at 0: give a positive "
                    "start value)") if lo == 0.0 and start == 0.0 else ""
            raise ValueError(
                f"start value of {f.name} = {start}{unit} is not inside its bounds {where}{unit}{hint}"
            )
        if lo is not None and hi is not None:
            q = (start - lo) / (hi - lo)
            kinds.append("interval")
            u0.append(math.log(q / (1.0 - q)))
            scales.append(hi - lo)
        elif lo is not None:
            kinds.append("lower")
            u0.append(0.0)
            scales.append(start - lo)
        elif hi is not None:
            kinds.append("upper")
            u0.append(0.0)
            scales.append(hi - start)
        else:
            kinds.append("affine")
            u0.append(0.0)
            scales.append(max(abs(start), 1.0))
        lows.append(-math.inf if lo is None else float(lo))
        highs.append(math.inf if hi is None else float(hi))
        offsets.append(start)
    t = Transform(tuple(f.name for f in free), tuple(kinds), tuple(lows), tuple(highs),
                  tuple(scales), tuple(offsets))
    return t, np.asarray(u0, dtype=float)
