"""A tiny progress bar for sweeps (stderr; no third-party dependency).

On a terminal it redraws one line in place::

    fusion-sweep [##########----------]  512/1024  50%  41.3 runs/s  ETA 0:00:12  3 err

Elsewhere (a log file, CI) it prints a plain line at most every
``interval_s`` seconds and at the end, so logs stay short.

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

__all__ = ["ProgressBar", "format_duration"]


def format_duration(seconds: float) -> str:
    """``H:MM:SS`` (``--:--:--`` when unknown).

    >>> format_duration(3725.2), format_duration(float("inf"))
    ('1:02:05', '--:--:--')
    """
    if not seconds >= 0 or seconds == float("inf"):
        return "--:--:--"
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


class ProgressBar:
    """Runs done / total, rate, time left.

    Parameters
    ----------
    total : int
        Runs to do in this session.
    label : str
        Shown first on the line.
    stream : file, optional
        Default ``sys.stderr``.
    enabled : bool
        When False, nothing is written.
    tty : bool, optional
        Redraw in place; default: whether ``stream`` is a terminal.
    interval_s : float
        Minimum time between two writes (the final line is always written).
    width : int
        Characters of the bar itself.
    initial : int
        Runs already done before this session (a resumed sweep): counted in
        ``done / total`` but not in the rate.
    """

    def __init__(self, total: int, label: str = "", stream: IO[str] | None = None,
                 enabled: bool = True, tty: bool | None = None, interval_s: float | None = None,
                 width: int = 24, initial: int = 0) -> None:
        self.total = max(0, int(total))
        self.initial = max(0, int(initial))
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        if tty is None:
            isatty = getattr(self.stream, "isatty", None)
            tty = bool(isatty and isatty())
        self.tty = tty
        self.interval_s = (0.1 if tty else 10.0) if interval_s is None else interval_s
        self.width = width
        self.done = self.initial
        self.errors = 0
        self.t0 = time.perf_counter()
        self._last = -1e9
        self._closed = False

    def update(self, n: int = 1, errors: int = 0) -> None:
        """Count ``n`` more finished runs (``errors`` of them raised)."""
        self.done += n
        self.errors += errors
        now = time.perf_counter()
        if now - self._last >= self.interval_s:
            self._write(now)

    def line(self, now: float | None = None) -> str:
        """The current status line."""
        now = time.perf_counter() if now is None else now
        el = max(now - self.t0, 1e-9)
        rate = (self.done - self.initial) / el
        left = (self.total - self.done) / rate if rate > 0 else float("inf")
        frac = self.done / self.total if self.total else 1.0
        fill = int(round(frac * self.width))
        bar = "#" * fill + "-" * (self.width - fill)
        w = len(str(self.total))
        err = f"  {self.errors} err" if self.errors else ""
        return (f"{self.label} [{bar}] {self.done:>{w}}/{self.total} {100 * frac:3.0f}%  "
                f"{rate:.1f} runs/s  ETA {format_duration(left)}{err}").lstrip()

    def _write(self, now: float) -> None:
        if not self.enabled or self._closed:
            return
        self._last = now
        text = self.line(now)
        if self.tty:
            self.stream.write("\r" + text + "\x1b[K")
        else:
            self.stream.write(text + "\n")
        self.stream.flush()

    def notice(self, text: str) -> None:
        """Write one line (``pathfuse: TEXT``) above the bar, even when the bar is off."""
        prefix = "\r\x1b[K" if self.tty and self.enabled and not self._closed else ""
        self.stream.write(f"{prefix}pathfuse: {text}\n")
        self.stream.flush()
        self._last = -1e9  # redraw the bar at the next update

    def close(self) -> None:
        """Write the final line (and end it with a newline on a terminal)."""
        if self._closed:
            return
        self._write(time.perf_counter())
        if self.enabled and self.tty:
            self.stream.write("\n")
            self.stream.flush()
        self._closed = True
