"""Independent re-verification of an exported route (``posegen check ROUTE``).

Nothing the planner computed is trusted: every point of the file is checked from the
stored arrays, vectorised where it can be, with pinocchio and coal on the original
meshes (:mod:`posegen.route.pose_check`). What every command needs of a route (its
structure: arrays holding the points the header declares, one column per joint, a segment
table covering them; finite values; times increasing from 0 by at least 1 us) is the
reader's (:func:`posegen.io.read_route`): a route it refuses is refused here the same way,
in one line. Here, on what it accepts, for this robot:

* **names**: every joint of the model is named once (in any order), every contact segment
  names a chain of the config (:meth:`posegen.io.Route.joint_columns`, ``check_chains``);
* **times**: no step below ``min_dt`` (default 1 ms, the controller's);
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
* **sole**, **CoM** and **collision** at every point (:mod:`posegen.route.pose_check`);
* **torque** and **zmp** at every point: the holding torques within the effort limits,
  the ZMP at the stored timing inside the support polygon (:mod:`posegen.route.load_check`).

Every violation is named: point index, time, joint (or pair), value and limit.
"""

from __future__ import annotations

import enum

import numpy as np

from posegen.io import MAX_DURATION_S, Route, Segment, SegmentType
from posegen.parallel import Backend
from posegen.progress import ProgressCallback, ignore_progress
from posegen.robot import Scene, Verification, Worst, worst_case
from posegen.route.load_check import check_loads
from posegen.route.pose_check import check_poses

MIN_DT_S = 1e-3  # default smallest time step between two points
TOLERANCE = 1e-6  # relative, on velocity and acceleration limits
VELOCITY_TOL = 2e-6  # rad/s, on the consistency of velocities with positions: twice their storage step
LIMIT_TOL_RAD = 5e-7  # on joint-limit margins: twice the float32 rounding of a stored angle


class RouteInvariant(str, enum.Enum):
    """What every route point must satisfy (those computed from kinematics are in :class:`PoseInvariant`)."""

    TIMES = "times"
    JOINT_LIMITS = "joint_limits"
    VELOCITY = "velocity"
    ACCELERATION = "acceleration"
    CONSISTENCY = "consistency"
    REST = "rest"


def verify_route(
    scene: Scene,
    route: Route,
    min_dt: float = MIN_DT_S,
    workers: int | Backend = 1,
    progress: ProgressCallback = ignore_progress,
    where: str = "route",
) -> Verification:
    """Check every point of a read route (see :func:`posegen.io.read_route`) on this robot.

    Args:
        scene: The scene the route was made for.
        route: The route, as its reader validated it.
        min_dt: Smallest allowed time step, s.
        workers: Local processes checking collisions on the meshes, or the backend to run them on.
        progress: Told as points are checked for collisions.
        where: The route's name in messages.

    Raises:
        InputError: The route names a joint or a chain this robot lacks, or lacks one of its joints.

    """
    columns = route.joint_columns(scene.joint_names, where)  # to model order
    route.check_chains([c.name for c in scene.config.chains], where)
    times = route.times
    q, v, a = (values[:, columns] for values in (route.positions, route.velocities, route.accelerations))
    worst = [_times(times, min_dt)]
    worst.extend(_limits(scene, times, q, v, a))
    worst.append(_consistency(scene, times, route.stored_dtype, q, v))
    worst.append(_rest(scene, route.segments, times, v))
    finite = np.ones(len(times), dtype=bool)  # the reader refuses any other value
    worst.extend(check_poses(scene, route.segments, times, q, finite, workers, progress))
    loads, efforts = check_loads(scene, route.segments, times, q, v, a)
    worst.extend(loads)
    return Verification(checked=len(times), worst=tuple(worst), efforts=efforts)


def _at(times: np.ndarray, k: int) -> str:
    return f"point {k} (t {times[k]:.4f} s)"


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
    margin = scene.limit_margins  # (nj,) rad
    free = ~scene.locked
    gap = np.minimum(q - scene.lower, scene.upper - q)  # (m, nj) rad
    slack = gap - margin  # (m, nj) rad, negative inside a joint's margin
    slack[:, ~free] = np.inf
    limit_excess = -LIMIT_TOL_RAD - slack.min(axis=1)

    def describe_limit(k: int) -> str:
        j = int(np.argmin(slack[k]))
        return (
            f"{_at(times, k)} {names[j]} at {q[k, j]:.5f} rad, {gap[k, j]:.5f} rad from its limit "
            f"[{scene.lower[j]:.4f}, {scene.upper[j]:.4f}]; margin {margin[j]:g} rad"
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


def _consistency(scene: Scene, times: np.ndarray, stored: np.dtype, q: np.ndarray, v: np.ndarray) -> Worst:
    """Velocities against finite differences of positions (see the module docstring)."""
    m = len(times)
    if m < 2:
        return Worst(RouteInvariant.CONSISTENCY, 0.0, -1, 0, "fewer than two points")
    dt = np.diff(times)[:, None]
    a_limit = scene.route.acceleration_limit_rad_s2
    stored_q, stored_v = q.astype(stored), v.astype(stored)  # exact: the values are the stored ones
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


def _rest(scene: Scene, segments: tuple[Segment, ...], times: np.ndarray, v: np.ndarray) -> Worst:
    """Zero velocity where the robot must stop."""
    must = np.zeros(len(times), dtype=bool)
    must[[0, -1]] = True
    for seg in segments:
        if seg.type == SegmentType.HOLD:
            must[seg.first_point : seg.last_point + 1] = True
        if seg.type == SegmentType.GO_TO_CONTACT:
            must[seg.first_point] = True
    speed = np.where(must, np.abs(v).max(axis=1), 0.0)
    names = scene.joint_names

    def describe(k: int) -> str:
        j = int(np.argmax(np.nan_to_num(np.abs(v[k]), nan=np.inf)))
        return f"{_at(times, k)} must be at rest (start, end, hold, go-to-contact start): {names[j]} at {v[k, j]} rad/s"

    return worst_case(RouteInvariant.REST, speed - 1e-9, describe, "at rest where it must stop")
