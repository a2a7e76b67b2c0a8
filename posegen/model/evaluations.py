"""A calibration model's evaluations at one set of observations, the last few remembered.

A fit asks for the same point more than once: the point where one fit ends is where
its noise is re-estimated (residuals and Jacobian), and where the next fit, at the new
noise, starts. The model's residuals and derivatives do not depend on the noise (only
their whitening does), so the evaluation there is made once. What is returned is the
model's own evaluation, read-only: the same numbers as evaluating again.
"""

from __future__ import annotations

import collections

import numpy as np

from posegen.model.calibration_model import CalibrationModel, Evaluation, Observations
from posegen.robot import FloatArray

REMEMBERED = 4  # evaluations kept: a fit's last point and its Jacobian, and the next fit's start


class Evaluations:
    """:meth:`CalibrationModel.evaluate` at ``observations``, the last ``remembered`` results kept.

    Example:
        >>> evaluations = Evaluations(model, observations)
        >>> evaluations.evaluate(x, jacobian=True).contact_jacobian  # (n, 3, nx), made once per x

    """

    def __init__(self, model: CalibrationModel, observations: Observations, remembered: int = REMEMBERED) -> None:
        self.model = model
        self.observations = observations
        self._remembered = remembered
        self._found: collections.OrderedDict[tuple[bytes, bool, bool], Evaluation] = collections.OrderedDict()

    def evaluate(self, x: FloatArray, jacobian: bool = False, floor: bool = True) -> Evaluation:
        """The model's evaluation at parameters ``x`` (nx,): a remembered one if ``x`` is the same bytes."""
        key = (np.ascontiguousarray(x, dtype=float).tobytes(), jacobian, floor)
        found = self._found.get(key)
        if found is not None:
            self._found.move_to_end(key)
            return found
        found = self.model.evaluate(x, self.observations, jacobian=jacobian, floor=floor)
        for array in (found.contact, found.floor, found.contact_jacobian, found.floor_jacobian):
            array.flags.writeable = False  # shared by every caller at this x
        self._found[key] = found
        if len(self._found) > self._remembered:
            self._found.popitem(last=False)
        return found
