"""Array types every layer shares, defined once at the bottom (below :mod:`posegen.io` and :mod:`posegen.robot`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.floating[Any]]  # any shape: the shape is given where it is used, in a comment

__all__ = ["FloatArray"]
