"""Route files: a YAML header with segment annotations, and the points in a binary sidecar.

Written by :mod:`posegen.route`; read here, below the stages, by whoever needs a
route (its check, exporters, viewers, a rehearsal on a simulated robot).

The header is YAML (or JSON when the file name ends in ``.json``); the trajectory points
(a ROS 2 ``trajectory_msgs/JointTrajectory``'s, as arrays) are in a NumPy ``.npz`` beside
it, named and hashed in the header (:mod:`posegen.io.arrays`)::

    format: posegen-route
    format_version: 2
    provenance: {posegen_version, robot_model_sha256, seed, config, selection, selection_sha256, pool, ...}
    trajectory:                 # trajectory_msgs/msg/JointTrajectory without its points
      header: {stamp: {sec: 0, nanosec: 0}, frame_id: ""}
      joint_names: [...]
      points: 6677              # how many points the sidecar holds
    segments: [{type: free|approach|go_to_contact|hold|release, chain, posture, pool_id,
                first_point, last_point, start_s, end_s}, ...]
    postures: [...]             # the routed postures, as in the selection (or pool), in visiting order
    skipped: [{posture, pool_id, reason}, ...]
    substitutions: [{posture, pool_id, reason, substitute_pool_id, gain, o1_before, o1_after, ...}, ...]
    summary: {...}
    arrays: {file: route.npz, sha256: ...}

The sidecar's arrays: ``time_from_start`` (m,) float64 s; ``positions``, ``velocities``,
``accelerations`` (m, nj) float32 in rad, rad/s, rad/s^2, columns in ``joint_names``
order. float32 rounds a joint angle by at most 2.4e-7 rad (|q| < 4 rad), 50 times finer
than a 19-bit encoder, and halves the file; velocities are stored on a 2^-20 rad/s grid
and accelerations on a 2^-16 rad/s^2 grid, rounded toward zero (never past a limit),
which deflate stores in fewer bytes. The 2-D arrays are column-major. Consecutive segments share their boundary
point. A controller switches to force control at ``go_to_contact`` segments.

Format version 1 (points inline in the YAML, ``time_from_start: {sec, nanosec}``) is
still read.
"""

from __future__ import annotations

import enum
import json
from pathlib import Path
from typing import Any

import numpy as np

from posegen.errors import InputError, reason
from posegen.io import read_arrays, read_text_file, read_yaml
from posegen.robot.geometry import FloatArray

ROUTE_FORMAT = "posegen-route"
ROUTE_VERSION = 2
ROUTE_ARRAYS = ("time_from_start", "positions", "velocities", "accelerations")
POSITION_DTYPE = np.float32  # positions, velocities and accelerations in the sidecar
TIME_DTYPE = np.float64
VELOCITY_STEP = 2.0**-20  # rad/s (~1e-6): stored velocities are multiples of it, rounded toward zero
ACCELERATION_STEP = 2.0**-16  # rad/s^2 (~1.5e-5): the same for accelerations
READ_VERSIONS = (1, 2)
MIN_STEP_S = 1e-6  # smallest time step a reader accepts (posegen check's --min-dt is the controller's, 1 ms)
MAX_DURATION_S = 1e6  # longest route a reader accepts (11.6 days): times fit a rosbag2 clock in ns


class SegmentType(str, enum.Enum):
    """What the robot does during a segment."""

    FREE = "free"  # away from the table, full (scaled) speed
    APPROACH = "approach"  # down from the approach posture to just above the table
    GO_TO_CONTACT = "go_to_contact"  # through the contact to the overshoot: switch to force control
    HOLD = "hold"  # in contact
    RELEASE = "release"  # back up to the approach posture

    @property
    def in_contact(self) -> bool:
        """Whether the fingertips may touch the table in this segment."""
        return self in (SegmentType.GO_TO_CONTACT, SegmentType.HOLD, SegmentType.RELEASE)


def read_route(path: str | Path) -> dict[str, Any]:
    """Read a route file's header and its points.

    The points are returned as arrays under the key ``point_arrays`` (see :data:`ROUTE_ARRAYS`), as
    stored: their consistency (lengths, finite values, times) is what
    ``posegen check`` verifies, not this reader.

    Raises:
        InputError: Missing or malformed header, not a route, a missing sidecar or one
            whose hash differs from the header's.

    """
    path = Path(path)
    if path.suffix.lower() == ".json":
        try:
            data = json.loads(read_text_file(path, InputError))
        except (json.JSONDecodeError, RecursionError) as exc:
            raise InputError(f"{path}: not valid JSON ({reason(exc)})") from exc
        if not isinstance(data, dict) or data.get("format") != ROUTE_FORMAT:
            raise InputError(f"{path}: not a {ROUTE_FORMAT} file")
    else:
        data = read_yaml(path, ROUTE_FORMAT)
    try:
        if not isinstance(data.get("provenance") or {}, dict):
            raise TypeError("provenance must be a mapping")
        trajectory = data["trajectory"]
        if not all(isinstance(name, str) for name in trajectory["joint_names"]):
            raise TypeError("joint_names must be a list of names")
        for seg in data["segments"]:
            SegmentType(seg["type"])
            int(seg["first_point"])
            int(seg["last_point"])
            if not all(np.isfinite(float(seg[k])) for k in ("start_s", "end_s")):
                raise ValueError(f"segment times must be finite numbers, not {seg['start_s']}, {seg['end_s']}")
        version = data.get("format_version", 1)
        if version not in READ_VERSIONS or isinstance(version, bool):
            raise InputError(f"{path}: format_version {version!r}: this posegen reads versions 1 and 2")
        if version == 2:
            points = trajectory["points"]
            if not isinstance(points, int) or isinstance(points, bool) or points < 0:
                raise ValueError(f"trajectory.points must be a count, not {points!r}")
            arrays = read_arrays(path, data.get("arrays"), ROUTE_ARRAYS, rows=points)
        else:
            arrays = _inline_arrays(trajectory["points"])
    except (KeyError, TypeError, ValueError, IndexError, OverflowError, AttributeError) as exc:
        raise InputError(f"{path}: malformed route ({reason(exc)})") from exc
    data["point_arrays"] = arrays
    return data


def _inline_arrays(points: list[dict[str, Any]]) -> dict[str, np.ndarray]:
    """Arrays of a version-1 route's inline points (rows of unequal length are an error)."""
    times = [p["time_from_start"]["sec"] + p["time_from_start"]["nanosec"] * 1e-9 for p in points]
    return {
        "time_from_start": np.array(times, dtype=float),
        "positions": np.array([p["positions"] for p in points], dtype=float),
        "velocities": np.array([p["velocities"] for p in points], dtype=float),
        "accelerations": np.array([p["accelerations"] for p in points], dtype=float),
    }


def is_route_file(path: str | Path) -> bool:
    """Whether a file is a route (by its suffix or its ``format`` field), not a pool.

    Raises:
        InputError: The file cannot be read.

    """
    path = Path(path)
    head = read_text_file(path, InputError)[:4096]
    return path.suffix.lower() == ".json" or f"format: {ROUTE_FORMAT}" in head


def route_arrays(data: dict[str, Any], where: str = "route") -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Times (m,), positions, velocities and accelerations (m, nj) of a read route, as C-ordered float64.

    For the route's users (viewer, exporter, rehearsal); ``posegen check`` reads
    ``point_arrays`` itself, to report what is wrong with them rather than refuse them.

    Raises:
        InputError: The arrays disagree in shape with each other or the joint names, or a
            segment points outside them.

    """
    arrays = data["point_arrays"]
    try:
        times, positions, velocities, accelerations = (
            np.ascontiguousarray(arrays[name], dtype=float) for name in ROUTE_ARRAYS
        )
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: point arrays that are not numbers ({reason(exc)})") from exc
    shape = (len(times), len(data["trajectory"]["joint_names"]))
    if times.ndim != 1 or any(a.shape != shape for a in (positions, velocities, accelerations)):
        raise InputError(f"{where}: point arrays of inconsistent shapes (expected {shape[0]} points of {shape[1]})")
    problem = points_problem(times, (positions, velocities, accelerations), data["segments"])
    if problem:
        raise InputError(f"{where}: {problem} (posegen check tells more)")
    return times, positions, velocities, accelerations


def points_problem(times: FloatArray, arrays: tuple[FloatArray, ...], segments: list[dict[str, Any]]) -> str:
    """What makes a route's points unusable by any reader ("" if nothing): the readers' rules.

    Every value finite; times from 0, strictly increasing by at least :data:`MIN_STEP_S`,
    within :data:`MAX_DURATION_S`; a segment table that covers the points from first to
    last, each segment starting where the previous one ends.

    Args:
        times: (m,) s.
        arrays: Positions, velocities, accelerations, each (m, nj).
        segments: The header's segment table.

    """
    m = len(times)
    if m == 0:
        return "the route has no point"
    for name, values in zip(("time_from_start", *ROUTE_ARRAYS[1:]), (times, *arrays), strict=True):
        bad = np.flatnonzero(~np.isfinite(values).reshape(m, -1).all(axis=1))
        if len(bad):
            return f"{name} at point {bad[0]} is not a finite number"
    steps = np.diff(times)
    if times[0] != 0.0 or (len(steps) and steps.min() < MIN_STEP_S) or times[-1] > MAX_DURATION_S:
        k = int(np.argmin(steps)) + 1 if len(steps) and steps.min() < MIN_STEP_S else (0 if times[0] else m - 1)
        return (
            f"time_from_start at point {k} is {times[k]} s: times start at 0, increase by at least "
            f"{MIN_STEP_S:g} s and end within {MAX_DURATION_S:g} s"
        )
    if not segments:
        return "the segment table is empty"
    expected = 0
    for i, seg in enumerate(segments):
        first, last = int(seg["first_point"]), int(seg["last_point"])
        if first != expected or not first <= last < m:
            return f"segment {i} covers points {first}..{last}: expected it to start at {expected}, end before {m}"
        expected = last
    if expected != m - 1:
        return f"the segments end at point {expected}, the route's last point is {m - 1}"
    return ""


def stamp(seconds: float) -> dict[str, int]:
    """A ROS ``builtin_interfaces/Duration`` {sec, nanosec} of a time in seconds."""
    sec = int(np.floor(seconds))
    nanosec = round((seconds - sec) * 1e9)
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return {"sec": sec, "nanosec": nanosec}
