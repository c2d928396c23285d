"""Readers for MoorDyn-C v2's wave files (the ``WaveKin`` option), turned into
wave components.

MoorDyn v2 documents the option and its files in ``docs/waterkinematics.rst``
("Wave Kinematics (MoorDyn-C)"); the files sit in the deck's folder under fixed
names, and the semantics below follow its sources ``source/Waves.cpp``,
``source/Waves/WaveGrid.cpp``, ``WaveSpectrum.cpp`` and ``SpectrumKin.cpp``
(FloatingArrayDesign/MoorDyn v2.7.1):

* ``WaveKin = 7`` (summing component waves): ``wave_frequencies.txt``, rows
  ``omega [rad/s]  Re(A)  Im(A)  [beta [rad]]`` (first row at 0 rad/s; any
  order, repeats allowed). MoorDyn sums η = Σ |A| sin(ωt − k(x cos β + y sin β)
  + arg A) and the Airy kinematics at the nodes; moorjax's phase (cosine
  convention) is arg A − π/2, and a 0 rad/s row is a constant level Im(A).
* ``WaveKin = 2`` (wave FFT grid): the same file, rows in increasing ω, all
  one direction per frequency. MoorDyn interpolates A and β linearly to evenly
  spaced frequencies i·Δω (Δω the smallest spacing of the file, up to the last
  frequency) and inverse-FFTs them (scaled so that) η = Σ Re(A e^{i(ωt − k·x)}):
  amplitude |A|, phase arg A; the 0 rad/s bin gives a level Re(A)/2 and the
  last (Nyquist) bin a component Re(A)/2.
* ``WaveKin = 3`` (wave grid): ``wave_elevation.txt``, rows ``t [s]  η [m]``.
  MoorDyn resamples η linearly at i·dtWave up to the last time (dtWave read as
  a 32-bit float, ``stof``), drops the last sample if their number N is odd,
  takes the real FFT X_j, zeroes the bins above 0.5 Hz, and uses the
  components 2X_j/N at ω_j = 2πj/(N·dtWave) (the mean X_0/N as a level),
  travelling along +x.
* Modes 2 and 3 also read ``water_grid.txt``: MoorDyn precomputes the
  kinematics on that (x, y, z, t) grid and interpolates linearly in it; moorjax
  sums the same components at the nodes directly (the differences are MoorDyn's
  interpolation errors, O(Δ²)). The grid is checked to exist and be readable.
* ``WaveKin = 1`` (external kinematics set through MoorDyn's API) has no file:
  the kinematics come at run time (:class:`moorjax.model.ExternalWaves`,
  ``build_scene(..., waves=...)``, ``--wave-kinematics``). 4, 5, 6 (not
  implemented in MoorDyn) are refused.

Components of zero amplitude are dropped (they add nothing). Pure Python +
numpy; no JAX.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import InputError
from .table import moordyn_file_lines, number_rows, row_numbers

__all__ = ["DeckWaves", "WAVE_FILES", "read_deck_waves", "read_wave_frequencies", "read_wave_elevation",
           "read_water_grid"]

#: ``WaveKin`` value -> the files MoorDyn-C reads from the deck's folder.
WAVE_FILES = {2: ("wave_frequencies.txt", "water_grid.txt"), 3: ("wave_elevation.txt", "water_grid.txt"),
              7: ("wave_frequencies.txt",)}


@dataclass(frozen=True)
class DeckWaves:
    """Wave components read from a deck's wave files (cosine convention).

    η(x, y, t) = mean_level + Σ amplitude cos(omega t − k (x cos heading + y sin heading) + phase).

    Attributes:
        mode: the deck's ``WaveKin`` value (2, 3 or 7).
        path: the file the components came from.
        omega, amplitude, phase, heading: (n,) [rad/s], [m], [rad], [rad].
        mean_level: the constant surface level η̄ [m] (MoorDyn's 0 rad/s bin).
        grid: for modes 2 and 3, the (x, y, z) axes [m] of ``water_grid.txt``.
    """

    mode: int
    path: str
    omega: np.ndarray
    amplitude: np.ndarray
    phase: np.ndarray
    heading: np.ndarray
    mean_level: float = 0.0
    grid: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None


def _lines(path: Path, origin: str) -> list[str]:
    return moordyn_file_lines(path, origin, "wave")


def read_wave_frequencies(path, origin: str = ""):
    """Rows of a ``wave_frequencies.txt``: (omega (n,) [rad/s], A (n,) complex [m],
    beta (n,) [rad]). The first row must be at 0 rad/s (as MoorDyn demands)."""
    path = Path(path)
    what = "wave frequency row 'omega [rad/s] Re(A) [m] Im(A) [m] [beta [rad]]'"
    om, amp, beta = [], [], []
    for lineno, _, vals in number_rows(path, _lines(path, origin or str(path)), 1, what):
        if len(vals) not in (3, 4):
            raise InputError(f"{path}:{lineno}: {len(vals)} numbers; expected 3 or 4 in a {what}")
        b = vals[3] if len(vals) == 4 else 0.0
        if abs(b) > 2 * math.pi:
            raise InputError(f"{path}:{lineno}: direction beta = {b} rad is outside [-2pi, 2pi]; give it "
                             "in radians")
        if vals[0] < 0:
            raise InputError(f"{path}:{lineno}: frequency {vals[0]} rad/s is negative; expected >= 0")
        om.append(vals[0])
        amp.append(complex(vals[1], vals[2]))
        beta.append(b)
    if len(om) < 2:
        raise InputError(f"{path}: {len(om)} frequency row(s); MoorDyn needs at least 2 (the first at 0 rad/s)")
    if om[0] != 0.0:
        raise InputError(f"{path}:1: the first frequency is {om[0]} rad/s; MoorDyn needs the first row at "
                         "0 rad/s")
    return np.asarray(om), np.asarray(amp), np.asarray(beta)


def read_wave_elevation(path, origin: str = ""):
    """Rows ``t [s]  η [m]`` of a ``wave_elevation.txt``: (t (n,), eta (n,))."""
    path = Path(path)
    ts, etas, where = [], [], []
    for lineno, _, vals in number_rows(path, _lines(path, origin or str(path)), 1,
                                       "wave elevation row 't [s] eta [m]'"):
        if len(vals) < 2:
            raise InputError(f"{path}:{lineno}: {len(vals)} number(s); expected 't [s] eta [m]'")
        if ts and not vals[0] > ts[-1]:
            raise InputError(f"{path}:{lineno}: t = {vals[0]} s is not after the previous {ts[-1]} s; the "
                             "times must increase")
        ts.append(vals[0])
        etas.append(vals[1])
        where.append(lineno)
    if len(ts) < 2:
        raise InputError(f"{path}: {len(ts)} elevation row(s); expected a time series 't [s] eta [m]'")
    return np.asarray(ts), np.asarray(etas)


def _grid_axis(path, lineno, kind_raw, raw):
    kind = row_numbers(path, lineno - 1, kind_raw, "grid axis kind (0 single, 1 list, 2 lattice)")
    vals = row_numbers(path, lineno, raw, "grid axis coordinates [m]")
    k = int(kind[0]) if kind else -1
    if k == 0:
        return np.zeros(1)
    if k == 1 and vals:
        return np.asarray(vals)
    if k == 2 and len(vals) >= 3 and int(vals[2]) >= 2:
        return np.linspace(vals[0], vals[1], int(vals[2]))
    raise InputError(f"{path}:{lineno - 1}: grid axis kind {kind_raw.strip()!r} with coordinates "
                     f"{raw.strip()!r}; expected 0 (a single 0), 1 (a list of coordinates) or 2 "
                     "('first last n')")


def read_water_grid(path, origin: str = ""):
    """The (x, y, z) axes [m] of a ``water_grid.txt`` (3 header lines, then per axis
    a kind line — 0 single, 1 list, 2 lattice — and its coordinates)."""
    path = Path(path)
    lines = _lines(path, origin or str(path))
    if len(lines) < 9:
        raise InputError(f"{path}: {len(lines)} lines; a water grid has 3 header lines and 2 lines per "
                         "axis (x, y, z)")
    return tuple(_grid_axis(path, 5 + 2 * i, lines[3 + 2 * i], lines[4 + 2 * i]) for i in range(3))


def _components(omega, c, beta):
    """(ω, amplitude, phase, heading) of complex cosine amplitudes c, zero ones dropped."""
    keep = np.abs(c) > 0
    return omega[keep], np.abs(c[keep]), np.angle(c[keep]), beta[keep]


def _sum_components(path, origin):
    om, c, beta = read_wave_frequencies(path, origin)
    dc = om == 0.0
    level = float(np.sum(c[dc].imag))  # |A| sin(arg A) of a 0 rad/s row
    # |A| sin(ψ + arg A) = |A| cos(ψ + arg A − π/2)
    c = c * np.exp(-0.5j * np.pi)
    return (*_components(om[~dc], c[~dc], beta[~dc]), level)


def _fft_grid(path, origin):
    om, c, beta = read_wave_frequencies(path, origin)
    dw = np.min(np.diff(om))
    if not dw > 0:
        raise InputError(f"{path}: the frequencies must increase strictly for WaveKin = 2 (MoorDyn "
                         "interpolates them to even spacing); use WaveKin = 7 for repeated or unsorted ones")
    nw = int(math.floor(om[-1] / dw)) + 1
    w = np.arange(nw) * dw
    ce = np.interp(w, om, c.real) + 1j * np.interp(w, om, c.imag)
    be = np.interp(w, om, beta)
    level = 0.5 * float(ce[0].real)
    ce = ce.copy()
    ce[-1] = 0.5 * ce[-1].real
    return (*_components(w[1:], ce[1:], be[1:]), level)


def _elevation_grid(path, origin, dt_wave):
    t, eta = read_wave_elevation(path, origin)
    dt = float(np.float32(dt_wave))  # MoorDyn reads dtWave with stof
    n = int(math.floor(t[-1] / dt)) + 1
    n -= n % 2  # MoorDyn's real FFT needs an even count; the last sample is dropped
    if n < 2:
        raise InputError(f"{path}: the record ({t[-1]} s) is shorter than two dtWave = {dt_wave} s steps")
    x = np.fft.rfft(np.interp(np.arange(n) * dt, t, eta))
    j = np.arange(x.shape[0])
    dw = np.pi / (dt * (n // 2))
    x[j * dw > np.pi] = 0.0  # MoorDyn cuts the bins above 0.5 Hz
    c = 2.0 * x / n
    c[-1] = x[-1].real / n  # Nyquist bin
    return (*_components(j[1:] * dw, c[1:], np.zeros(j.shape[0] - 1)), float(x[0].real) / n)


def read_deck_waves(folder, mode: int, dt_wave: float = 0.25, origin: str = "") -> DeckWaves:
    """The wave components of ``WaveKin = mode`` from the files in ``folder``.

    Args:
        folder: the deck's folder (MoorDyn reads the files from there).
        mode: 2, 3 or 7 (see the module docstring).
        dt_wave: the deck's ``dtWave`` [s] (mode 3 only).
        origin: where the deck asked for them (``deck:line``), for messages.
    """
    folder = Path(folder)
    if mode not in WAVE_FILES:
        raise InputError(f"{origin}: WaveKin = {mode} is not supported; expected 0, 2, 3 or 7")
    main = folder / WAVE_FILES[mode][0]
    grid = read_water_grid(folder / "water_grid.txt", origin) if mode in (2, 3) else None
    if mode == 7:
        om, a, ph, beta, level = _sum_components(main, origin)
    elif mode == 2:
        om, a, ph, beta, level = _fft_grid(main, origin)
    else:
        om, a, ph, beta, level = _elevation_grid(main, origin, dt_wave)
    return DeckWaves(mode, str(main), om, a, ph, beta, level, grid)
