"""Writing a :class:`~posegen.io.route_file.Route`: its YAML header, its ``.npz`` sidecar, optionally a CSV.

The format is described in :mod:`posegen.io.route_file`, beside its reader. The header
is YAML, or JSON when the file name ends in ``.json``; the points go to a sidecar beside
it, in their stored types and resolutions (:func:`stored_arrays`). The CSV, when asked
for, goes to ``<name>.<sha256 prefix of the header>.csv`` (replaced with the header as
one); it has one row per point: time (s), segment, chain, posture, then the joint positions
(rad), as stored.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

import numpy as np

from posegen.io.arrays import write_with_arrays
from posegen.io.cdr import FloatArray
from posegen.io.companion import companion_of, companions_of
from posegen.io.route_file import POSITION_DTYPE, ROUTE_FORMAT, ROUTE_VERSION, TIME_DTYPE, Route, Segment

CSV_SUFFIX = ".csv"  # a route's CSV: ``<name>.<sha256 prefix of the header>.csv``

VELOCITY_STEP = 2.0**-20  # rad/s (~1e-6): stored velocities are multiples of it, rounded toward zero
ACCELERATION_STEP = 2.0**-16  # rad/s^2 (~1.5e-5): the same for accelerations


def stored_arrays(
    times: FloatArray, positions: FloatArray, velocities: FloatArray, accelerations: FloatArray
) -> dict[str, np.ndarray]:
    """A route's sidecar arrays, in their stored types and resolutions (column-major: they compress better).

    Args:
        times: (m,) s.
        positions: (m, nj) rad.
        velocities: (m, nj) rad/s.
        accelerations: (m, nj) rad/s^2.

    """
    return {
        "time_from_start": np.asarray(times, dtype=TIME_DTYPE),
        "positions": np.asfortranarray(positions, dtype=POSITION_DTYPE),
        "velocities": np.asfortranarray(_toward_zero(velocities, VELOCITY_STEP), dtype=POSITION_DTYPE),
        "accelerations": np.asfortranarray(_toward_zero(accelerations, ACCELERATION_STEP), dtype=POSITION_DTYPE),
    }


def _toward_zero(values: np.ndarray, step: float) -> np.ndarray:
    """Values on a grid of ``step``, rounded toward zero: never past a limit the exact ones respect."""
    return np.asarray(np.trunc(np.asarray(values) / step) * step)


def segment_data(segment: Segment) -> dict[str, Any]:
    """Plain data of one row of the segment table."""
    return {
        "type": segment.type.value,
        "chain": segment.chain,
        "posture": segment.posture,
        "pool_id": segment.pool_id,
        "first_point": segment.first_point,
        "last_point": segment.last_point,
        "start_s": segment.start_s,
        "end_s": segment.end_s,
    }


def route_header(route: Route) -> dict[str, Any]:
    """Plain data of a route file's header (without the sidecar reference)."""
    return {
        "format": ROUTE_FORMAT,
        "format_version": ROUTE_VERSION,
        "provenance": route.provenance,
        "trajectory": {
            "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
            "joint_names": list(route.joint_names),
            "points": len(route.times),
        },
        "segments": [segment_data(s) for s in route.segments],
        "postures": list(route.postures),
        "skipped": list(route.skipped),
        "substitutions": list(route.substitutions),
        "summary": route.summary if route.summary is not None else {},
    }


def route_outputs(path: Path) -> list[Path]:
    """The files :func:`write_route` writes or replaces whose names are known before.

    The header, and the companions an older route left there (its CSV, replaced or
    removed with it). The sidecar's name follows its content
    (:func:`posegen.io.sidecar_path`), the CSV's the header's
    (:func:`posegen.io.companion_path`), both beside the header.
    """
    return [path, *companions_of(path, CSV_SUFFIX)]


def write_route(path: Path, route: Route, csv_too: bool = False) -> list[Path]:
    """Write the route (the deflated sidecar and the CSV if asked first, the header last).

    The CSV is the header's companion, ``<name>.<sha256 prefix of the header>.csv``: it
    is replaced with the header, as one; without ``csv_too`` an older route's CSV is removed.

    Returns:
        The paths written: the header, its sidecar, and the CSV if asked.

    """
    arrays = stored_arrays(route.times, route.positions, route.velocities, route.accelerations)
    csv_bytes = _csv(route, arrays).encode() if csv_too else None
    sidecar = write_with_arrays(path, route_header(route), arrays, compress=True, companions={CSV_SUFFIX: csv_bytes})
    csv_path = companion_of(path, CSV_SUFFIX) if csv_too else None
    return [path, sidecar, *([csv_path] if csv_path else [])]


def _csv(route: Route, arrays: dict[str, np.ndarray]) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(["time_s", "segment", "chain", "posture", *route.joint_names])
    segment_of: dict[int, Segment] = {}
    for seg in route.segments:
        for k in range(seg.first_point, seg.last_point + 1):
            segment_of[k] = seg  # a shared boundary point belongs to the later segment
    for k, (time_s, positions) in enumerate(zip(arrays["time_from_start"], arrays["positions"], strict=True)):
        seg = segment_of[k]
        posture = seg.posture if seg.posture is not None else ""
        writer.writerow(
            [f"{time_s:.9f}", seg.type.value, seg.chain or "", posture, *(repr(float(v)) for v in positions)]
        )
    return buffer.getvalue()
