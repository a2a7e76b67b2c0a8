"""Progress bars on stderr: the command line's rendering of a stage's progress callback."""

from __future__ import annotations

import sys
from types import TracebackType
from typing import Any

from posegen.progress import Progress


class ProgressBar:
    """A progress callback that draws a bar on stderr (nothing with ``quiet``).

    The bar starts at the first report, which gives its total and unit.
    """

    def __init__(self, quiet: bool) -> None:
        self.quiet = quiet
        self._bar: Any = None

    def __call__(self, progress: Progress) -> None:
        """Show a report."""
        if self._bar is None:
            from tqdm import tqdm

            self._bar = tqdm(
                total=progress.total, unit=progress.unit, disable=self.quiet, file=sys.stderr, dynamic_ncols=True
            )
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
