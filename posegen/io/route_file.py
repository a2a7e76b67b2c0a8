"""Route files: the typed :class:`Route` a route file holds, and its one reader.

Written by :mod:`posegen.io.route_writer` (from what the route stage plans); read here,
below the stages, by whoever needs a route (its check, exporters, viewers, a rehearsal
on a simulated robot). Every reader goes through :func:`read_route`, which validates
the file once: what it returns is a route any command can run.

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
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from posegen.errors import InputError, reason
from posegen.io.arrays import read_arrays
from posegen.io.artefact import read_text_file, read_yaml
from posegen.io.cdr import FloatArray
from posegen.io.route_fields import index_field, inline_arrays, is_number, joint_name_list, shown

ROUTE_FORMAT = "posegen-route"
ROUTE_VERSION = 2
ROUTE_ARRAYS = ("time_from_start", "positions", "velocities", "accelerations")
READ_VERSIONS = (1, 2)
POSITION_DTYPE = np.float32  # positions, velocities and accelerations in the sidecar (version 2)
TIME_DTYPE = np.float64
MIN_STEP_S = 1e-6  # smallest time step a reader accepts (posegen check's --min-dt is the controller's, 1 ms)
MAX_DURATION_S = 1e6  # longest route a reader accepts (11.6 days): times fit a rosbag2 clock in ns
MAX_POINT_VALUE = 1e6  # largest |position| (rad), |velocity| (rad/s), |acceleration| (rad/s^2) a reader accepts


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


@dataclass(frozen=True)
class Segment:
    """A run of route points with one meaning; consecutive segments share their boundary point."""

    type: SegmentType
    chain: str | None  # the arm at the table (None for free motions)
    posture: int | None  # the posture's node: its index in the routed plan (n + r: pool row r); None: none
    pool_id: int | None  # the posture's pool row (None: none, or not numbered yet by the planner)
    first_point: int  # index of its first point
    last_point: int  # index of its last point (inclusive)
    start_s: float  # time of its first point, s
    end_s: float  # time of its last point, s


@dataclass(frozen=True)
class Route:
    """A timed route as its file holds it: points, segment table, what it routes and how it was made.

    The arrays are float64 copies of the stored values (C-ordered): times strictly
    increasing from 0, every value finite, the segments covering the points from first
    to last (checked by :func:`read_route`).

    Example:
        >>> route = posegen.load("plans/route.yaml")
        >>> route.times[-1], [s.type for s in route.segments][:3]

    """

    joint_names: tuple[str, ...]
    times: FloatArray  # (m,) s
    positions: FloatArray  # (m, nj) rad, columns in joint_names order
    velocities: FloatArray  # (m, nj) rad/s
    accelerations: FloatArray  # (m, nj) rad/s^2
    segments: tuple[Segment, ...]
    provenance: dict[str, Any]
    postures: tuple[dict[str, Any], ...] = ()  # the routed postures' plain data, in visiting order
    skipped: tuple[dict[str, Any], ...] = ()  # {posture, pool_id, reason}
    substitutions: tuple[dict[str, Any], ...] = ()  # {posture, pool_id, reason, substitute_pool_id, ...}
    summary: dict[str, Any] | None = None  # the figures the route stage recorded
    format_version: int = ROUTE_VERSION  # as read: version 1 held its points as float64, version 2 as float32

    @property
    def stored_dtype(self) -> np.dtype[Any]:
        """The type the file stores positions, velocities and accelerations in (their rounding)."""
        return np.dtype(POSITION_DTYPE if self.format_version >= 2 else np.float64)

    def joint_columns(self, names: Sequence[str], where: str = "route") -> list[int]:
        """The columns of ``names`` (a robot's joints) in the arrays: the route must name each once, in any order.

        Raises:
            InputError: A joint the robot lacks, or a robot joint the route lacks (named).

        """
        problems = []
        for i, name in enumerate(self.joint_names):
            if name not in names:
                expected = f"'{names[i]}' here; " if i < len(names) and names[i] not in self.joint_names else ""
                problems.append(
                    f"joint {i} '{name}' is not a joint of the robot model ({expected}valid: {', '.join(names)})"
                )
        problems += [f"the robot model's joint '{name}' is missing" for name in names if name not in self.joint_names]
        if problems:
            more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
            raise InputError(f"{where}: {problems[0]}{more}")
        return [self.joint_names.index(name) for name in names]

    def check_chains(self, chains: Sequence[str], where: str = "route") -> None:
        """Every contact segment names one of ``chains``, and so does any other segment that names a chain.

        Raises:
            InputError: A contact segment naming another chain (or none), or another segment naming another chain.

        """
        for i, seg in enumerate(self.segments):
            if (seg.type.in_contact or seg.chain is not None) and seg.chain not in chains:
                raise InputError(
                    f"{where}: segment {i} ({seg.type.value}) names chain {seg.chain!r}; valid: {sorted(chains)}"
                )

    def hold_pool_rows(self) -> tuple[int | None, ...]:
        """The pool row of every hold, in route order."""
        return tuple(s.pool_id for s in self.segments if s.type == SegmentType.HOLD)


def read_route(path: str | Path) -> Route:
    """Read and validate a route file: the one reader every command goes through.

    Raises:
        InputError: Missing or malformed header, not a route, a missing sidecar or one
            whose hash differs from the header's, arrays that disagree with the header's
            count or with each other, points no controller can run (see
            :func:`points_problem`), or a segment table that does not cover them.

    """
    path = Path(path)
    data = _header(path)
    version = data.get("format_version", 1)
    if version not in READ_VERSIONS or isinstance(version, bool):
        raise InputError(f"{path}: format_version {version!r}: this posegen reads versions 1 and 2")
    try:
        provenance = data.get("provenance") or {}
        if not isinstance(provenance, dict):
            raise TypeError(f"provenance must be a mapping, not {shown(provenance)}")
        trajectory = data.get("trajectory")
        if not isinstance(trajectory, dict):
            raise TypeError(f"trajectory must be a mapping with joint_names and points, not {shown(trajectory)}")
        names = joint_name_list(trajectory.get("joint_names"))
        segments = data.get("segments")
        if not isinstance(segments, list):
            raise TypeError(f"segments must be a list of segments, not {shown(segments)}")
        rows = [_segment_row(seg, i) for i, seg in enumerate(segments)]
        points = trajectory.get("points")
        if version == 2:
            if not isinstance(points, int) or isinstance(points, bool) or points < 0:
                raise ValueError(f"trajectory.points must be the number of points, not {shown(points)}")
            arrays = read_arrays(path, data.get("arrays"), ROUTE_ARRAYS, rows=points)
        else:
            arrays = inline_arrays(points, ROUTE_ARRAYS[1:])
        extras = {key: tuple(_mappings(data, key)) for key in ("postures", "skipped", "substitutions")}
        summary = data.get("summary")
        if summary is not None and not isinstance(summary, dict):
            raise TypeError(f"summary must be a mapping, not {shown(summary)}")
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"{path}: malformed route: {exc}") from exc
    times, positions, velocities, accelerations = _point_arrays(arrays, len(names), str(path))
    problem = points_problem(times, (positions, velocities, accelerations), [(r[4], r[5]) for r in rows])
    if problem:
        raise InputError(f"{path}: {problem}")
    segments = tuple(
        Segment(kind, chain, posture, pool_id, first, last, float(times[first]), float(times[last]))
        for kind, chain, posture, pool_id, first, last in rows
    )
    return Route(
        names,
        times,
        positions,
        velocities,
        accelerations,
        segments,
        provenance,
        **extras,
        summary=summary,
        format_version=version,
    )


def _header(path: Path) -> dict[str, Any]:
    """A route file's header, as plain data (YAML, or JSON by the file's suffix)."""
    if path.suffix.lower() != ".json":
        return read_yaml(path, ROUTE_FORMAT)
    try:
        data = json.loads(read_text_file(path, InputError))
    except (json.JSONDecodeError, RecursionError) as exc:
        raise InputError(f"{path}: not valid JSON ({reason(exc)})") from exc
    if not isinstance(data, dict) or data.get("format") != ROUTE_FORMAT:
        raise InputError(f"{path}: not a {ROUTE_FORMAT} file")
    return data


def _segment_row(seg: Any, i: int) -> tuple[SegmentType, str | None, int | None, int | None, int, int]:
    """Segment ``i`` of the header, its fields typed (its times are checked finite, then taken from the points).

    Raises:
        TypeError, ValueError: A field missing or of the wrong type (the segment and the field named).

    """
    where = f"segments[{i}]"
    if not isinstance(seg, dict):
        raise TypeError(f"{where} must be a mapping, not {shown(seg)}")
    kinds = [k.value for k in SegmentType]
    if seg.get("type") not in kinds:
        raise ValueError(f"{where}.type must be one of {', '.join(kinds)}, not {shown(seg.get('type'))}")
    chain = seg.get("chain")
    if chain is not None and not isinstance(chain, str):
        raise TypeError(f"{where}.chain must be a name, not {shown(chain)}")
    for key in ("start_s", "end_s"):
        value: Any = seg.get(key)
        if not is_number(value) or not np.isfinite(float(value)):
            raise ValueError(f"{where}.{key}: segment times must be finite numbers, not {shown(value)}")
    first, last = (index_field(seg.get(k), f"{where}.{k}") for k in ("first_point", "last_point"))
    if first is None or last is None:
        raise ValueError(f"{where}: first_point and last_point must be point indexes")
    posture, pool_id = (index_field(seg.get(k), f"{where}.{k}") for k in ("posture", "pool_id"))
    return SegmentType(seg["type"]), chain, posture, pool_id, first, last


def _mappings(data: dict[str, Any], key: str) -> list[dict[str, Any]]:
    """The header's list of mappings under ``key`` (empty when absent)."""
    values = data.get(key) or []
    if not isinstance(values, list) or not all(isinstance(v, dict) for v in values):
        raise TypeError(f"{key} must be a list of mappings")
    return values


def _point_arrays(arrays: dict[str, np.ndarray], nj: int, where: str) -> tuple[FloatArray, ...]:
    """Times (m,), positions, velocities and accelerations (m, nj), as C-ordered float64 copies.

    Raises:
        InputError: Arrays that are not of real floating-point numbers (integers, booleans,
            complex numbers or text), or shapes that disagree with each other or the joint names.

    """
    for name in ROUTE_ARRAYS:
        dtype = np.asarray(arrays[name]).dtype
        if not np.issubdtype(dtype, np.floating):
            raise InputError(f"{where}: {name} holds {dtype} values; a route's points are floating-point numbers")
    times, positions, velocities, accelerations = (
        np.array(arrays[name], dtype=float, order="C") for name in ROUTE_ARRAYS
    )
    if times.ndim != 1:
        raise InputError(f"{where}: time_from_start is an array of shape {times.shape}; expected one time per point")
    for name, values in zip(ROUTE_ARRAYS[1:], (positions, velocities, accelerations), strict=True):
        if values.shape != (len(times), nj):
            raise InputError(
                f"{where}: {name} is an array of shape {values.shape}; expected {len(times)} points of {nj} joints"
            )
    return times, positions, velocities, accelerations


def points_problem(times: FloatArray, arrays: tuple[FloatArray, ...], segments: Sequence[tuple[int, int]]) -> str:
    """What makes a route's points unusable by any reader ("" if nothing): the readers' rules.

    Every value finite, positions, velocities and accelerations within :data:`MAX_POINT_VALUE`
    in magnitude; times from 0, strictly increasing by at least :data:`MIN_STEP_S`,
    within :data:`MAX_DURATION_S`; a segment table that covers the points from first to
    last, each segment starting where the previous one ends.

    Args:
        times: (m,) s.
        arrays: Positions, velocities, accelerations, each (m, nj).
        segments: The first and last point of every segment, in the table's order.

    """
    m = len(times)
    if m == 0:
        return "the route has no point"
    for name, values in zip(ROUTE_ARRAYS, (times, *arrays), strict=True):
        bad = np.flatnonzero(~np.isfinite(values).reshape(m, -1).all(axis=1))
        if len(bad):
            return f"{name} at point {bad[0]} is not a finite number"
        if name != "time_from_start" and values.size and np.abs(values).max() > MAX_POINT_VALUE:
            k = int(np.argmax(np.abs(values).max(axis=1)))
            return (
                f"{name} at point {k} holds {np.abs(values[k]).max():.3g}: beyond {MAX_POINT_VALUE:g}, no joint runs it"
            )
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
    for i, (first, last) in enumerate(segments):
        if first != expected or not first <= last < m:
            return f"segment {i} covers points {first}..{last}: expected it to start at {expected}, end before {m}"
        expected = last
    if expected != m - 1:
        return f"the segments end at point {expected}, the route's last point is {m - 1}"
    return ""


def is_route_file(path: str | Path) -> bool:
    """Whether a file is a route (by its suffix or its ``format`` field), not a pool.

    Raises:
        InputError: The file cannot be read.

    """
    path = Path(path)
    head = read_text_file(path, InputError)[:4096]
    return path.suffix.lower() == ".json" or f"format: {ROUTE_FORMAT}" in head


def stamp(seconds: float) -> dict[str, int]:
    """A ROS ``builtin_interfaces/Duration`` {sec, nanosec} of a time in seconds."""
    sec = int(np.floor(seconds))
    nanosec = round((seconds - sec) * 1e9)
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return {"sec": sec, "nanosec": nanosec}
