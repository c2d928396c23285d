"""Progress reports of the command line, on stderr.

On only when stderr is a terminal and ``--quiet`` is not given (so logs and
pipes stay clean). :class:`Progress` prints phase lines and a one-line bar;
:meth:`Progress.meter` turns the run's progress lines (which
``simulate(progress=True)`` prints on stdout as ``12.00% 1234 56``: progress,
steps, rejected steps; see :mod:`moorjax.dynamics.meter`) into the bar with the
simulated time and the step counts.
"""

from __future__ import annotations

import contextlib
import sys
import time


def enabled(quiet: bool, stream=None) -> bool:
    stream = sys.stderr if stream is None else stream
    return not quiet and hasattr(stream, "isatty") and stream.isatty()


class Progress:
    """Phase messages and a bar for one command (``on=False``: silent)."""

    def __init__(self, command: str, on: bool, stream=None):
        self.command = command
        self.on = on
        self.stream = sys.stderr if stream is None else stream
        self.start = time.perf_counter()
        self._open = False

    def elapsed(self) -> float:
        return time.perf_counter() - self.start

    def say(self, text: str) -> None:
        if self.on:
            self._end_bar()
            print(f"moorjax {self.command}: {text}", file=self.stream, flush=True)

    def bar(self, fraction: float, text: str) -> None:
        if not self.on:
            return
        fraction = min(max(fraction, 0.0), 1.0)
        filled = int(round(24 * fraction))
        line = f"\r[{'#' * filled}{'.' * (24 - filled)}] {100 * fraction:5.1f}% {text}"
        self.stream.write(line + " " * 4)
        self.stream.flush()
        self._open = True

    def _end_bar(self):
        if self._open:
            self.stream.write("\n")
            self._open = False

    def close(self) -> None:
        if self.on:
            self._end_bar()

    @contextlib.contextmanager
    def meter(self, t0: float, duration: float):
        """Redirect stdout while diffrax's meter prints; show simulated time."""
        if not self.on:
            yield
            return
        sink = _MeterSink(self, t0, duration)
        with contextlib.redirect_stdout(sink):
            yield
        self._end_bar()


class _MeterSink:
    """A stdout stand-in that reads ``NN.NN%`` lines into :meth:`Progress.bar`."""

    def __init__(self, progress: Progress, t0: float, duration: float):
        self.p, self.t0, self.duration = progress, t0, duration
        self.buf = ""

    def write(self, text: str) -> int:
        self.buf += text
        while "\n" in self.buf:
            line, self.buf = self.buf.split("\n", 1)
            fields = line.split()
            if fields and fields[0].endswith("%"):
                try:
                    frac = float(fields[0][:-1]) / 100.0
                    counts = [int(x) for x in fields[1:3]]
                except ValueError:
                    continue
                steps = (f", {counts[0]} steps ({counts[1]} rejected)" if len(counts) == 2 else "")
                self.p.bar(frac, f"t = {self.t0 + frac * self.duration:.4g} / "
                                 f"{self.t0 + self.duration:.4g} s simulated{steps}, "
                                 f"{self.p.elapsed():.0f} s wall")
            elif line:
                print(line, file=sys.__stdout__)
        return len(text)

    def flush(self) -> None:
        pass
