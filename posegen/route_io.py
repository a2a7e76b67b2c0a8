"""Route files: a ROS 2 ``trajectory_msgs/JointTrajectory`` with segment annotations.

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

import csv
import io
import json
from pathlib import Path
from typing import Any

import numpy as np

from posegen.artefact import dump_yaml, read_yaml, write_atomic
from posegen.errors import InputError
from posegen.geometry import FloatArray
from posegen.route import Route, SegmentType

ROUTE_FORMAT = "posegen-route"
ROUTE_VERSION = 1


def _stamp(seconds: float) -> dict[str, int]:
    sec = int(np.floor(seconds))
    nanosec = round((seconds - sec) * 1e9)
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return {"sec": sec, "nanosec": nanosec}


def route_to_dict(
    route: Route, postures: list[dict[str, Any]], provenance: dict[str, Any], summary: dict[str, Any]
) -> dict[str, Any]:
    """Plain data of a route file.

    Args:
        route: The timed route.
        postures: The input postures' plain data (selection or pool entries).
        provenance: Provenance block.
        summary: Figures to record.

    """

    def pool_id(index: int | None) -> int | None:
        if index is None:
            return None
        return int(postures[index].get("pool_id", postures[index].get("id", index)))

    points = [
        {
            "positions": [float(v) for v in route.positions[k]],
            "velocities": [float(v) for v in route.velocities[k]],
            "accelerations": [float(v) for v in route.accelerations[k]],
            "effort": [],
            "time_from_start": _stamp(float(route.times[k])),
        }
        for k in range(len(route.times))
    ]
    return {
        "format": ROUTE_FORMAT,
        "format_version": ROUTE_VERSION,
        "provenance": provenance,
        "trajectory": {
            "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
            "joint_names": list(route.joint_names),
            "points": points,
        },
        "segments": [
            {
                "type": s.type.value,
                "chain": s.chain,
                "posture": s.posture,
                "pool_id": pool_id(s.posture),
                "first_point": s.first,
                "last_point": s.last,
                "start_s": float(route.times[s.first]),
                "end_s": float(route.times[s.last]),
            }
            for s in route.segments
        ],
        "postures": [postures[i] for i in route.visited],
        "skipped": [{"posture": i, "pool_id": pool_id(i), "reason": reason} for i, reason in route.skipped],
        "summary": summary,
    }


def write_route(path: Path, data: dict[str, Any]) -> Path:
    """Write the route file (YAML or JSON by suffix) and its CSV; return the CSV path."""
    text = json.dumps(data, indent=1) if path.suffix.lower() == ".json" else dump_yaml(data)
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    names = data["trajectory"]["joint_names"]
    writer.writerow(["time_s", "segment", "chain", "posture", *names])
    segment_of = {}
    for seg in data["segments"]:
        for k in range(seg["first_point"], seg["last_point"] + 1):
            segment_of[k] = seg  # a shared boundary point belongs to the later segment
    for k, point in enumerate(data["trajectory"]["points"]):
        seg = segment_of[k]
        stamp = point["time_from_start"]
        time_s = stamp["sec"] + stamp["nanosec"] * 1e-9
        writer.writerow(
            [
                f"{time_s:.9f}",
                seg["type"],
                seg["chain"] or "",
                seg["posture"] if seg["posture"] is not None else "",
                *(repr(v) for v in point["positions"]),
            ]
        )
    csv_path = path.with_suffix(".csv")
    write_atomic(path, text)
    write_atomic(csv_path, buffer.getvalue())
    return csv_path


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


def arrays(data: dict[str, Any]) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Times (m,), positions, velocities and accelerations (m, nj) of a route's points."""
    points = data["trajectory"]["points"]
    times = np.array([p["time_from_start"]["sec"] + p["time_from_start"]["nanosec"] * 1e-9 for p in points])
    positions = np.array([p["positions"] for p in points], dtype=float)
    velocities = np.array([p["velocities"] for p in points], dtype=float)
    accelerations = np.array([p["accelerations"] for p in points], dtype=float)
    return times, positions, velocities, accelerations
