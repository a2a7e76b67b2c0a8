"""Independent re-verification of an exported route (``posegen check ROUTE``).

Nothing the planner computed is trusted: every point of the file is checked from the
stored arrays, vectorised where it can be, with pinocchio and coal on the original
meshes (:mod:`posegen.route.pose_check`). In order:

* **structure**: every joint of the model is named once (in any order), every array holds the
  number of points the header declares with one column per joint, and the segment table
  covers the points from first to last, consecutive segments sharing their boundary;
  when this fails nothing else can be checked;
* **finite**: no NaN or infinite time, position, velocity or acceleration;
* **times**: strictly increasing from 0, no step below ``min_dt`` (default 1 ms);
* **joint limits** (with the configured margin), **velocity** (exported values, and the
  mean velocity between consecutive points, within the URDF limits), **acceleration**
  (within the configured limit);
* **consistency** of velocities with positions: for any motion whose acceleration stays
  within the limit A, the mean velocity (q[k+1] - q[k]) / dt differs from the velocities
  at both ends by at most A dt / 2. Allowed: A dt / 2 plus the storage rounding of the
  two positions (one ulp of the stored type, over dt) and of the velocity, plus 2e-6 rad/s
  (twice the 2^-20 rad/s step velocities are stored on);
* **rest**: zero velocity at the first and last points, in every hold, and where every
  go-to-contact starts (force control takes over there);
* **sole**, **CoM** and **collision** at every point (:mod:`posegen.route.pose_check`).

Every violation is named: point index, time, joint (or pair), value and limit.
"""

from __future__ import annotations

import enum
from typing import Any

import numpy as np

from posegen.parallel import Backend
from posegen.progress import ProgressCallback, ignore_progress
from posegen.robot import EXAMPLES, MAX_DURATION_S, Scene, SegmentType, Verification, Worst, worst_case
from posegen.route.pose_check import PoseInvariant, check_poses

MIN_DT_S = 1e-3  # default smallest time step between two points
TOLERANCE = 1e-6  # relative, on velocity and acceleration limits
VELOCITY_TOL = 2e-6  # rad/s, on the consistency of velocities with positions: twice their storage step
LIMIT_TOL_RAD = 5e-7  # on joint-limit margins: twice the float32 rounding of a stored angle


class RouteInvariant(str, enum.Enum):
    """What every route point must satisfy (those computed from kinematics are in :class:`PoseInvariant`)."""

    STRUCTURE = "structure"
    FINITE = "finite"
    TIMES = "times"
    JOINT_LIMITS = "joint_limits"
    VELOCITY = "velocity"
    ACCELERATION = "acceleration"
    CONSISTENCY = "consistency"
    REST = "rest"


def verify_route(
    scene: Scene,
    data: dict[str, Any],
    min_dt: float = MIN_DT_S,
    workers: int | Backend = 1,
    progress: ProgressCallback = ignore_progress,
) -> Verification:
    """Check every point of a read route (see :func:`posegen.robot.read_route`).

    Args:
        scene: The scene the route was made for.
        data: The route's header, with its arrays under ``point_arrays``.
        min_dt: Smallest allowed time step, s.
        workers: Local processes checking collisions on the meshes, or the backend to run them on.
        progress: Told as points are checked for collisions.

    """
    arrays = {name: np.asarray(value) for name, value in data["point_arrays"].items()}
    problems = _structure(scene, data, arrays)
    m = len(arrays["time_from_start"]) if arrays["time_from_start"].ndim == 1 else 0
    if problems:
        first = Worst(RouteInvariant.STRUCTURE, 1.0, -1, len(problems), problems[0], tuple(problems[:EXAMPLES]))
        rest = [
            Worst(k, 0.0, -1, 0, "not checked: the route's structure is broken", checked=False)
            for k in [*list(RouteInvariant)[1:], *PoseInvariant]
        ]
        return Verification(checked=m, worst=(first, *rest))
    times = arrays["time_from_start"].astype(float)
    columns = [list(data["trajectory"]["joint_names"]).index(name) for name in scene.joint_names]  # to model order
    arrays = {name: value[:, columns] if value.ndim == 2 else value for name, value in arrays.items()}
    q, v, a = (arrays[name].astype(float) for name in ("positions", "velocities", "accelerations"))
    worst = [Worst(RouteInvariant.STRUCTURE, 0.0, -1, 0, f"{m} points, {len(scene.joint_names)} joints, segments")]
    worst.append(_finite(times, arrays))
    worst.append(_times(times, min_dt))
    worst.extend(_limits(scene, times, q, v, a))
    worst.append(_consistency(scene, times, arrays, q, v))
    worst.append(_rest(scene, data["segments"], times, v))
    finite = np.all(np.isfinite(q), axis=1)
    worst.extend(check_poses(scene, data["segments"], times, q, finite, workers, progress))
    return Verification(checked=m, worst=tuple(worst))


def _structure(scene: Scene, data: dict[str, Any], arrays: dict[str, np.ndarray]) -> list[str]:
    """What makes the route unreadable as a trajectory of this robot (empty if nothing)."""
    problems = []
    names = [str(n) for n in data["trajectory"]["joint_names"]]
    valid = scene.joint_names
    for i, name in enumerate(names):
        if name not in valid:
            expected = f"'{valid[i]}' here; " if i < len(valid) and valid[i] not in names else ""
            problems.append(
                f"joint {i} '{name}' is not a joint of the robot model ({expected}valid: {', '.join(valid)})"
            )
        elif names.index(name) != i:
            problems.append(f"joint {i} '{name}' is named twice")
    problems += [f"the robot model's joint '{name}' is missing" for name in valid if name not in names]
    declared = data["trajectory"].get("points")
    times = arrays["time_from_start"]
    m = int(declared) if isinstance(declared, int) else len(times)
    if times.ndim != 1 or len(times) != m:
        problems.append(f"time_from_start holds {times.shape} values, the header declares {m} points")
    for name in ("positions", "velocities", "accelerations"):
        shape = arrays[name].shape
        if len(shape) != 2 or shape[0] != m or shape[1] != len(names):
            problems.append(f"{name} has shape {shape}, expected ({m}, {len(names)}): a point or a joint is missing")
    chains = {c.name for c in scene.config.chains}
    expected_first = 0
    for i, seg in enumerate(data["segments"]):
        first, last = int(seg["first_point"]), int(seg["last_point"])
        if first != expected_first or last < first or last >= max(m, 1):
            problems.append(
                f"segment {i} ({seg['type']}) covers points {first}..{last}; expected it to start at "
                f"{expected_first} and end before point {m}"
            )
        if SegmentType(seg["type"]).in_contact and seg.get("chain") not in chains:
            problems.append(f"segment {i} ({seg['type']}) names chain {seg.get('chain')!r}; valid: {sorted(chains)}")
        expected_first = last
    if not data["segments"]:
        problems.append("the segment table is empty: no point says what the robot does")
    elif expected_first != m - 1:
        problems.append(f"the segments end at point {expected_first}, the route's last point is {m - 1}")
    return problems


def _at(times: np.ndarray, k: int) -> str:
    return f"point {k} (t {times[k]:.4f} s)"


def _finite(times: np.ndarray, arrays: dict[str, np.ndarray]) -> Worst:
    bad = ~np.isfinite(times)
    columns = {}
    for name in ("positions", "velocities", "accelerations"):
        columns[name] = ~np.isfinite(arrays[name])
        bad = bad | columns[name].any(axis=1)

    def describe(k: int) -> str:
        what = [f"time_from_start {times[k]}"] if not np.isfinite(times[k]) else []
        for name, mask in columns.items():
            what += [f"{name}[{j}] = {arrays[name][k, j]}" for j in np.flatnonzero(mask[k])[:3]]
        return f"point {k}: " + ", ".join(what)

    return worst_case(RouteInvariant.FINITE, bad.astype(float), describe, "every value finite")


def _times(times: np.ndarray, min_dt: float) -> Worst:
    excess = np.zeros(len(times))
    excess[0] = abs(times[0]) if len(times) else 0.0
    excess[1:] = min_dt - np.diff(times)
    excess = np.maximum(excess, times - MAX_DURATION_S)  # a time no clock holds (1e39 s) is no step

    def describe(k: int) -> str:
        if k == 0:
            return f"point 0 at t {times[0]} s: a route starts at 0"
        if times[k] > MAX_DURATION_S:
            return f"{_at(times, k)}: beyond the longest route a reader accepts, {MAX_DURATION_S:g} s"
        dt = times[k] - times[k - 1]
        kind = "repeats the time of" if dt == 0 else ("goes back from" if dt < 0 else "is too close to")
        return f"{_at(times, k)} {kind} point {k - 1}: dt {dt:.3e} s, minimum {min_dt:.3e} s"

    return worst_case(RouteInvariant.TIMES, excess, describe, f"strictly increasing, every step >= {min_dt:g} s")


def _limits(scene: Scene, times: np.ndarray, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> list[Worst]:
    names = scene.joint_names
    margin = scene.margins.joint_limit_rad
    free = ~scene.locked
    gap = np.minimum(q - scene.lower, scene.upper - q)  # (m, nj) rad
    gap[:, ~free] = np.inf
    limit_excess = margin - LIMIT_TOL_RAD - gap.min(axis=1)

    def describe_limit(k: int) -> str:
        j = int(np.argmin(gap[k]))
        return (
            f"{_at(times, k)} {names[j]} at {q[k, j]:.5f} rad, {gap[k, j]:.5f} rad from its limit "
            f"[{scene.lower[j]:.4f}, {scene.upper[j]:.4f}]; margin {margin} rad"
        )

    dt = np.diff(times)
    mean = np.zeros_like(q)
    with np.errstate(divide="ignore", invalid="ignore"):
        mean[1:] = np.diff(q, axis=0) / dt[:, None]  # rad/s, the mean velocity reaching each point
    v_limit = scene.velocity_limit
    ratio = np.maximum(np.abs(v), np.abs(mean)) / v_limit

    def describe_velocity(k: int) -> str:
        j = int(np.argmax(np.nan_to_num(ratio[k], nan=np.inf)))  # a NaN time makes a whole row NaN
        return (
            f"{_at(times, k)} {names[j]}: velocity {v[k, j]:.4f} rad/s, mean since the previous point "
            f"{mean[k, j]:.4f} rad/s; limit {v_limit[j]:.4f} rad/s"
        )

    a_limit = scene.route.acceleration_limit_rad_s2

    def describe_acceleration(k: int) -> str:
        j = int(np.argmax(np.nan_to_num(np.abs(a[k]), nan=np.inf)))
        return f"{_at(times, k)} {names[j]}: acceleration {a[k, j]:.4f} rad/s^2; limit {a_limit} rad/s^2"

    return [
        worst_case(RouteInvariant.JOINT_LIMITS, limit_excess, describe_limit, "within the limits less the margin"),
        worst_case(
            RouteInvariant.VELOCITY, ratio.max(axis=1) - 1 - TOLERANCE, describe_velocity, "within the URDF limits"
        ),
        worst_case(
            RouteInvariant.ACCELERATION,
            np.abs(a).max(axis=1) / a_limit - 1 - TOLERANCE,
            describe_acceleration,
            f"within {a_limit} rad/s^2",
        ),
    ]


def _consistency(scene: Scene, times: np.ndarray, arrays: dict[str, np.ndarray], q: np.ndarray, v: np.ndarray) -> Worst:
    """Velocities against finite differences of positions (see the module docstring)."""
    m = len(times)
    if m < 2:
        return Worst(RouteInvariant.CONSISTENCY, 0.0, -1, 0, "fewer than two points")
    dt = np.diff(times)[:, None]
    a_limit = scene.route.acceleration_limit_rad_s2
    stored_q, stored_v = arrays["positions"], arrays["velocities"]
    q_ulp = np.spacing(np.maximum(np.abs(stored_q[:-1]), np.abs(stored_q[1:]))).astype(float)  # (m-1, nj)
    v_ulp = np.spacing(np.maximum(np.abs(stored_v[:-1]), np.abs(stored_v[1:]))).astype(float)
    with np.errstate(divide="ignore", invalid="ignore"):
        mean = np.diff(q, axis=0) / dt
        allowed = a_limit * dt / 2 * (1 + TOLERANCE) + q_ulp / dt + v_ulp + VELOCITY_TOL
        error = np.maximum(np.abs(mean - v[:-1]), np.abs(mean - v[1:]))
        ratio = error / allowed  # (m-1, nj)
    excess = np.zeros(m)
    excess[1:] = np.where(dt[:, 0] > 0, np.nanmax(np.where(np.isnan(ratio), np.inf, ratio), axis=1) - 1, -1)
    names = scene.joint_names

    def describe(k: int) -> str:
        j = int(np.nanargmax(np.where(np.isnan(ratio[k - 1]), np.inf, ratio[k - 1])))
        return (
            f"points {k - 1}-{k} (t {times[k - 1]:.4f}-{times[k]:.4f} s) {names[j]}: positions "
            f"{q[k - 1, j]:.5f} -> {q[k, j]:.5f} rad, mean velocity {mean[k - 1, j]:.4f} rad/s, exported "
            f"{v[k - 1, j]:.4f} and {v[k, j]:.4f} rad/s; allowed difference {allowed[k - 1, j]:.4f} rad/s"
        )

    return worst_case(
        RouteInvariant.CONSISTENCY, excess, describe, f"finite differences agree (acceleration <= {a_limit} rad/s^2)"
    )


def _rest(scene: Scene, segments: list[dict[str, Any]], times: np.ndarray, v: np.ndarray) -> Worst:
    """Zero velocity where the robot must stop."""
    must = np.zeros(len(times), dtype=bool)
    must[[0, -1]] = True
    for seg in segments:
        kind = SegmentType(seg["type"])
        if kind == SegmentType.HOLD:
            must[int(seg["first_point"]) : int(seg["last_point"]) + 1] = True
        if kind == SegmentType.GO_TO_CONTACT:
            must[int(seg["first_point"])] = True
    speed = np.where(must, np.abs(v).max(axis=1), 0.0)
    names = scene.joint_names

    def describe(k: int) -> str:
        j = int(np.argmax(np.nan_to_num(np.abs(v[k]), nan=np.inf)))
        return f"{_at(times, k)} must be at rest (start, end, hold, go-to-contact start): {names[j]} at {v[k, j]} rad/s"

    return worst_case(RouteInvariant.REST, speed - 1e-9, describe, "at rest where it must stop")
