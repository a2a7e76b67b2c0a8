"""Writing a route: the ROS 2 ``JointTrajectory`` file with segment annotations, and a CSV.

The file format is described, and read back, in :mod:`posegen.robot.trajectory` (below
the stages, so that any of them may read a route). YAML, or JSON when the file name ends
in ``.json``. The CSV beside it has one row per point: time (s), segment, chain,
posture, then the joint positions (rad).
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

import numpy as np

from posegen.io import dump_yaml, write_atomic
from posegen.robot import ROUTE_FORMAT, ROUTE_VERSION
from posegen.route.route import Route


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
