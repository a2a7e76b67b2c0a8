"""The fields of a route file's header, typed: each one wrong said with its place in the header.

Used by :func:`posegen.io.route_file.read_route` only (its one reader); the messages name
the field (``segments[3].first_point``, ``trajectory.points[7].time_from_start``) and show
the value found, short.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np


def shown(value: Any) -> str:
    """A value as a message shows it: short."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def joint_name_list(names: Any) -> tuple[str, ...]:
    """The trajectory's joint names: a list of distinct names.

    Raises:
        TypeError, ValueError: Not a list of names, or a name given twice.

    """
    if not isinstance(names, list) or not all(isinstance(name, str) and name for name in names):
        raise TypeError(f"trajectory.joint_names must be a list of joint names, not {shown(names)}")
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ValueError(f"trajectory.joint_names: joint {twice[0]!r} is named twice")
    return tuple(names)


def is_number(value: Any) -> bool:
    """Whether ``value`` is a number (a bool is not)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def index_field(value: Any, where: str) -> int | None:
    """An index or None (a bool, a fraction or a negative number is not an index).

    Raises:
        TypeError: Not an index (``where`` named).

    """
    if value is None:
        return None
    if not is_number(value) or not np.isfinite(value) or int(value) != value or value < 0:
        raise TypeError(f"{where} must be an index (a whole number from 0), not {shown(value)}")
    return int(value)


def inline_arrays(points: Any, names: Sequence[str]) -> dict[str, np.ndarray]:
    """A version-1 route's inline points as arrays: ``time_from_start`` and ``names`` (numbers, rows of one length).

    Raises:
        TypeError, ValueError: A point that is not numbers, or rows of unequal length (the field named).

    """
    if not isinstance(points, list) or not all(isinstance(p, dict) for p in points):
        raise TypeError(f"trajectory.points must be a list of points, not {shown(points)}")
    times = []
    for k, point in enumerate(points):
        stamp = point.get("time_from_start")
        parts: list[Any] = [stamp.get(key) for key in ("sec", "nanosec")] if isinstance(stamp, dict) else [None]
        if not all(is_number(v) for v in parts):
            raise TypeError(f"trajectory.points[{k}].time_from_start must be {{sec, nanosec}}, not {shown(stamp)}")
        times.append(parts[0] + parts[1] * 1e-9)
    arrays = {"time_from_start": np.array(times, dtype=float)}
    for name in names:
        rows = [point.get(name) for point in points]
        if not all(isinstance(row, list) and all(is_number(v) for v in row) for row in rows):
            raise TypeError(f"trajectory.points: every point's {name} must be a list of numbers")
        if len({len(row) for row in rows}) > 1:
            raise ValueError(f"trajectory.points: the points' {name} are not all of one length")
        arrays[name] = np.array(rows, dtype=float)
    return arrays
