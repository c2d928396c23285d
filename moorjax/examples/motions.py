"""Write the bundled examples' fairlead motions (``<name>_motion.csv``).

Each deck describes a sine surge x(t) = x0 + A·sin(2πt/T) of its coupled point;
the file samples it every 0.25 s over 600 s with the exact velocity, so the
C¹ Hermite spline that reads it is within ~1e-5 m of the sine. Regenerate with::

    python -m moorjax.examples.motions
"""

from __future__ import annotations

import numpy as np

from . import _EXAMPLES, Example

DT = 0.25  # [s]
DURATION = 600.0  # [s]


def sample(ex: Example, t) -> np.ndarray:
    """(len(t), 7) rows t, P_x, P_y, P_z, P_vx, P_vy, P_vz [s, m, m/s] of the surge."""
    t = np.asarray(t, dtype=float)
    w = 2.0 * np.pi / ex.period
    zero = np.zeros_like(t)
    return np.column_stack([
        t, ex.x0 + ex.amplitude * np.sin(w * t), zero + ex.y0, zero + ex.z0,
        ex.amplitude * w * np.cos(w * t), zero, zero,
    ])


def motion_text(ex: Example) -> str:
    t = np.round(np.arange(0.0, DURATION + DT / 2, DT), 6)
    rows = sample(ex, t)
    p = f"P{ex.point}"
    lines = [
        f"# {ex.name}: fairlead surge x = {ex.x0:g} + {ex.amplitude:g}*sin(2*pi*t/{ex.period:g}) "
        "[m]; written by python -m moorjax.examples.motions",
        f"t,{p}_x,{p}_y,{p}_z,{p}_vx,{p}_vy,{p}_vz",
    ]
    lines += [",".join(f"{v:.10g}" for v in r) for r in rows]
    return "\n".join(lines) + "\n"


def main() -> None:  # pragma: no cover - a maintenance script
    for ex in _EXAMPLES:
        with open(ex.motion, "w") as f:
            f.write(motion_text(ex))
        print(ex.motion)


if __name__ == "__main__":  # pragma: no cover
    main()
