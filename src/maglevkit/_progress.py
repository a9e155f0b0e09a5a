"""Progress of long computations: a rich bar on a terminal, plain lines in logs.

On a terminal (stderr is a tty) a transient rich progress bar is drawn on stderr.  Off a
terminal (pipes, log files, CI) rich draws nothing, so long runs would be silent; there
the reporter writes plain lines to stderr instead::

    transient maps: 40/160 (25 %), 61 s elapsed, ETA 183 s

one each time another ``percent_step`` (10 %) of the tasks is done, but at most one per
``min_interval_s`` (1 s; short runs stay quiet), and at least one per ``max_interval_s``
(10 s) while tasks keep finishing; a final ``... done in ... s`` line closes the run.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from types import TracebackType
from typing import IO, Any

__all__ = ["ProgressReporter"]


class ProgressReporter:
    """Report the progress of ``total`` tasks (a context manager; call :meth:`advance`).

    Parameters
    ----------
    total : int
        Number of tasks.
    label : str
        What is computed (the start of every line).
    stream : file-like, optional
        Where to report; default ``sys.stderr`` at the time of the call.
    tty : bool, optional
        Draw the rich bar (True) or write plain lines (False); default: whether
        ``stream`` is a terminal.
    percent_step : float
        Plain mode: a line per this many percent of the tasks [%].
    min_interval_s, max_interval_s : float
        Plain mode: at most / at least (while tasks finish) one line per interval [s].
    clock : callable
        Time source [s] (monotonic; for tests).
    """

    def __init__(self, total: int, label: str, *, stream: IO[str] | None = None,
                 tty: bool | None = None, percent_step: float = 10.0,
                 min_interval_s: float = 1.0, max_interval_s: float = 10.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.total = max(int(total), 0)
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        if tty is None:
            isatty = getattr(self.stream, "isatty", None)
            tty = bool(isatty()) if callable(isatty) else False
        self.tty = tty
        self.percent_step = percent_step
        self.min_interval_s = min_interval_s
        self.max_interval_s = max_interval_s
        self.clock = clock
        self.done = 0
        self._start = clock()
        self._last_line = self._start
        self._next_percent = percent_step
        self._lines = 0
        self._bar: Any = None
        self._task: Any = None

    # ------------------------------------------------------------------ context
    def __enter__(self) -> ProgressReporter:
        self._start = self._last_line = self.clock()
        if self.tty:
            from rich.console import Console
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            self._bar = Progress(TextColumn("{task.description}", markup=False), BarColumn(),
                                 MofNCompleteColumn(), TimeElapsedColumn(),
                                 TextColumn("ETA"), TimeRemainingColumn(),
                                 console=Console(file=self.stream), transient=True)
            self._bar.start()
            self._task = self._bar.add_task(self.label, total=self.total)
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if self._bar is not None:
            self._bar.stop()
            self._bar = None
        elif exc_type is None and self.total > 0:
            self._write(f"{self.label}: {self.done}/{self.total} done in "
                        f"{self._fmt(self.clock() - self._start)}")

    # ------------------------------------------------------------------ progress
    def advance(self, n: int = 1) -> None:
        """Mark ``n`` more tasks as done.

        Parameters
        ----------
        n : int, default 1
            Tasks finished since the last call (the count stops at the total).
        """
        self.done = min(self.done + n, self.total)
        if self._bar is not None:
            self._bar.update(self._task, completed=self.done)
            return
        if self.done >= self.total:
            return          # the final line comes from __exit__
        now = self.clock()
        percent = 100.0 * self.done / self.total if self.total else 100.0
        since = now - self._last_line
        due = (percent >= self._next_percent and since >= self.min_interval_s) or \
            since >= self.max_interval_s
        if not due:
            return
        elapsed = now - self._start
        eta = elapsed * (self.total - self.done) / self.done if self.done else float("nan")
        self._write(f"{self.label}: {self.done}/{self.total} ({percent:.0f} %), "
                    f"{self._fmt(elapsed)} elapsed, ETA {self._fmt(eta)}")
        self._last_line = now
        while self._next_percent <= percent:
            self._next_percent += self.percent_step

    @staticmethod
    def _fmt(seconds: float) -> str:
        if seconds != seconds:          # NaN: no task done yet
            return "unknown"
        if seconds < 100.0:
            return f"{seconds:.1f} s"
        minutes, sec = divmod(int(round(seconds)), 60)
        return f"{minutes} min {sec:02d} s"

    def _write(self, line: str) -> None:
        self._lines += 1
        try:
            self.stream.write(line + "\n")
            self.stream.flush()
        except (OSError, ValueError):   # a closed stream must not break the computation
            pass
