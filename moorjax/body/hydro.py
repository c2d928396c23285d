"""Frequency-domain hydrodynamics of a floating body: coefficients, file format,
interpolation. The radiation memory (retardation function, state-space fit) is
in :mod:`moorjax.body.radiation`; its names are re-exported here.

Conventions (6 DOF about the body's reference point, its centre of gravity):
surge, sway, heave [m], roll, pitch, yaw [rad]; z up, z = 0 at the still water
level; wave heading β is the direction of *propagation*, measured from +x
towards +y.

Complex wave amplitudes use the time factor e^{+iωt}: a regular wave whose
incident elevation at the global origin (x, y) = (0, 0) is
η(t) = a·cos(ωt + φ) = Re[a e^{i(ωt+φ)}] excites the force
F(t) = Re[X(ω, β) a e^{i(ωt+φ)}] = a|X| cos(ωt + φ + arg X).
Capytaine (and Nemoh) write amplitudes with e^{−iωt}; their excitation force is
the complex conjugate of ``X`` here (``benchmarks/make_box_hydro.py``
conjugates it).

Everything here but the interpolation helpers is preprocessing in NumPy (it
runs once, outside ``jit``).
"""

from __future__ import annotations

import json

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

# the radiation memory, re-exported from its own module
from .radiation import RadiationFitReport as RadiationFitReport
from .radiation import RadiationStateSpace as RadiationStateSpace
from .radiation import fit_radiation as fit_radiation
from .radiation import retardation_function as retardation_function

#: file format tag written by :func:`save_hydro`
FORMAT = "moorjax-hydro-1"
_FIELDS = ("omega", "added_mass", "damping", "added_mass_inf", "headings", "excitation_re",
           "excitation_im", "drift", "hydrostatic", "rho", "g", "volume", "reference_point")
_UNITS = {
    "omega": "rad/s", "added_mass": "kg, kg·m, kg·m²", "damping": "N·s/m, N·s, N·m·s/rad",
    "added_mass_inf": "kg, kg·m, kg·m²", "headings": "rad", "excitation_re": "N/m, N·m/m",
    "excitation_im": "N/m, N·m/m", "drift": "N/m², N·m/m²", "hydrostatic": "N/m, N, N·m/rad",
    "rho": "kg/m³", "g": "m/s²", "volume": "m³", "reference_point": "m",
}


def _concrete(x):
    return None if isinstance(x, jax.core.Tracer) else np.asarray(x, dtype=float)


class HydroCoefficients(eqx.Module):
    """Linear hydrodynamic database of one rigid body (all about ``reference_point``).

    Args (keyword only):
        omega: (K,) wave frequencies [rad/s], positive and strictly increasing.
        added_mass: (K, 6, 6) added mass A(ω) [kg, kg·m, kg·m²].
        damping: (K, 6, 6) radiation damping B(ω) [N·s/m, N·s, N·m·s/rad].
        added_mass_inf: (6, 6) infinite-frequency added mass A∞.
        headings: (H,) wave headings β [rad], strictly increasing (direction of
            propagation from +x towards +y).
        excitation_re, excitation_im: (H, K, 6) first-order excitation force per
            unit wave amplitude X(ω, β) [N/m, N·m/m] (diffraction + Froude–Krylov,
            e^{+iωt} convention, phase relative to the incident elevation at the
            global origin; see the module docstring).
        drift: (H, K, 6) mean drift force per unit amplitude squared D(ω, β)
            [N/m², N·m/m²] (the diagonal of the difference-frequency QTF; used by
            Newman's approximation).
        hydrostatic: (6, 6) hydrostatic restoring matrix C [N/m, N, N·m/rad],
            including the weight's contribution for the body's centre of gravity at
            ``reference_point``; C[2, 2] must be positive.
        rho: water density [kg/m³]; g: gravity [m/s²]; volume: displaced volume [m³].
        reference_point: (3,) point the moments refer to [m] (global frame at rest).
    """

    omega: Array
    added_mass: Array
    damping: Array
    added_mass_inf: Array
    headings: Array
    excitation_re: Array
    excitation_im: Array
    drift: Array
    hydrostatic: Array
    rho: Array
    g: Array
    volume: Array
    reference_point: Array

    def __init__(self, *, omega, added_mass, damping, added_mass_inf, headings, excitation_re,
                 excitation_im, drift, hydrostatic, rho=1025.0, g=9.81, volume, reference_point):
        values = dict(omega=omega, added_mass=added_mass, damping=damping,
                      added_mass_inf=added_mass_inf, headings=headings,
                      excitation_re=excitation_re, excitation_im=excitation_im, drift=drift,
                      hydrostatic=hydrostatic, rho=rho, g=g, volume=volume,
                      reference_point=reference_point)
        _validate(values)
        for name in _FIELDS:
            setattr(self, name, jnp.asarray(values[name], dtype=float))

    @property
    def n_frequencies(self) -> int:
        return int(self.omega.shape[0])

    @property
    def n_headings(self) -> int:
        return int(self.headings.shape[0])

    @property
    def excitation(self) -> Array:
        """(H, K, 6) complex excitation force per unit amplitude [N/m, N·m/m]."""
        return self.excitation_re + 1j * self.excitation_im


def _validate(v: dict) -> None:
    arrays = {}
    for name, value in v.items():
        a = _concrete(value)
        if a is None:
            return  # traced: nothing to check
        arrays[name] = a
    omega = arrays["omega"]
    if omega.ndim != 1 or omega.shape[0] < 2:
        raise ValueError(f"omega has shape {omega.shape}, expected (K,) with K >= 2 frequencies [rad/s]")
    k = omega.shape[0]
    if arrays["headings"].ndim != 1 or arrays["headings"].shape[0] < 1:
        raise ValueError(f"headings has shape {arrays['headings'].shape}, expected (H,) [rad] with H >= 1")
    h = arrays["headings"].shape[0]
    expected = {
        "added_mass": ((k, 6, 6), f"(K, 6, 6) with K = len(omega) = {k}"),
        "damping": ((k, 6, 6), f"(K, 6, 6) with K = len(omega) = {k}"),
        "added_mass_inf": ((6, 6), "(6, 6)"),
        "excitation_re": ((h, k, 6), f"(H, K, 6) with H = len(headings) = {h}, K = len(omega) = {k}"),
        "excitation_im": ((h, k, 6), f"(H, K, 6) with H = len(headings) = {h}, K = len(omega) = {k}"),
        "drift": ((h, k, 6), f"(H, K, 6) with H = len(headings) = {h}, K = len(omega) = {k}"),
        "hydrostatic": ((6, 6), "(6, 6)"),
        "rho": ((), "() (a scalar)"),
        "g": ((), "() (a scalar)"),
        "volume": ((), "() (a scalar)"),
        "reference_point": ((3,), "(3,)"),
    }
    for name, (shape, text) in expected.items():
        if arrays[name].shape != shape:
            raise ValueError(f"{name} has shape {arrays[name].shape}, expected {text}")
    for name, a in arrays.items():
        if not np.all(np.isfinite(a)):
            bad = np.argwhere(~np.isfinite(a))[0]
            raise ValueError(f"{name} [{_UNITS[name]}] has a non-finite value at index "
                             f"{tuple(int(i) for i in bad)}; all entries must be finite")
    if not np.all(omega > 0):
        raise ValueError(f"omega must be positive [rad/s]; smallest is {omega.min():g} "
                         "(give ω = ∞ separately as added_mass_inf)")
    if not np.all(np.diff(omega) > 0):
        i = int(np.argmax(np.diff(omega) <= 0))
        raise ValueError(f"omega must be strictly increasing [rad/s]; omega[{i}] = {omega[i]:g} "
                         f">= omega[{i + 1}] = {omega[i + 1]:g}")
    if not np.all(np.diff(arrays["headings"]) > 0):
        raise ValueError("headings must be strictly increasing [rad]")
    for name in ("rho", "g", "volume"):
        if not arrays[name] > 0:
            raise ValueError(f"{name} = {arrays[name]:g} {_UNITS[name]} must be > 0")
    c33 = arrays["hydrostatic"][2, 2]
    if not c33 > 0:
        raise ValueError(f"body's hydrostatic stiffness in heave must be positive: "
                         f"hydrostatic[2, 2] = {c33:g} N/m (a floating body needs a waterplane)")


# -- file format -------------------------------------------------------------

def save_hydro(path, coeffs: HydroCoefficients, metadata: dict | None = None) -> None:
    """Write ``coeffs`` to a compressed ``.npz`` (SI units, fields of
    :class:`HydroCoefficients`); ``metadata`` (JSON-serialisable) is stored with it."""
    arrays = {name: np.asarray(getattr(coeffs, name)) for name in _FIELDS}
    arrays["format"] = np.array(FORMAT)
    arrays["metadata"] = np.array(json.dumps(metadata or {}))
    with open(path, "wb") as f:
        np.savez_compressed(f, **arrays)


def load_hydro(path) -> HydroCoefficients:
    """Read a file written by :func:`save_hydro` (validated as on construction)."""
    with np.load(path, allow_pickle=False) as data:
        missing = [n for n in _FIELDS if n not in data.files]
        if missing:
            raise ValueError(f"hydrodynamic file {path} lacks {', '.join(missing)} "
                             f"(expected the fields {', '.join(_FIELDS)})")
        values = {n: np.array(data[n]) for n in _FIELDS}
    try:
        return HydroCoefficients(**values)
    except ValueError as err:
        raise ValueError(f"hydrodynamic file {path}: {err}") from None


def hydro_metadata(path) -> dict:
    """The metadata dictionary stored by :func:`save_hydro` (empty if none)."""
    with np.load(path, allow_pickle=False) as data:
        return json.loads(str(data["metadata"])) if "metadata" in data.files else {}


# -- interpolation -----------------------------------------------------------

def _heading_weights(coeffs, heading):
    """Index and weight for linear interpolation in heading (wrapped to the table)."""
    hs = coeffs.headings
    beta = hs[0] + jnp.mod(jnp.asarray(heading, dtype=float) - hs[0], 2 * jnp.pi)
    b = _concrete(beta)
    if b is not None:
        lo, hi = float(hs[0]), float(hs[-1])
        if not (lo - 1e-9 <= b <= hi + 1e-9):
            raise ValueError(
                f"wave heading {np.degrees(float(_concrete(heading))):.6g}° is outside the "
                f"hydrodynamic table's headings [{np.degrees(lo):.6g}°, {np.degrees(hi):.6g}°]; "
                "give coefficients that cover it (no symmetry of the body is assumed)")
    if hs.shape[0] == 1:
        return 0, 0, jnp.asarray(0.0)
    i = jnp.clip(jnp.searchsorted(hs, beta, side="right") - 1, 0, hs.shape[0] - 2)
    w = jnp.clip((beta - hs[i]) / (hs[i + 1] - hs[i]), 0.0, 1.0)
    return i, i + 1, w


def _check_omega(coeffs, omega):
    w = _concrete(omega)
    if w is not None:
        lo, hi = float(coeffs.omega[0]), float(coeffs.omega[-1])
        if np.any(w < lo * (1 - 1e-12)) or np.any(w > hi * (1 + 1e-12)):
            raise ValueError(
                f"wave frequencies {w.min():.6g}–{w.max():.6g} rad/s leave the hydrodynamic "
                f"table's range [{lo:.6g}, {hi:.6g}] rad/s; restrict the wave components to it")


def _interp_table(coeffs, table, omega, heading):
    i0, i1, w = _heading_weights(coeffs, heading)
    tab = (1.0 - w) * table[i0] + w * table[i1]  # (K, 6)
    _check_omega(coeffs, omega)
    om = jnp.asarray(omega, dtype=float)
    cols = jax.vmap(lambda c: jnp.interp(om.reshape(-1), coeffs.omega, c), in_axes=1, out_axes=-1)(tab)
    return cols.reshape(om.shape + (6,))


def excitation_at(coeffs: HydroCoefficients, omega, heading) -> Array:
    """Complex excitation force per unit amplitude (…, 6) [N/m, N·m/m] at frequencies
    ``omega`` (…) [rad/s] and heading [rad]: linear in heading, then linear in ω
    (real and imaginary parts separately).

    Frequencies outside the table, or a heading outside it (after wrapping into
    [headings[0], headings[0] + 2π)), raise ``ValueError``; under tracing they are
    not checked and the values are held constant beyond the ends.
    """
    re = _interp_table(coeffs, coeffs.excitation_re, omega, heading)
    im = _interp_table(coeffs, coeffs.excitation_im, omega, heading)
    return re + 1j * im


def drift_at(coeffs: HydroCoefficients, omega, heading) -> Array:
    """Mean drift force per unit amplitude squared (…, 6) [N/m², N·m/m²], interpolated
    as :func:`excitation_at`."""
    return _interp_table(coeffs, coeffs.drift, omega, heading)

