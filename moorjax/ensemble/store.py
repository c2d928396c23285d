"""Streaming large ensembles to disk in chunks, resumable after a crash.

Members are run ``chunk_size`` at a time (one compiled function: the last chunk
is padded). After each chunk its results are written atomically to
``DIR/chunks/chunk_<k>.npz`` (temporary file, then rename), so memory stays
bounded by two chunks (the next one is dispatched before a chunk's results are
read) and a crash loses at most the two in flight. Running the
same ensemble again into the same directory skips the chunks already on disk;
``DIR/manifest.json`` records a fingerprint of the members and settings, and a
directory holding a *different* ensemble is refused rather than mixed.

Per member, a chunk holds the summary statistics of every end tension (max,
mean, std over the output times), the diffrax result code and status, step
counts, and — with ``histories=True`` — the full tension histories.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable, Sequence

import jax
import numpy as np

from . import batch as _batch
from ..dynamics.integrate import result_codes
from .run import simulate_ensemble, status

SUMMARY_STATS = ("max", "mean", "std")


def _fingerprint(scenes, settings) -> str:
    h = hashlib.sha256()
    for s in scenes:
        for leaf in jax.tree_util.tree_leaves(s):
            a = np.asarray(leaf)
            h.update(str(a.shape).encode())
            h.update(np.ascontiguousarray(a, dtype=float).tobytes() if a.dtype != object else b"")
        h.update(str(jax.tree_util.tree_structure(s)).encode())
    h.update(json.dumps(settings, sort_keys=True, default=str).encode())
    return h.hexdigest()


def summarise(res) -> dict[str, np.ndarray]:
    """Per-member statistics of each end tension: ``{'tension_b_max': (m, lines), ...}``."""
    out = {}
    for end in ("tension_a", "tension_b"):
        x = np.asarray(getattr(res, end))  # (members, times, lines)
        out[f"{end}_max"] = x.max(axis=1)
        out[f"{end}_mean"] = x.mean(axis=1)
        out[f"{end}_std"] = x.std(axis=1)
    return out


def _write_atomic(path, **arrays):
    tmp = path + ".tmp.npz"
    np.savez(tmp, **arrays)
    os.replace(tmp, path)


def run_chunked(
    scenes: Sequence,
    out_dir: str,
    duration=None,
    *,
    chunk_size: int = 100,
    histories: bool = False,
    on_chunk: Callable[[int, int], None] | None = None,
    **settings,
) -> dict[str, np.ndarray]:
    """Run an ensemble chunk by chunk into ``out_dir`` (resuming if it exists).

    Args:
        scenes: the members (a sequence of scenes of one structure).
        out_dir: directory for ``manifest.json`` and ``chunks/``.
        duration, settings: as :func:`simulate_ensemble`.
        chunk_size: members per compiled call (bounds memory).
        histories: also store full tension histories (``ts``, ``tension_a``,
            ``tension_b``) per chunk.
        on_chunk: called as ``on_chunk(k, n_chunks)`` after each chunk (progress).

    Returns:
        the concatenated per-member arrays of all chunks (see :func:`load`).
    """
    scenes = list(scenes)
    n = len(scenes)
    if n == 0:
        raise ValueError("an ensemble needs at least one member")
    if int(chunk_size) < 1:
        raise ValueError(f"chunk_size = {chunk_size} must be >= 1")
    chunk_size = min(int(chunk_size), n)
    # fail on structure before any work (names the differing field)
    for i, s in enumerate(scenes[1:], start=1):
        d = _batch.structure_difference(scenes[0], s, "scene")
        if d is not None:
            raise _batch.StructureMismatchError(
                f"ensemble members 0 and {i} differ in structure at {d}"
            )
    key = _fingerprint(scenes, dict(duration=duration, chunk_size=chunk_size,
                                     histories=histories, **settings))
    os.makedirs(os.path.join(out_dir, "chunks"), exist_ok=True)
    manifest_path = os.path.join(out_dir, "manifest.json")
    n_chunks = -(-n // chunk_size)
    manifest = dict(fingerprint=key, members=n, chunk_size=chunk_size, chunks=n_chunks)
    if os.path.exists(manifest_path):
        with open(manifest_path) as f:
            old = json.load(f)
        if old.get("fingerprint") != key:
            raise ValueError(
                f"{out_dir} holds results of a different ensemble (other members or "
                "settings); use a new directory or delete it"
            )
    else:
        with open(manifest_path, "w") as f:
            json.dump(manifest, f, indent=1)

    def finish(k, idx, res):
        """Chunk k's statistics and outcomes, written to its file."""
        res = _batch.first(res, len(idx), chunk_size)
        arrays = {f"stat_{k2}": v for k2, v in summarise(res).items()}
        arrays.update(
            member=idx,
            result=result_codes(res.result),
            status=status(res).astype(str),
            num_steps=np.asarray(res.num_steps),
            num_rejected_steps=np.asarray(res.num_rejected_steps),
        )
        if histories:
            arrays.update(
                ts=np.asarray(res.ts[0]),
                tension_a=np.asarray(res.tension_a),
                tension_b=np.asarray(res.tension_b),
            )
        _write_atomic(_chunk_path(out_dir, k), **arrays)
        if on_chunk is not None:
            on_chunk(k, n_chunks)

    # one chunk ahead: chunk k is prepared and dispatched (JAX runs it
    # asynchronously) before chunk k-1's results are read and written, so the
    # host's work between chunks overlaps the devices' (at most two chunks'
    # results are held; a crash loses at most the two in flight)
    pending = None
    for k in range(n_chunks):
        if os.path.exists(_chunk_path(out_dir, k)):
            continue  # resumed: this chunk is already on disk
        idx = np.arange(k * chunk_size, min((k + 1) * chunk_size, n))
        members = [scenes[i] for i in idx]
        members += [members[-1]] * (chunk_size - len(members))  # same compiled shape
        try:
            res = simulate_ensemble(members, duration, **settings)
        except Exception:  # e.g. a member's bad geometry: keep the chunk already run
            if pending is not None:
                finish(*pending)
            raise
        if pending is not None:
            finish(*pending)
        pending = (k, idx, res)
    if pending is not None:
        finish(*pending)
    return load(out_dir)


def _chunk_path(out_dir, k):
    return os.path.join(out_dir, "chunks", f"chunk_{k:05d}.npz")


def load(out_dir: str) -> dict[str, np.ndarray]:
    """All chunks of ``out_dir`` concatenated along the member axis, in member order."""
    with open(os.path.join(out_dir, "manifest.json")) as f:
        manifest = json.load(f)
    parts = []
    for k in range(manifest["chunks"]):
        path = _chunk_path(out_dir, k)
        if not os.path.exists(path):
            raise FileNotFoundError(f"{path} is missing: the run did not finish; run it again to resume")
        with np.load(path) as z:
            parts.append({name: z[name] for name in z.files})
    out = {}
    for name in parts[0]:
        if name == "ts":
            out[name] = parts[0][name]
        else:
            out[name] = np.concatenate([p[name] for p in parts], axis=0)
    return out
