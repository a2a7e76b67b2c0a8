"""Progress on stderr: the command line's rendering of a stage's progress callback.

On a terminal, a progress bar (tqdm). Anywhere else (CI, ``nohup``, a log file), one
plain line at most every :data:`LOG_INTERVAL_S` seconds, and the last report. With
``-q``, nothing.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from types import TracebackType
from typing import Any, TextIO

from posegen.progress import Progress

LOG_INTERVAL_S = 10.0  # at most one progress line this often when stderr is not a terminal


def _line(progress: Progress) -> str:
    percent = f" ({100 * progress.done / progress.total:.0f}%)" if progress.total else ""
    text = f"posegen: {progress.done}/{progress.total} {progress.unit}s{percent}"
    if progress.step:
        text += f": {progress.step}"
    if progress.attempts is not None:
        text += f", {progress.attempts} attempted"
    return text


class ProgressBar:
    """A progress callback that shows reports on ``stream`` (stderr by default).

    Args:
        quiet: Show nothing.
        stream: Where to show them; a terminal gets a bar, anything else plain lines.
        interval_s: Least time between two plain lines (the last report is always shown).
        clock: Seconds, monotonic (a parameter for tests).

    """

    def __init__(
        self,
        quiet: bool,
        stream: TextIO | None = None,
        interval_s: float = LOG_INTERVAL_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.quiet = quiet
        self.stream = stream if stream is not None else sys.stderr
        self.interval_s = interval_s
        self._clock = clock
        self._terminal = not quiet and _is_terminal(self.stream)
        self._bar: Any = None
        self._last_line_s = -math.inf
        self._last: Progress | None = None
        self._shown: Progress | None = None

    def __call__(self, progress: Progress) -> None:
        """Show a report (or not, by the rules above)."""
        if self.quiet:
            return
        if self._terminal:
            self._draw(progress)
            return
        self._last = progress
        now = self._clock()
        if now - self._last_line_s >= self.interval_s or (progress.done >= progress.total and progress != self._shown):
            self._write(progress)
            self._last_line_s = now

    def _write(self, progress: Progress) -> None:
        print(_line(progress), file=self.stream, flush=True)
        self._shown = progress

    def _draw(self, progress: Progress) -> None:
        if self._bar is None:
            from tqdm import tqdm

            self._bar = tqdm(total=progress.total, unit=progress.unit, file=self.stream, dynamic_ncols=True)
        if progress.total != self._bar.total:  # work that grows as it goes (a route's repairs)
            self._bar.total = progress.total
        if progress.step:
            self._bar.set_description(progress.step, refresh=False)
        if progress.attempts is not None:
            self._bar.set_postfix(attempted=progress.attempts, refresh=False)
        self._bar.update(progress.done - self._bar.n)

    def __enter__(self) -> ProgressBar:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        if self._bar is not None:
            self._bar.close()
        elif kind is None and self._last is not None and self._last != self._shown:
            self._write(self._last)  # a log ends with where the work ended


def _is_terminal(stream: TextIO) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False
