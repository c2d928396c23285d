"""Which MoorDyn decks moorjax reads and solves: statics over every deck in a folder.

    python benchmarks/deck_survey.py FOLDER [--out survey.md] [--json survey.json]
        [--timeout 300] [--segments N]

Every ``*.txt``/``*.dat`` file under FOLDER with a MoorDyn section header
(``--- LINE TYPES ---``, ``LINE DICTIONARY``, ``ROD TYPES``, ``BODIES``) is a
deck. Each is read (:func:`moorjax.io.read_deck`), built
(:func:`moorjax.io.build_scene`) and solved for its static equilibrium in a
child process (so that one deck's compilations, crash or time-out cannot touch
the others): :func:`moorjax.statics.solve_line_statics` per line, or
:func:`moorjax.statics.solve_system_statics` when the deck has free points or
free bodies.
The table gives, per deck, ``runs`` (statics converged: the largest end
tension and the wall time, compilation included), ``refused`` (the reader's
or builder's message: what is not supported and where), ``statics (issue 11)``
(read and built, but the static solve did not converge — the static solver's
robustness, not the deck) or ``time-out``.

``deck_survey.md`` says how its tables were made: the folder holds MoorDyn's
``tests/Mooring``, ``bench/Mooring``, ``example`` (FloatingArrayDesign/MoorDyn
319ff99) under ``MoorDyn/`` and MoorPy's ``tests``, ``examples`` (NREL/MoorPy
30b7fc4) under ``MoorPy/``.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import time
from pathlib import Path

_DECK_HEADER = re.compile(r"-{3}.*(LINE TYPES|LINE DICTIONARY|ROD TYPES|ROD DICTIONARY|BODIES|BODY LIST)",
                          re.IGNORECASE)

_CHILD = r"""
import json, sys, time, warnings
warnings.simplefilter("ignore")
path, segments = sys.argv[1], (int(sys.argv[2]) if sys.argv[2] != "-" else None)
out = {}
t0 = time.perf_counter()
try:
    from moorjax.io import build_scene, read_deck
    from moorjax.io.errors import InputError
    try:
        deck = read_deck(path)
        scene = build_scene(deck, segments=segments)
    except (InputError, ValueError) as err:
        out = {"status": "refused", "reason": str(err)}
    else:
        from moorjax.statics import solve_line_statics, solve_system_statics
        try:
            if scene.bodies:
                st = solve_system_statics(scene, throw=False)
                ok = bool(st.converged)
                lines = st.lines
            else:
                lines = [solve_line_statics(ln, scene.env, throw=False) for ln in scene.lines]
                ok = all(bool(s.converged) for s in lines)
            tens = max(max(float(s.tension_a), float(s.tension_b)) for s in lines)
            if ok:
                out = {"status": "runs", "reason": f"max end tension {tens:.6g} N",
                       "n_lines": len(scene.lines), "n_free_objects": len(scene.bodies)}
            else:
                out = {"status": "statics (issue 11)", "reason": "static solve did not converge"}
        except Exception as err:  # the static solver's runtime errors
            msg = str(err).splitlines()
            out = {"status": "statics (issue 11)",
                   "reason": "static solve failed: " + next((m for m in msg if "EquinoxRuntimeError" in m
                                                              or "did not converge" in m), msg[0] if msg else "")[:200]}
except Exception as err:
    out = {"status": "error", "reason": f"{type(err).__name__}: {err}"[:300]}
out["wall_s"] = round(time.perf_counter() - t0, 1)
print("SURVEY-RESULT " + json.dumps(out))
"""


def find_decks(folder: Path) -> list[Path]:
    """MoorDyn decks under ``folder`` (sorted)."""
    out = []
    for p in sorted(folder.rglob("*")):
        if p.suffix.lower() not in (".txt", ".dat") or not p.is_file():
            continue
        try:
            text = p.read_text(encoding="utf-8", errors="replace")
        except OSError:
            continue
        if any(_DECK_HEADER.search(line) for line in text.splitlines()):
            out.append(p)
    return out


def survey_one(path: Path, timeout: float, segments: int | None, root: Path) -> dict:
    t0 = time.perf_counter()
    try:
        proc = subprocess.run([sys.executable, "-c", _CHILD, str(path), str(segments or "-")],
                              capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        res = {"status": "time-out", "reason": f"statics did not finish in {timeout:g} s",
               "wall_s": round(time.perf_counter() - t0, 1)}
    else:
        line = next((ln for ln in proc.stdout.splitlines() if ln.startswith("SURVEY-RESULT ")), None)
        if line is None:
            tail = (proc.stderr.strip().splitlines() or ["(no output)"])[-1]
            res = {"status": "error", "reason": f"child exited {proc.returncode}: {tail}"[:300],
                   "wall_s": round(time.perf_counter() - t0, 1)}
        else:
            res = json.loads(line[len("SURVEY-RESULT "):])
    res["deck"] = str(path.relative_to(root))
    return res


def _short(reason: str) -> str:
    """The reason without the deck's path (the table names the deck)."""
    reason = reason.replace("\n", " ")
    m = re.match(r"^\S+?:(\d+): ", reason)
    if m:
        reason = f"line {m.group(1)}: " + reason[m.end():]
    return reason if len(reason) <= 400 else reason[:397] + "..."


def table(results: list[dict]) -> str:
    rows = ["| deck | result | reason | wall [s] |", "|---|---|---|---|"]
    for r in results:
        rows.append(f"| {r['deck']} | {r['status']} | {_short(r['reason']).replace('|', '/')} | {r['wall_s']} |")
    counts: dict[str, int] = {}
    for r in results:
        counts[r["status"]] = counts.get(r["status"], 0) + 1
    summary = ", ".join(f"{k}: {v}" for k, v in sorted(counts.items()))
    return "\n".join(rows) + f"\n\n{len(results)} decks — {summary}\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path)
    ap.add_argument("--out", type=Path, help="write the markdown table here too")
    ap.add_argument("--json", type=Path, help="write the results as JSON")
    ap.add_argument("--timeout", type=float, default=300.0, help="per deck [s]")
    ap.add_argument("--segments", type=int, default=None, help="override every line's segment count")
    args = ap.parse_args(argv)
    decks = find_decks(args.folder)
    results = []
    for p in decks:
        r = survey_one(p, args.timeout, args.segments, args.folder)
        results.append(r)
        print(f"{r['deck']}: {r['status']} ({r['wall_s']} s) {_short(r['reason'])[:160]}", flush=True)
        if args.json:
            args.json.write_text(json.dumps(results, indent=1))
    text = table(results)
    print(text)
    if args.out:
        args.out.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
