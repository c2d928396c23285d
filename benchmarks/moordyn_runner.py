"""Run MoorDyn v2 (the ``moordyn`` Python package) on a single-line deck with a
prescribed fairlead path, the way the project's reference data was made.

The caller drives the Coupled point: each call to ``MoorDyn_Step`` gets
``dt = dt_coupling`` (by default ``dt``, i.e. ``dtM``), the position of the
path at the start of the step and the chord velocity
``(path(t + dt) - path(t)) / dt``.  The initial state is MoorDyn's own IC
solver (``moordyn.Init``) at the t = 0 fairlead position with zero velocity,
followed by an optional dynamic hold of the fairlead at that position.

Only MoorDyn's public Python API is used (``moordyn`` / its ``cmoordyn``
extension); nothing of MoorDyn's source is copied here.

Example::

    from benchmarks.moordyn_runner import run_moordyn, rel_rms_error
    import numpy as np
    path = lambda t: np.array([-5.2 + 5*np.sin(2*np.pi*t/10), 0.0, -70.0])
    r = run_moordyn("moorjax/examples/oc3_catenary.dat", path, 20.0,
                    n_segments=40, dt=3.125e-3, scheme="rk2")
    print(r["ms_per_sim_s"], r["status"])
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import os
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

__all__ = ["run_moordyn", "rel_rms_error", "load_reference", "SCHEMES",
           "UNSTABLE_FORCE_N", "DEFAULT_HOLD_S", "REFERENCE_DIR"]

#: our scheme names -> the ``tScheme`` strings written into the deck.  MoorDyn
#: 2.7.2 compares them case-insensitively ("RK2" == "rk2"); "midpoint5" is its
#: k = 0.5 implicit Euler with 5 fixed-point iterations.  Other MoorDyn names
#: (euler, heun, ab3, beuler5, aca5, ...) are passed through unchanged.
SCHEMES = {"rk2": "RK2", "rk4": "RK4", "midpoint5": "Midpoint5"}

#: |F| above this (or NaN/inf) marks a run as unstable (the bound of most rows
#: of the reference cost table; a few case-B rows used 2x the reference peak).
UNSTABLE_FORCE_N = 5.0e7

#: default dynamic hold [s] after MoorDyn's IC solver (see ``run_moordyn``).
DEFAULT_HOLD_S = 2.0

#: where the project's reference data lives when it is available (optional;
#: override with the MOORJAX_REFERENCE_DIR environment variable).
#: the reference folder: $MOORJAX_REFERENCE_DIR, else ../shared/reference beside the
#: repository root (as every benchmark's --reference default)
REFERENCE_DIR = Path(os.environ.get(
    "MOORJAX_REFERENCE_DIR",
    Path(__file__).resolve().parents[1].parent / "shared" / "reference"))


# --------------------------------------------------------------------------
# deck rewriting
# --------------------------------------------------------------------------

_HEADER = re.compile(r"^\s*-{2,}")


def _section(line: str) -> str | None:
    """Name of the section a ``----- NAME -----`` header opens, else None."""
    if not _HEADER.match(line):
        return None
    name = line.strip().strip("-").strip().upper()
    if name.startswith("LINE TYPE") or name.startswith("LINE DICTIONARY"):
        return "LINETYPES"
    if name.startswith("LINES") or name.startswith("LINE PROPERTIES") or name == "LINE LIST":
        return "LINES"
    if name.startswith("OPTIONS") or name.startswith("SOLVER OPTIONS"):
        return "OPTIONS"
    return "OTHER"


def _rewrite_deck(text: str, n_segments: int, dt: float, tscheme: str) -> str:
    """Copy of ``text`` with NumSegs, dtM and tScheme replaced.

    Also forces ``writeLog 0``, ``disableOutput 1`` and ``disableOutTime 1``
    (inserted when missing) so MoorDyn writes as little as possible.
    """
    forced = {"dtm": repr(float(dt)), "tscheme": tscheme, "writelog": "0",
              "disableoutput": "1", "disableouttime": "1"}
    lines = text.splitlines()
    out: list[str] = []
    section = None
    rows_to_skip = 0
    n_lines_done = 0
    seen: set[str] = set()
    for raw in lines:
        sec = _section(raw)
        if sec is not None:
            if section == "OPTIONS":
                # closing the OPTIONS table: add whatever was not in the deck
                for key, val in forced.items():
                    if key not in seen:
                        name = {"dtm": "dtM", "tscheme": "tScheme", "writelog": "writeLog",
                                "disableoutput": "disableOutput",
                                "disableouttime": "disableOutTime"}[key]
                        out.append(f"{val:<24} {name}")
                        seen.add(key)
            section = sec
            # LINES has two heading rows (names, units); OPTIONS has none
            rows_to_skip = 2 if sec == "LINES" else 0
            out.append(raw)
            continue
        if section == "LINES":
            if rows_to_skip:
                rows_to_skip -= 1
                out.append(raw)
                continue
            tok = raw.split()
            if len(tok) >= 6:
                # ID LineType AttachA AttachB UnstrLen NumSegs [LineOutputs]
                tok[5] = str(int(n_segments))
                out.append("  ".join(tok))
                n_lines_done += 1
                continue
        elif section == "OPTIONS":
            tok = raw.split(None, 2)
            if len(tok) >= 2 and tok[1].lower() in forced:
                key = tok[1].lower()
                seen.add(key)
                rest = tok[2] if len(tok) > 2 else ""
                out.append(f"{forced[key]:<24} {tok[1]}  {rest}".rstrip())
                continue
        out.append(raw)
    if n_lines_done == 0:
        raise ValueError("deck: no LINES table row found (cannot set NumSegs)")
    if section == "OPTIONS" and len(seen) < len(forced):
        raise ValueError("deck: OPTIONS section is not closed by a '----' line")
    if "dtm" not in seen:
        raise ValueError("deck: no OPTIONS section found (cannot set dtM)")
    return "\n".join(out) + "\n"


# --------------------------------------------------------------------------
# console capture (MoorDyn's C++ core writes to the process's stdout/stderr)
# --------------------------------------------------------------------------

try:
    _libc = ctypes.CDLL(None)
except OSError:  # pragma: no cover - non-POSIX
    _libc = None


def _flush_all() -> None:
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:
            pass
    if _libc is not None:
        try:
            _libc.fflush(None)
        except Exception:
            pass


@contextlib.contextmanager
def _console_to(path: Path):
    """Send file descriptors 1 and 2 to ``path`` (C/C++ output included)."""
    _flush_all()
    saved = []
    try:
        fd = os.open(str(path), os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    except OSError:
        yield
        return
    try:
        for target in (1, 2):
            try:
                saved.append((target, os.dup(target)))
                os.dup2(fd, target)
            except OSError:
                pass
        yield
    finally:
        _flush_all()
        for target, copy in saved:
            os.dup2(copy, target)
            os.close(copy)
        os.close(fd)


# --------------------------------------------------------------------------
# the runner
# --------------------------------------------------------------------------

def _finite_small(f, limit) -> bool:
    mag = math.sqrt(f[0] ** 2 + f[1] ** 2 + f[2] ** 2)
    return math.isfinite(mag) and mag <= limit


def _coupled_point(md, s):
    import cmoordyn
    for i in range(1, cmoordyn.get_number_points(s) + 1):
        p = cmoordyn.get_point(s, i)
        if cmoordyn.point_get_type(p) == md.POINT_TYPE_COUPLED:
            return p
    raise ValueError("deck has no Coupled point")


def _one_run(md, deck_file: Path, log_file: Path, x0, P, dtc, hold_steps,
             out_steps, max_force):
    """Create + Init + hold (timed as init_s) then the stepping loop (wall_s)."""
    import cmoordyn

    step = cmoordyn.step
    fairten = cmoordyn.line_get_fairlead_tension
    nout = len(out_steps)
    F = np.full((nout, 3), np.nan)
    Tseg = np.full(nout, np.nan)
    status = "ok"
    n_done = 0
    wall = 0.0
    cpu = 0.0
    with _console_to(log_file):
        t_init = time.perf_counter()
        s = md.Create(str(deck_file))
        try:
            if md.NCoupledDOF(s) != 3:
                raise ValueError("expected exactly one Coupled point (3 DOF), got "
                                 f"{md.NCoupledDOF(s)} coupled DOFs")
            line = cmoordyn.get_line(s, 1)
            _coupled_point(md, s)
            err = md.Init(s, list(x0), [0.0, 0.0, 0.0])
            if err != md.ERRCODE_SUCCESS:
                raise RuntimeError(f"moordyn.Init failed with error code {err}")
        except BaseException:
            md.Close(s)
            raise
        zero = [0.0, 0.0, 0.0]
        x0l = [float(c) for c in x0]
        try:  # dynamic hold, fairlead still
            for k in range(hold_steps):
                f = step(s, x0l, zero, k * dtc, dtc)
            if hold_steps and not _finite_small(f, max_force):
                status = "unstable"
        except RuntimeError:  # MoorDyn raises on NaN states
            status = "unstable"
        t_md = hold_steps * dtc
        init_s = time.perf_counter() - t_init

        k0 = 0
        if status == "ok":
            for j, k1 in enumerate(out_steps):
                # chunk of steps k0 .. k1-1; converting to lists is not timed
                xs = P[k0:k1].tolist()
                vs = ((P[k0 + 1:k1 + 1] - P[k0:k1]) / dtc).tolist()
                base = t_md + k0 * dtc
                ctic = time.thread_time()
                tic = time.perf_counter()
                try:
                    for i in range(k1 - k0):
                        f = step(s, xs[i], vs[i], base + i * dtc, dtc)
                except RuntimeError:
                    wall += time.perf_counter() - tic
                    cpu += time.thread_time() - ctic
                    status = "unstable"
                    break
                wall += time.perf_counter() - tic
                cpu += time.thread_time() - ctic
                F[j] = f
                Tseg[j] = fairten(line)
                n_done = k1
                k0 = k1
                if not (_finite_small(f, max_force) and math.isfinite(Tseg[j])):
                    status = "unstable"
                    break
        md.Close(s)
    return dict(force=F, fair_ten=Tseg, status=status, wall_s=wall, cpu_s=cpu,
                init_s=init_s, steps_done=n_done)


def run_moordyn(deck_path, path_fn, duration, *, n_segments, dt, scheme="rk2",
                dt_out=0.05, hold=None, repeats=1, workdir=None,
                dt_coupling=None, max_force=UNSTABLE_FORCE_N) -> dict:
    """Run MoorDyn v2 on a single-line deck with a prescribed fairlead path.

    Parameters
    ----------
    deck_path : MoorDyn v2 input file with one line and one Coupled point (the
        fairlead).  A copy with ``NumSegs = n_segments``, ``dtM = dt`` and
        ``tScheme = scheme`` is written to a temporary folder (removed after,
        unless ``workdir`` is given, which is then used and kept).
    path_fn : ``path_fn(t) -> (3,)`` fairlead position [m], t >= 0 [s].
    duration : simulated time after the hold [s].
    n_segments, dt : number of segments and MoorDyn's time step dtM [s].
    scheme : ``"rk2"``, ``"rk4"``, ``"midpoint5"`` (or any MoorDyn tScheme
        name; an unknown name raises instead of MoorDyn's silent RK2 fallback).
    dt_out : sampling interval of the returned history [s] (rounded to a
        whole number of coupling steps).
    hold : seconds of dynamic hold at ``path_fn(0)`` (zero velocity) after
        MoorDyn's IC solver; ``None`` -> ``DEFAULT_HOLD_S`` (2 s).  The
        reference runs held 40 s (case A) and 2 s (case B); the hold length
        changes rel_rms_error by < 1e-6 with rk2/rk4 and ~5e-6 with
        midpoint5 (0 to 40 s, N = 10..40).  The hold
        is counted in ``init_s``, not in ``wall_s``.
    repeats : the whole run (Create, Init, hold, loop) is repeated; ``wall_s``
        is the minimum stepping-loop time, the history is the first run's.
    dt_coupling : time between ``MoorDyn_Step`` calls (default ``dt``, the
        reference protocol).  A multiple of ``dt`` lets MoorDyn sub-step
        internally (less Python overhead, coupled point moved linearly
        within the call); the reference cost table timed with ~12.5 ms.
    max_force : |F| [N] above which the run is declared unstable (5e7).

    Returns
    -------
    dict with ``t`` (k,), ``tension`` (k,) = |F| (the force MoorDyn returns
    for the coupled point = the end node's net force; compare with
    sqrt(Fx²+Fy²+Fz²) of ref_*.csv), ``force`` (k, 3), ``fair_ten`` (k,) =
    MoorDyn's fairlead segment tension |T + Td| of the top segment (compare
    with ``T_fair_N``), ``wall_s`` (stepping loop only, min over repeats),
    ``init_s`` (Create + IC solver + hold), ``ms_per_sim_s`` (1e3 * wall_s /
    simulated seconds), ``cpu_s`` / ``cpu_ms_per_sim_s`` (the same loop in
    thread CPU time, min over repeats: steadier than wall time when other
    processes share the cores),
    ``n_segments``, ``dt``, ``dt_coupling``, ``scheme``, ``hold``,
    ``integrator`` (MoorDyn's own name for the scheme it used) and
    ``status`` ('ok' or 'unstable': NaN/inf, a MoorDyn NaN error, or |F| >
    ``max_force``; the loop stops there, later samples are NaN).

    MoorDyn's console output (it prints a lot from C++) is sent to a file in
    the temporary folder while MoorDyn runs; if a run fails its tail is
    written to stderr.
    """
    import moordyn as md

    if n_segments < 1 or int(n_segments) != n_segments:
        raise ValueError("n_segments must be a positive integer")
    dt = float(dt)
    if not dt > 0:
        raise ValueError("dt must be > 0")
    dtc = dt if dt_coupling is None else float(dt_coupling)
    if dtc < dt * (1 - 1e-9):
        raise ValueError("dt_coupling must be >= dt")
    hold = DEFAULT_HOLD_S if hold is None else float(hold)
    tscheme = SCHEMES.get(scheme.lower(), scheme)

    n_steps = int(round(duration / dtc))
    hold_steps = int(round(hold / dtc))
    per_out = max(1, int(round(dt_out / dtc)))
    out_steps = list(range(per_out, n_steps + 1, per_out))
    if not out_steps:
        raise ValueError("duration shorter than dt_out")

    # the prescribed path at every coupling instant (not timed)
    P = np.empty((n_steps + 1, 3))
    for k in range(n_steps + 1):
        P[k] = np.asarray(path_fn(k * dtc), dtype=float).reshape(3)
    x0 = P[0]

    text = Path(deck_path).read_text()
    deck = _rewrite_deck(text, int(n_segments), dt, tscheme)

    own_tmp = workdir is None
    wd = Path(tempfile.mkdtemp(prefix="moordyn_run_")) if own_tmp else Path(workdir)
    wd.mkdir(parents=True, exist_ok=True)
    try:
        deck_file = wd / "line.dat"
        deck_file.write_text(deck)
        log_file = wd / "console.txt"
        runs = []
        for _ in range(max(1, int(repeats))):
            if log_file.exists():
                log_file.unlink()
            try:
                runs.append(_one_run(md, deck_file, log_file, x0, P, dtc,
                                     hold_steps, out_steps, float(max_force)))
            except BaseException:
                if log_file.exists():  # MoorDyn's own diagnostics
                    sys.stderr.write("MoorDyn console output (tail):\n"
                                     + log_file.read_text(errors="replace")[-3000:]
                                     + "\n")
                raise
            console = log_file.read_text(errors="replace") if log_file.exists() else ""
            if "Unknown time scheme" in console:
                raise ValueError(f"MoorDyn does not know tScheme {tscheme!r}")
            if runs[-1]["status"] != "ok":
                break
        m = re.search(r"Time integrator\s*=\s*(.+)", console)
        integrator = m.group(1).strip() if m else None
    finally:
        if own_tmp:
            shutil.rmtree(wd, ignore_errors=True)

    first = runs[0]
    F = first["force"]
    wall = min(r["wall_s"] for r in runs)
    cpu = min(r["cpu_s"] for r in runs)
    sim_s = first["steps_done"] * dtc
    ok = all(r["status"] == "ok" for r in runs)
    return dict(
        t=np.array(out_steps, dtype=float) * dtc,
        tension=np.linalg.norm(F, axis=1),
        force=F,
        fair_ten=first["fair_ten"],
        wall_s=wall,
        init_s=min(r["init_s"] for r in runs),
        ms_per_sim_s=(1e3 * wall / sim_s) if (ok and sim_s > 0) else float("nan"),
        cpu_s=cpu,
        cpu_ms_per_sim_s=(1e3 * cpu / sim_s) if (ok and sim_s > 0) else float("nan"),
        n_segments=int(n_segments),
        dt=dt,
        dt_coupling=dtc,
        scheme=scheme,
        hold=hold_steps * dtc,
        integrator=integrator,
        status="ok" if ok else "unstable",
    )


# --------------------------------------------------------------------------
# reference comparison
# --------------------------------------------------------------------------

def load_reference(ref_csv, column="force"):
    """(t, tension) from a ``ref_*.csv``.

    ``column="force"`` gives |F| = sqrt(Fx²+Fy²+Fz²) (compare with
    ``run_moordyn(...)["tension"]``); ``"T_fair"`` gives ``T_fair_N`` (compare
    with ``fair_ten``); any other name is read as is.
    """
    data = np.genfromtxt(ref_csv, delimiter=",", names=True)
    t = np.asarray(data["t_s"], float)
    if column == "force":
        v = np.sqrt(data["Fx_N"] ** 2 + data["Fy_N"] ** 2 + data["Fz_N"] ** 2)
    elif column == "T_fair":
        v = data["T_fair_N"]
    else:
        v = data[column]
    return t, np.asarray(v, float)


def rel_rms_error(t, tension, ref, column="force"):
    """RMS(tension - reference) / std(reference) over the common samples.

    ``ref`` is a ``ref_*.csv`` path or a ``(t_ref, T_ref)`` pair.  The
    reference is linearly interpolated at ``t`` (samples of ``t`` outside
    the reference's time span are dropped); the std is that of the whole
    reference history, as in ``moordyn_cost_error.csv`` (whose
    ``rel_rms_err`` is ``fair_ten`` against ``T_fair_N`` over (0, 60] s:
    use ``column="T_fair"`` to reproduce it).
    """
    if isinstance(ref, (str, os.PathLike)):
        t_ref, T_ref = load_reference(ref, column)
    else:
        t_ref, T_ref = (np.asarray(a, float) for a in ref)
    t = np.asarray(t, float)
    tension = np.asarray(tension, float)
    eps = 1e-9 * max(1.0, float(np.max(np.abs(t_ref))))
    keep = (t >= t_ref[0] - eps) & (t <= t_ref[-1] + eps)
    if not keep.any():
        raise ValueError("no overlap between the run and the reference times")
    r = np.interp(t[keep], t_ref, T_ref)
    return float(np.sqrt(np.mean((tension[keep] - r) ** 2)) / np.std(T_ref))


# --------------------------------------------------------------------------
# demo
# --------------------------------------------------------------------------

def _demo() -> None:
    here = Path(__file__).resolve().parent
    deck = here.parent / "moorjax" / "examples" / "oc3_catenary.dat"
    ref = REFERENCE_DIR / "ref_A.csv"

    def path(t):
        return np.array([-5.2 + 5.0 * math.sin(2 * math.pi * t / 10.0), 0.0, -70.0])

    r = run_moordyn(deck, path, 20.0, n_segments=40, dt=3.125e-3, scheme="rk2",
                    repeats=3)
    print(f"MoorDyn case A, N=40, rk2, dtM=3.125 ms, 20 s, hold {r['hold']:g} s "
          f"[{r['integrator']}]: status {r['status']}")
    print(f"  stepping loop: {r['ms_per_sim_s']:.3f} ms per simulated second "
          f"wall, {r['cpu_ms_per_sim_s']:.3f} CPU (one Step call per dtM; min of 3); "
          f"init {r['init_s']:.2f} s")
    if ref.exists():
        e_f = rel_rms_error(r["t"], r["tension"], ref)
        e_t = rel_rms_error(r["t"], r["fair_ten"], ref, column="T_fair")
        print(f"  rel RMS error vs {ref.name} over (0, 20] s: |F| {e_f:.4g}, "
              f"T_fair {e_t:.4g}")
        print("  (moordyn_cost_error.csv, same run over 60 s: 2.31 ms per "
              "simulated second, T_fair rel_rms_err 0.00905)")
    else:
        print(f"  ({ref} not found: skipping the error column)")


if __name__ == "__main__":
    _demo()
