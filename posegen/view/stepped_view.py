"""Views shown one step at a time (a posture, a contact): a second each in a page, a slider live."""

from __future__ import annotations

import abc
import logging
from collections.abc import Iterator

import viser

LOG = logging.getLogger(__name__)
STEP_S = 1.0  # playback time per step in the HTML page: second k of the playback bar is step k


class SteppedView(abc.ABC):
    """A view that steps through ``steps`` items, each shown by :meth:`show` and told by :meth:`describe`."""

    STEP_NAME = "step"  # what the live viewer's slider is called

    def __init__(self, server: viser.ViserServer) -> None:
        self._server = server

    @property
    @abc.abstractmethod
    def steps(self) -> int:
        """Number of steps."""

    @abc.abstractmethod
    def show(self, k: int) -> None:
        """Show step ``k``."""

    @abc.abstractmethod
    def describe(self, k: int) -> str:
        """Step ``k`` in words: fields separated by `` | `` (and line breaks)."""

    def frames(self) -> Iterator[float]:
        """Show each step in turn; yield the playback time (s) it stays on screen."""
        for k in range(self.steps):
            self.show(k)
            yield STEP_S

    def add_controls(self) -> None:
        """A slider over the steps and the current step's fields, for the live viewer."""
        gui = self._server.gui
        slider = gui.add_slider(self.STEP_NAME, min=0, max=max(self.steps - 1, 1), step=1, initial_value=0)
        text = gui.add_markdown("")

        def update(_: object = None) -> None:
            k = min(int(slider.value), self.steps - 1)
            self.show(k)
            text.content = self.describe(k).replace("\n", " | ").replace(" | ", "  \n")  # one field a line

        slider.on_update(update)
        update()

    def close(self) -> None:
        """Nothing runs by itself in a stepped view: nothing to stop."""
        LOG.debug("%s closed", type(self).__name__)
