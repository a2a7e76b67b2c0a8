"""Shorter and rounder free motions: shortcuts and corner blends, every new state checked.

A time-optimal timing must stop wherever a path turns sharply (the joint-space path has
a kink, and the speed through a kink is zero), so the paths are improved before they
are timed:

* **Shortcuts**: two waypoints picked at random (seeded) are joined by a straight line
  in the stance space when it is checked free and shorter; repeated a few times. Via
  detours and OMPL's zig-zags shrink.
* **Corner blends**: at each remaining corner (the direction turns by more than
  ``CORNER_DEG``), the waypoints within a window on either side are replaced by a
  quadratic Bezier curve in stance coordinates from the window's first waypoint, with
  the corner as its control point, to its last; if a new state is invalid the window
  is halved. This also rounds the corner where a vertical lift meets a free motion, so
  the robot does not stop above the table: blends may reach into the upper part of an
  approach or release (``keep`` says which waypoints must stay), never into its lower part.

Lengths are time-like: sum over steps of max_j |dq_j| / v_j (s at the velocity limits).
"""

from __future__ import annotations

from typing import TypeVar

import numpy as np

from posegen.robot import FloatArray, StanceSpace
from posegen.route.motion import follow, straight

CORNER_DEG = 10.0  # a turn sharper than this between two steps is a corner
BLEND_WINDOW = 12  # waypoints on either side of a corner that a blend may replace, at most
SHORTCUT_TRIES = 24  # random shortcut attempts per free motion
SHORTCUT_GAIN = 0.95  # try a shortcut only if its straight line is this much shorter at least

L = TypeVar("L")  # a waypoint label


def path_length(path: list[FloatArray] | FloatArray, velocity_limit: FloatArray) -> float:
    """Time-like length of a path (s at the velocity limits)."""
    points = np.asarray(path)
    if len(points) < 2:
        return 0.0
    return float(np.sum(np.max(np.abs(np.diff(points, axis=0)) / velocity_limit, axis=1)))


def shortcut(
    space: StanceSpace, path: list[FloatArray], rng: np.random.Generator, tries: int = SHORTCUT_TRIES
) -> list[FloatArray]:
    """Join random pairs of waypoints by checked straight lines when that is shorter.

    Args:
        space: The stance space.
        path: Checked waypoints; its ends stay.
        rng: Picks the pairs (seed it per path for repeatable results).
        tries: Number of pairs tried.

    """
    limit = space.scene.velocity_limit
    path = list(path)
    for _ in range(tries):
        if len(path) < 3:
            break
        i, j = sorted(int(k) for k in rng.choice(len(path), 2, replace=False))
        if j - i < 2:
            continue
        old = path_length(path[i : j + 1], limit)
        if float(np.max(np.abs(path[j] - path[i]) / limit)) > SHORTCUT_GAIN * old:
            continue
        leg = straight(space, path[i], path[j])
        if leg is not None and path_length(leg, limit) < old:
            path = path[:i] + leg + path[j + 1 :]
    return path


def corners(path: list[FloatArray], velocity_limit: FloatArray) -> list[int]:
    """Indices of the waypoints where the path turns by more than CORNER_DEG (ends excluded)."""
    steps = np.diff(np.asarray(path) / velocity_limit, axis=0)
    norms = np.linalg.norm(steps, axis=1)
    found = []
    for k in range(1, len(path) - 1):
        if norms[k - 1] > 1e-12 and norms[k] > 1e-12:
            cosine = float(steps[k - 1] @ steps[k]) / (norms[k - 1] * norms[k])
            if cosine < np.cos(np.deg2rad(CORNER_DEG)):
                found.append(k)
    return found


def blend_corners(
    space: StanceSpace, path: list[FloatArray], keep: list[bool], labels: list[L], fill: L
) -> tuple[list[FloatArray], list[bool], list[L]]:
    """Round every corner that lies in a stretch of waypoints that may change.

    Args:
        space: The stance space.
        path: Checked waypoints.
        keep: Per waypoint, whether it must stay (a blend never replaces it, and a
            corner on it is left as it is).
        labels: Per waypoint, a label carried along (e.g. the segment type).
        fill: The label of the waypoints a blend creates.

    Returns:
        The new waypoints, their ``keep`` flags and their labels.

    """
    path, keep, labels = list(path), list(keep), list(labels)
    for k in reversed(corners(path, space.scene.velocity_limit)):  # from the end: earlier indices stay valid
        if k >= len(path) - 1 or keep[k]:  # past the end: a later blend of fewer waypoints took this corner in
            continue
        before = next((i for i in range(k - 1, -1, -1) if keep[i]), -1)  # the window may reach, not pass, a kept point
        after = next((i for i in range(k + 1, len(path)) if keep[i]), len(path))
        w1, w2 = min(BLEND_WINDOW, k - max(before, 0)), min(BLEND_WINDOW, min(after, len(path) - 1) - k)
        while w1 >= 1 and w2 >= 1:
            curve = _bezier(space, path[k - w1], path[k], path[k + w2])
            if curve is not None:
                path = path[: k - w1] + curve + path[k + w2 + 1 :]
                inner = len(curve) - 2
                keep = keep[: k - w1 + 1] + [False] * inner + keep[k + w2 :]
                labels = labels[: k - w1 + 1] + [fill] * inner + labels[k + w2 :]
                break
            w1, w2 = w1 // 2, w2 // 2
    return path, keep, labels


def _bezier(space: StanceSpace, first: FloatArray, corner: FloatArray, last: FloatArray) -> list[FloatArray] | None:
    """Checked waypoints of the quadratic Bezier first -> last with control point ``corner``."""
    a, c, b = space.coordinates_of(first), space.coordinates_of(corner), space.coordinates_of(last)

    def curve(t: float) -> FloatArray:
        return np.asarray((1 - t) ** 2 * a + 2 * t * (1 - t) * c + t**2 * b)

    length = float(np.max(np.abs(c - a)) + np.max(np.abs(b - c)))  # the control polygon bounds the curve's length
    return follow(space, curve, length, first, last)
