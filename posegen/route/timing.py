"""Time parameterisation of a geometric path (toppra), rest to rest, verified after.

The waypoints themselves are the trajectory points: each got both soles exact and was
checked for collisions, so no point is invented between them. toppra finds the fastest
path velocity at the waypoints (a cubic spline through them as the path) under joint
velocity and acceleration limits shrunk by ``SAFETY``; the result is then verified at
every point and, should toppra overshoot a limit, the segment is slowed down uniformly.

The velocity limit may differ from waypoint to waypoint (slow near the table, fast away
from it): one path from a contact to the next is then timed at once, and the robot
stops only at its two ends. Between two waypoints the lower of their limits holds.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import toppra
import toppra.algorithm
import toppra.constraint

from posegen.errors import InfeasibleError
from posegen.robot import FloatArray

LOG = logging.getLogger(__name__)

SAFETY = 0.95  # toppra plans to this fraction of the limits
GRID_FACTOR = 8  # toppra grid points per waypoint (with 4, the spline went up to 20 % past the limits between them)
DUPLICATE_RAD = 1e-12


@dataclass(frozen=True)
class Timed:
    """A time-parameterised segment."""

    times: FloatArray  # (m,) s from the segment start, strictly increasing
    positions: FloatArray  # (m, nj) rad
    velocities: FloatArray  # (m, nj) rad/s, zero at both ends
    accelerations: FloatArray  # (m, nj) rad/s^2


def hold(position: FloatArray, duration_s: float) -> Timed:
    """Stay at ``position`` for ``duration_s``."""
    positions = np.vstack([position, position])
    zeros = np.zeros_like(positions)
    return Timed(np.array([0.0, duration_s]), positions, zeros, zeros.copy())


def path_parameter(positions: FloatArray) -> FloatArray:
    """(m,) the path parameter of waypoints (m, nj): their cumulative joint-space distance (rad).

    Example:
        >>> s = path_parameter(np.array([[0.0, 0.0], [0.3, 0.4]]))  # [0.0, 0.5]

    """
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(positions, axis=0), axis=1))])


def parameterize(
    waypoints: FloatArray,
    velocity_limit: FloatArray,
    acceleration_limit: FloatArray,
    constraints: Sequence[toppra.constraint.Constraint] = (),
) -> Timed:
    """Fastest rest-to-rest timing of a path within the limits.

    Args:
        waypoints: (m, nj) rad; consecutive duplicates are dropped.
        velocity_limit: (nj,) rad/s, or (m, nj): the limit at each waypoint.
        acceleration_limit: (nj,) rad/s^2.
        constraints: More toppra constraints on the path (e.g. balance:
            :class:`posegen.route.balancing.ZmpConstraint`); a path of two waypoints is
            timed without them (checked afterwards by the caller).

    Raises:
        InfeasibleError: toppra finds no timing of the path (seen on paths that wind
            tightly near a singular, limited knee).

    """
    waypoints = np.asarray(waypoints, dtype=float)
    limits = np.broadcast_to(np.asarray(velocity_limit, dtype=float), waypoints.shape)
    points, point_limits = [waypoints[0]], [limits[0]]
    for w, limit in zip(waypoints[1:], limits[1:], strict=True):
        if np.max(np.abs(w - points[-1])) > DUPLICATE_RAD:
            points.append(w)
            point_limits.append(limit)
        else:
            point_limits[-1] = np.minimum(point_limits[-1], limit)
    positions = np.array(points)
    vlim = np.array(point_limits)  # (m, nj) rad/s
    if len(positions) == 1:
        zeros = np.zeros_like(positions)
        return Timed(np.array([0.0]), positions, zeros, zeros.copy())
    s = path_parameter(positions)
    if len(positions) == 2:  # no spline: the rest-to-rest time of the slowest joint (bang-bang)
        distance = np.abs(positions[1] - positions[0])
        v, a = SAFETY * np.minimum(vlim[0], vlim[1]), SAFETY * acceleration_limit
        duration = float(np.max(np.where(distance <= v**2 / a, 2 * np.sqrt(distance / a), distance / v + v / a)))
        zeros = np.zeros_like(positions)
        return Timed(np.array([0.0, duration]), positions, zeros, zeros.copy())
    path = toppra.SplineInterpolator(s, positions)
    a = SAFETY * acceleration_limit
    # Grid: the waypoints plus a uniform subdivision. On the waypoints alone toppra can
    # return a near-zero path speed before a sharp turn (seen: 108 s for a 0.5 s move).
    grid = np.unique(np.concatenate([s, np.linspace(0.0, s[-1], GRID_FACTOR * len(s))]))
    at_waypoint = np.searchsorted(grid, s)
    interval = np.clip(
        np.searchsorted(s, grid, side="right") - 1, 0, len(s) - 2
    )  # waypoint interval of each grid point
    grid_limit = SAFETY * np.minimum(vlim[interval], vlim[interval + 1])  # (grid, nj)
    bounds = {float(g): np.column_stack([-v, v]) for g, v in zip(grid, grid_limit, strict=True)}
    checks: list[toppra.constraint.Constraint] = [
        toppra.constraint.JointVelocityConstraintVarying(lambda x: bounds[float(x)]),
        toppra.constraint.JointAccelerationConstraint(np.column_stack([-a, a])),
        *constraints,
    ]
    instance = toppra.algorithm.TOPPRA(checks, path, gridpoints=grid, parametrizer="ParametrizeConstAccel")
    sdd, sd, _ = instance.compute_parameterization(0, 0)
    if sd is None or sdd is None:
        raise InfeasibleError(f"toppra found no parameterisation of a path of {len(positions)} waypoints")
    sd = np.maximum(np.asarray(sd, dtype=float), 0.0)
    sdd = np.append(np.asarray(sdd, dtype=float), float(sdd[-1]))
    dt = 2.0 * np.diff(grid) / np.maximum(sd[:-1] + sd[1:], 1e-12)
    times = np.concatenate([[0.0], np.cumsum(dt)])[at_waypoint]
    sd, sdd = sd[at_waypoint], sdd[at_waypoint]
    velocities = path(s, 1) * sd[:, None]
    accelerations = path(s, 2) * sd[:, None] ** 2 + path(s, 1) * sdd[:, None]
    return _within_limits(Timed(times, positions, velocities, accelerations), vlim, acceleration_limit)


def consistency_ratio(timed: Timed, acceleration_limit: FloatArray) -> float:
    """How far the velocities are from agreeing with the positions, as a fraction of what is allowed.

    A motion whose acceleration stays within ``a`` has, between two points, a mean
    velocity within a dt / 2 of the velocities at both ends. toppra bounds accelerations
    at its grid points only; between them the timed spline may exceed the limit a
    little, which this ratio (> 1) reveals. ``posegen check`` verifies the same rule.
    """
    if len(timed.times) < 2:
        return 0.0
    dt = np.diff(timed.times)[:, None]
    mean = np.diff(timed.positions, axis=0) / dt
    error = np.maximum(np.abs(mean - timed.velocities[:-1]), np.abs(mean - timed.velocities[1:]))
    return float(np.max(error / (acceleration_limit * dt / 2)))


def _within_limits(timed: Timed, velocity_limit: FloatArray, acceleration_limit: FloatArray) -> Timed:
    """Slow the segment down uniformly (t -> l t) if it exceeds a limit anywhere.

    Velocities scale by 1 / l, accelerations and the consistency ratio by 1 / l^2.
    ``velocity_limit`` is (nj,) or (m, nj), one row per point.
    """
    ratio_v = float(np.max(np.abs(timed.velocities) / velocity_limit))
    ratio_a = float(np.max(np.abs(timed.accelerations) / acceleration_limit))
    ratio_c = consistency_ratio(timed, acceleration_limit)
    stretch = max(1.0, ratio_v, np.sqrt(ratio_a), np.sqrt(ratio_c))
    if stretch == 1.0:
        return timed
    LOG.debug("slowed by %.3f (velocity %.3f, acceleration %.3f, consistency %.3f)", stretch, ratio_v, ratio_a, ratio_c)
    return Timed(
        timed.times * stretch,
        timed.positions,
        timed.velocities / stretch,
        timed.accelerations / stretch**2,
    )
