"""Time parameterisation of a geometric path (toppra), rest to rest, verified after.

The waypoints themselves are the trajectory points: each got both soles exact and was
checked for collisions, so no point is invented between them. toppra finds the fastest
path velocity at the waypoints (a cubic spline through them as the path) under joint
velocity and acceleration limits shrunk by ``SAFETY``; the result is then verified at
every point and, should toppra overshoot a limit, the segment is slowed down uniformly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import toppra
import toppra.algorithm
import toppra.constraint

from posegen.robot import FloatArray

SAFETY = 0.95  # toppra plans to this fraction of the limits
GRID_FACTOR = 4  # toppra grid points per waypoint
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


def parameterize(waypoints: FloatArray, velocity_limit: FloatArray, acceleration_limit: FloatArray) -> Timed:
    """Fastest rest-to-rest timing of a path within the limits.

    Args:
        waypoints: (m, nj) rad; consecutive duplicates are dropped.
        velocity_limit: (nj,) rad/s.
        acceleration_limit: (nj,) rad/s^2.

    """
    points = [np.asarray(waypoints[0], dtype=float)]
    for w in waypoints[1:]:
        if np.max(np.abs(w - points[-1])) > DUPLICATE_RAD:
            points.append(np.asarray(w, dtype=float))
    positions = np.array(points)
    if len(positions) == 1:
        zeros = np.zeros_like(positions)
        return Timed(np.array([0.0]), positions, zeros, zeros.copy())
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(positions, axis=0), axis=1))])
    if len(positions) == 2:  # no spline: the rest-to-rest time of the slowest joint (bang-bang)
        distance = np.abs(positions[1] - positions[0])
        v, a = SAFETY * velocity_limit, SAFETY * acceleration_limit
        duration = float(np.max(np.where(distance <= v**2 / a, 2 * np.sqrt(distance / a), distance / v + v / a)))
        zeros = np.zeros_like(positions)
        return Timed(np.array([0.0, duration]), positions, zeros, zeros.copy())
    path = toppra.SplineInterpolator(s, positions)
    v = SAFETY * velocity_limit
    a = SAFETY * acceleration_limit
    constraints = [
        toppra.constraint.JointVelocityConstraint(np.column_stack([-v, v])),
        toppra.constraint.JointAccelerationConstraint(np.column_stack([-a, a])),
    ]
    # Grid: the waypoints plus a uniform subdivision. On the waypoints alone toppra can
    # return a near-zero path speed before a sharp turn (seen: 108 s for a 0.5 s move).
    grid = np.unique(np.concatenate([s, np.linspace(0.0, s[-1], GRID_FACTOR * len(s))]))
    at_waypoint = np.searchsorted(grid, s)
    instance = toppra.algorithm.TOPPRA(constraints, path, gridpoints=grid, parametrizer="ParametrizeConstAccel")
    sdd, sd, _ = instance.compute_parameterization(0, 0)
    if sd is None or sdd is None:
        raise RuntimeError("toppra found no parameterisation")
    sd = np.maximum(np.asarray(sd, dtype=float), 0.0)
    sdd = np.append(np.asarray(sdd, dtype=float), float(sdd[-1]))
    dt = 2.0 * np.diff(grid) / np.maximum(sd[:-1] + sd[1:], 1e-12)
    times = np.concatenate([[0.0], np.cumsum(dt)])[at_waypoint]
    sd, sdd = sd[at_waypoint], sdd[at_waypoint]
    velocities = path(s, 1) * sd[:, None]
    accelerations = path(s, 2) * sd[:, None] ** 2 + path(s, 1) * sdd[:, None]
    return _within_limits(Timed(times, positions, velocities, accelerations), velocity_limit, acceleration_limit)


def _within_limits(timed: Timed, velocity_limit: FloatArray, acceleration_limit: FloatArray) -> Timed:
    """Slow the segment down uniformly (t -> l t) if it exceeds a limit anywhere."""
    ratio_v = float(np.max(np.abs(timed.velocities) / velocity_limit))
    ratio_a = float(np.max(np.abs(timed.accelerations) / acceleration_limit))
    stretch = max(1.0, ratio_v, np.sqrt(ratio_a))
    if stretch == 1.0:
        return timed
    return Timed(
        timed.times * stretch,
        timed.positions,
        timed.velocities / stretch,
        timed.accelerations / stretch**2,
    )
