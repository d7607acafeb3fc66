"""The one progress display of pathfuse (``bench``, ``paper``, ``dynamic``, ``scen``), on stderr.

On a terminal it redraws one line in place::

    fusion-sweep [##########----------]  512/1024  50%  41.3 runs/s  ETA 0:00:12  3 err

Elsewhere (a log file, CI, a pipe) it writes a few plain lines: one every
``interval_s`` seconds (30 by default) and a last one, so logs stay short.

The rate and the time left are measured from the first finished item on,
so starting the workers (and loading kernels) does not make the first
estimate absurd; until two updates have come in, the line says
``starting`` instead of a rate.  The last line gives that rate and the
time since :meth:`start` (a sweep calls it once its kernels are compiled,
before it starts its workers).
``unit`` names what is counted (runs, episodes, lines).

Examples
--------
>>> import io
>>> out = io.StringIO()
>>> bar = ProgressBar(4, label="demo", stream=out, tty=False, interval_s=0.0)
>>> bar.update(2); bar.update(2, errors=1); bar.close()
>>> lines = out.getvalue().splitlines()
>>> lines[-1].startswith("demo") and "4/4" in lines[-1] and "1 err" in lines[-1]
True
>>> ProgressBar(10, label="resumed", initial=6, enabled=False).line().split("]")[1].split()[:2]
['6/10', '60%']
"""

from __future__ import annotations

import sys
import time
from typing import IO

__all__ = ["ProgressBar", "format_duration", "progress_enabled"]


def format_duration(seconds: float) -> str:
    """``H:MM:SS`` (``--:--:--`` when unknown).

    >>> format_duration(3725.2), format_duration(float("inf"))
    ('1:02:05', '--:--:--')
    """
    if not seconds >= 0 or seconds == float("inf"):
        return "--:--:--"
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


def progress_enabled(progress: bool | None) -> bool:
    """``progress`` of the library calls: False shows nothing; True or None show the
    display (a live bar on a terminal, a few plain lines elsewhere)."""
    return progress is not False


class ProgressBar:
    """Items done / total, rate, time left.

    Parameters
    ----------
    total : int
        Items of the whole task (those done before this session included).
    label : str
        Shown first on the line.
    stream : file, optional
        Default ``sys.stderr``.
    enabled : bool
        When False, nothing is written but :meth:`notice` lines.
    tty : bool, optional
        Redraw in place; default: whether ``stream`` is a terminal.
    interval_s : float, optional
        Minimum time between two writes (default 0.1 s on a terminal, 30 s
        otherwise); the last line is always written.
    width : int
        Characters of the bar itself.
    initial : int
        Items already done before this session (a resumed sweep): counted in
        ``done / total`` but not in the rate.
    unit : str
        What is counted, plural (``runs``, ``episodes``, ``lines``).
    """

    def __init__(self, total: int, label: str = "", stream: IO[str] | None = None,
                 enabled: bool = True, tty: bool | None = None, interval_s: float | None = None,
                 width: int = 24, initial: int = 0, unit: str = "runs") -> None:
        self.total = max(0, int(total))
        self.initial = max(0, int(initial))
        self.label = label
        self.unit = unit
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        if tty is None:
            isatty = getattr(self.stream, "isatty", None)
            tty = bool(isatty and isatty())
        self.tty = tty
        self.interval_s = (0.1 if tty else 30.0) if interval_s is None else interval_s
        self.width = width
        self.done = self.initial
        self.errors = 0
        self.t0 = time.perf_counter()
        self._first: tuple[float, int] | None = None  # (time, done) at the first update
        self._updates = 0
        self._last = time.perf_counter() if not tty else -1e9
        self._closed = False
        if self.enabled and self.tty:
            self._write(time.perf_counter(), force=True)

    def start(self) -> None:
        """Restart the clock (after a set-up phase that should not count)."""
        self.t0 = time.perf_counter()
        if not self.tty:  # the first plain line comes interval_s after the start
            self._last = self.t0
        if self.enabled and self.tty:
            self._write(self.t0, force=True)

    def update(self, n: int = 1, errors: int = 0) -> None:
        """Count ``n`` more finished items (``errors`` of them raised)."""
        now = time.perf_counter()
        if self._first is None:
            self._first = (now, self.done)
        self.done += n
        self.errors += errors
        self._updates += 1
        if now - self._last >= self.interval_s:
            self._write(now)

    def rate(self, now: float) -> float | None:
        """Items per second since the first finished one (None until known)."""
        if self._first is None or self._updates < 2:
            return None
        t1, d1 = self._first
        if now - t1 <= 0:
            return None
        return (self.done - d1) / (now - t1)

    def line(self, now: float | None = None, final: bool = False) -> str:
        """The current status line."""
        now = time.perf_counter() if now is None else now
        frac = self.done / self.total if self.total else 1.0
        fill = int(round(frac * self.width))
        bar = "#" * fill + "-" * (self.width - fill)
        w = len(str(self.total))
        err = f"  {self.errors} err" if self.errors else ""
        rate = self.rate(now)
        if final:
            ran, el = self.done - self.initial, now - self.t0
            rate = rate if rate is not None else (ran / el if ran and el > 0 else None)
            per = f"  {rate:.1f} {self.unit}/s" if rate else ""
            tail = f"{per}  in {format_duration(now - self.t0)}"
        elif rate is None:
            tail = "  starting"
        else:
            left = (self.total - self.done) / rate if rate > 0 else float("inf")
            tail = f"  {rate:.1f} {self.unit}/s  ETA {format_duration(left)}"
        return (f"{self.label} [{bar}] {self.done:>{w}}/{self.total} {100 * frac:3.0f}%"
                f"{tail}{err}").lstrip()

    def _write(self, now: float, force: bool = False, final: bool = False) -> None:
        if not self.enabled or self._closed:
            return
        self._last = now
        text = self.line(now, final=final)
        if self.tty:
            self.stream.write("\r" + text + "\x1b[K")
        else:
            self.stream.write(text + "\n")
        self.stream.flush()

    def notice(self, text: str) -> None:
        """Write one line (``pathfuse: TEXT``) above the bar, even when the bar is off."""
        live = self.tty and self.enabled and not self._closed
        self.stream.write(("\r\x1b[K" if live else "") + f"pathfuse: {text}\n")
        if live:
            self.stream.write(self.line() + "\x1b[K")
        self.stream.flush()

    def close(self) -> None:
        """Write the last line (and end it with a newline on a terminal)."""
        if self._closed:
            return
        self._write(time.perf_counter(), final=True)
        if self.enabled and self.tty:
            self.stream.write("\n")
            self.stream.flush()
        self._closed = True
