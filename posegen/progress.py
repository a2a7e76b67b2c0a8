"""The one way long work reports how far it has come: a callback taking a :class:`Progress`.

Stages call it; only :mod:`posegen.cli` draws it (a progress bar on stderr).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass


@dataclass(frozen=True)
class Progress:
    """One report of long work."""

    done: int  # units finished so far
    total: int  # units to finish
    unit: str  # what a unit is: "posture", "point", "step"
    step: str = ""  # the step under way, where the work has named steps
    attempts: int | None = None  # tries so far, where a try may finish no unit (pool samples)


ProgressCallback = Callable[[Progress], None]


def ignore_progress(_: Progress) -> None:
    """A progress callback that reports nowhere (the default of every stage)."""


class Steps:
    """Named steps of a known number, reported as progress: each call starts the next step."""

    def __init__(self, total: int, progress: ProgressCallback) -> None:
        self.total = total
        self.done = 0
        self._progress = progress

    def __call__(self, step: str) -> None:
        """Report that ``step`` starts."""
        self.done += 1
        self._progress(Progress(self.done, self.total, "step", step))
