"""Route files: a ROS 2 ``trajectory_msgs/JointTrajectory`` with segment annotations.

Written by :mod:`posegen.route`; read here, below the stages, by whoever needs a
route (its check, exporters, viewers, a rehearsal on a simulated robot).

YAML (or JSON when the file name ends in ``.json``)::

    format: posegen-route
    format_version: 1
    provenance: {posegen_version, robot_model_sha256, seed, config, selection, selection_sha256}
    trajectory:                 # trajectory_msgs/msg/JointTrajectory, field for field
      header: {stamp: {sec: 0, nanosec: 0}, frame_id: ""}
      joint_names: [...]
      points: [{positions: [rad], velocities: [rad/s], accelerations: [rad/s^2], effort: [],
                time_from_start: {sec, nanosec}}, ...]
    segments: [{type: free|approach|go_to_contact|hold|release, chain, posture, pool_id,
                first_point, last_point, start_s, end_s}, ...]
    postures: [...]             # the routed postures, as in the selection, in visiting order
    skipped: [{posture, pool_id, reason}, ...]
    summary: {...}

A controller switches to force control at ``go_to_contact`` segments. The CSV beside it
has one row per point: time (s), segment, chain, posture, then the joint positions (rad).
"""

from __future__ import annotations

import enum
import json
from pathlib import Path
from typing import Any

import numpy as np

from posegen.errors import InputError
from posegen.io import read_yaml
from posegen.robot.geometry import FloatArray

ROUTE_FORMAT = "posegen-route"
ROUTE_VERSION = 1


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
    """Read and validate a route file (YAML or JSON).

    Raises:
        InputError: Missing, malformed, or not a route.

    """
    path = Path(path)
    if path.suffix.lower() == ".json":
        try:
            data = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError) as exc:
            raise InputError(f"cannot read route {path}: {exc}") from exc
        if not isinstance(data, dict) or data.get("format") != ROUTE_FORMAT:
            raise InputError(f"{path}: not a {ROUTE_FORMAT} file")
    else:
        data = read_yaml(path, ROUTE_FORMAT)
    try:
        trajectory = data["trajectory"]
        names = trajectory["joint_names"]
        points = trajectory["points"]
        for seg in data["segments"]:
            SegmentType(seg["type"])
            int(seg["first_point"])
            int(seg["last_point"])
        for point in points:
            if len(point["positions"]) != len(names):
                raise ValueError("positions of the wrong length")
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{path}: malformed route ({type(exc).__name__}: {exc})") from exc
    return data


def is_route_file(path: str | Path) -> bool:
    """Whether a file is a route (by its suffix or its ``format`` field), not a pool.

    Raises:
        InputError: The file cannot be read.

    """
    path = Path(path)
    try:
        head = path.read_text()[:4096]
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc.strerror}") from exc
    return path.suffix.lower() == ".json" or f"format: {ROUTE_FORMAT}" in head


def route_arrays(data: dict[str, Any]) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Times (m,), positions, velocities and accelerations (m, nj) of a route's points."""
    points = data["trajectory"]["points"]
    times = np.array([p["time_from_start"]["sec"] + p["time_from_start"]["nanosec"] * 1e-9 for p in points])
    positions = np.array([p["positions"] for p in points], dtype=float)
    velocities = np.array([p["velocities"] for p in points], dtype=float)
    accelerations = np.array([p["accelerations"] for p in points], dtype=float)
    return times, positions, velocities, accelerations
