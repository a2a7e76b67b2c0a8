"""Writing a route: the YAML header with segment annotations, its ``.npz`` sidecar, optionally a CSV.

The file format is described, and read back, in :mod:`posegen.robot.trajectory` (below
the stages, so that any of them may read a route). The header is YAML, or JSON when the
file name ends in ``.json``; the points go to ``<name>.<sha256 prefix>.npz`` beside it.
The CSV, when asked for, goes to ``<name>.<sha256 prefix of the header>.csv`` (replaced
with the header as one); it has one row per point: time (s), segment, chain, posture,
then the joint positions (rad), as stored.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

import numpy as np

from posegen.io import companion_of, companions_of, write_with_arrays
from posegen.robot import ACCELERATION_STEP, POSITION_DTYPE, ROUTE_FORMAT, ROUTE_VERSION, TIME_DTYPE, VELOCITY_STEP
from posegen.route.route import Route

CSV_SUFFIX = ".csv"  # a route's CSV: ``<name>.<sha256 prefix of the header>.csv``


def route_arrays_of(route: Route) -> dict[str, np.ndarray]:
    """The sidecar's arrays of a route, in their stored types and resolutions (column-major: they compress better)."""
    return {
        "time_from_start": np.asarray(route.times, dtype=TIME_DTYPE),
        "positions": np.asfortranarray(route.positions, dtype=POSITION_DTYPE),
        "velocities": np.asfortranarray(_toward_zero(route.velocities, VELOCITY_STEP), dtype=POSITION_DTYPE),
        "accelerations": np.asfortranarray(_toward_zero(route.accelerations, ACCELERATION_STEP), dtype=POSITION_DTYPE),
    }


def _toward_zero(values: np.ndarray, step: float) -> np.ndarray:
    """Values on a grid of ``step``, rounded toward zero: never past a limit the exact ones respect."""
    return np.asarray(np.trunc(np.asarray(values) / step) * step)


def route_header(
    route: Route,
    entries: dict[int, dict[str, Any]],
    provenance: dict[str, Any],
    summary: dict[str, Any],
) -> dict[str, Any]:
    """Plain data of a route file's header (without the sidecar reference).

    Args:
        route: The timed route.
        entries: The plain data (selection or pool entry) of every node the route
            mentions (visited, skipped, substituted), by node.
        provenance: Provenance block.
        summary: Figures to record.

    """

    def pool_id(node: int | None) -> int | None:
        if node is None:
            return None
        entry = entries[node]
        return int(entry.get("pool_id", entry.get("id", node)))

    return {
        "format": ROUTE_FORMAT,
        "format_version": ROUTE_VERSION,
        "provenance": provenance,
        "trajectory": {
            "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
            "joint_names": list(route.joint_names),
            "points": len(route.times),
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
        "postures": [entries[i] for i in route.visited],
        "skipped": [{"posture": i, "pool_id": pool_id(i), "reason": reason} for i, reason in route.skipped],
        "substitutions": [
            {
                "posture": s.lost,
                "pool_id": pool_id(s.lost),
                "reason": s.reason,
                "substitute_pool_id": s.substitute,
                "log_det_gain": s.gain,
                "o1_before": s.o1_before,
                "o1_after": s.o1_after,
                "rank_before": s.rank_before,
                "rank_after": s.rank_after,
            }
            for s in route.substitutions
        ],
        "summary": summary,
    }


def route_outputs(path: Path) -> list[Path]:
    """The files :func:`write_route` writes or replaces whose names are known before.

    The header, and the companions an older route left there (its CSV, replaced or
    removed with it). The sidecar's name follows its content
    (:func:`posegen.io.sidecar_path`), the CSV's the header's
    (:func:`posegen.io.companion_path`), both beside the header.
    """
    return [path, *companions_of(path, CSV_SUFFIX)]


def write_route(path: Path, route: Route, header: dict[str, Any], csv_too: bool = False) -> list[Path]:
    """Write the route (the deflated sidecar and the CSV if asked first, the header last).

    The CSV is the header's companion, ``<name>.<sha256 prefix of the header>.csv``: it
    is replaced with the header, as one; without ``csv_too`` an older route's CSV is removed.

    Returns:
        The paths written: the header, its sidecar, and the CSV if asked.

    """
    arrays = route_arrays_of(route)
    csv_bytes = _csv(header, arrays).encode() if csv_too else None
    sidecar = write_with_arrays(path, header, arrays, compress=True, companions={CSV_SUFFIX: csv_bytes})
    csv_path = companion_of(path, CSV_SUFFIX) if csv_too else None
    return [path, sidecar, *([csv_path] if csv_path else [])]


def _csv(header: dict[str, Any], arrays: dict[str, np.ndarray]) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(["time_s", "segment", "chain", "posture", *header["trajectory"]["joint_names"]])
    segment_of: dict[int, dict[str, Any]] = {}
    for seg in header["segments"]:
        for k in range(seg["first_point"], seg["last_point"] + 1):
            segment_of[k] = seg  # a shared boundary point belongs to the later segment
    for k, (time_s, positions) in enumerate(zip(arrays["time_from_start"], arrays["positions"], strict=True)):
        seg = segment_of[k]
        posture = seg["posture"] if seg["posture"] is not None else ""
        writer.writerow(
            [f"{time_s:.9f}", seg["type"], seg["chain"] or "", posture, *(repr(float(v)) for v in positions)]
        )
    return buffer.getvalue()
