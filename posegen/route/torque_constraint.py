"""Torques at the planned speed as a toppra constraint: slow only where a joint needs it.

A motion whose joint torques at speed pass their allowed ratio (:mod:`posegen.robot.motion_torques`)
used to be slowed down uniformly, the release, the free motion and the approach of a
transfer alike, for one hip loaded on one weight transfer. :class:`TorqueConstraint` times
the path again with the torques as toppra constraints, so that it slows down where they
bind only.

The torques are planned within the static margin (``margins.effort_ratio``, 0.9), not the
0.95 the check at speed allows (:func:`posegen.robot.allowed_ratios`): a transfer timed
this way is fast wherever no joint binds, and it leaves the controllers the whole margin
where one does (planned to 0.95, the route was faster still: docs/physics.md has what the
free-standing rehearsals made of both). A point that asks more at rest (the flat feet's
split is not the least-size one the pool checked) may add ``REST_ADDED`` to it (half what
the check at speed lets it add).

The joint torques of a point are affine in the floor's wrench but for the soles' split of
it, which is piecewise smooth (:func:`posegen.robot.sole_split.split_wrench`): the split is
linearised at the floor's wrench of a reference timing (the one that missed), at the
reference point nearest each grid point. The generalized forces are exactly affine in the
path acceleration and the squared path speed (``fa s'' + fb s'^2 + g``), as the ZMP's are
(:class:`posegen.route.balancing.ZmpConstraint`), so each torque is too. The timing found
is then checked exactly by the caller (:func:`posegen.route.balancing.within_torques`), which
slows it uniformly where the linearisation or the grid left a torque past its ratio.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import toppra.constraint

from posegen.robot import FloatArray, MotionTorques, PointLoad, Scene, effort_ratios_at
from posegen.route.timing import Timed, path_parameter

SPLIT_STEP_N = 1e-3  # finite-difference step of the split's Jacobian (N, N m)
TORQUE_SLACK = 0.01  # planned this fraction of the effort inside the static margin (grid, linearisation)
REST_ADDED = 0.01  # a point asking more at rest may add this (half what the check at speed lets it add)


@dataclass(frozen=True)
class TimedLoads:
    """A timing with what its points ask of the robot: computed once, for the check and the constraint alike.

    Example:
        >>> loaded = TimedLoads.of(MotionTorques(scene), timed)
        >>> len(loaded.loads) == len(timed.times)
        True

    """

    timed: Timed
    loads: list[PointLoad]  # one per point (:meth:`MotionTorques.loads`)
    spreads: FloatArray  # (m, nj) N m, each point's torques' spread over the CoM's uncertainty

    @classmethod
    def of(cls, torques: MotionTorques, timed: Timed) -> TimedLoads:
        """The loads and spreads of ``timed``'s points, on the workspace ``torques``."""
        loads = torques.loads(timed.positions, timed.velocities, timed.accelerations)
        return cls(timed, loads, torques.spreads(timed.positions))


class TorqueConstraint(toppra.constraint.SecondOrderConstraint):
    """toppra constraint: each joint's torque at speed within the static margin (flat feet, split linearised).

    Example:
        >>> constraint = TorqueConstraint(scene, torques, TimedLoads.of(torques, timed))  # the timing that missed
        >>> parameterize(waypoints, velocity_limit, acceleration_limit, [constraint])

    """

    def __init__(self, scene: Scene, torques: MotionTorques, reference: TimedLoads) -> None:
        self.torques = torques
        loads, spreads = reference.loads, reference.spreads  # spreads (m, nj) N m
        effort = scene.effort_limit  # (nj,) N m
        self._finite = np.flatnonzero(np.isfinite(effort))
        at_rest = effort_ratios_at(scene, torques, loads, spreads, np.inf)  # (m, nj)
        planned = np.maximum(scene.margins.effort_ratio - TORQUE_SLACK, at_rest + REST_ADDED)  # (m, nj)
        limit = planned * np.where(np.isfinite(effort), effort, 0.0) - spreads  # (m, nj) N m
        self._limit = limit[:, self._finite]  # (m, nf)
        self._linear = [self._split_map(load) for load in loads]  # the split linearised at each reference point
        self._s = path_parameter(reference.timed.positions)  # (m,)
        nf = len(self._finite)
        matrix = np.vstack([np.eye(nf), -np.eye(nf)])  # (2 nf, nf): tau <= limit, -tau <= limit
        super().__init__(self._unused, lambda _q: matrix, lambda _q: np.zeros(2 * nf), len(scene.joint_names))

    @staticmethod
    def _unused(q: FloatArray, v: FloatArray, a: FloatArray) -> FloatArray:
        raise NotImplementedError("the parameters come from compute_constraint_params")

    def _split_map(self, load: PointLoad) -> tuple[FloatArray, FloatArray]:
        """(12, 6) the split's Jacobian and (12,) its offset at a reference point's floor wrench."""
        total = load.base @ (load.static + load.dynamic)[:6]  # (6,)
        at = self.torques.sole_wrenches(load, total)  # (12,)
        jacobian = np.empty((12, 6))
        for i in range(6):
            step = np.zeros(6)
            step[i] = SPLIT_STEP_N
            jacobian[:, i] = (self.torques.sole_wrenches(load, total + step) - at) / SPLIT_STEP_N
        return jacobian, at - jacobian @ total

    def _torque_map(self, load: PointLoad, split: tuple[FloatArray, FloatArray]) -> tuple[FloatArray, FloatArray]:
        """The torques (nf,) of the finite-effort joints as ``L forces + e``: (nf, nv) L and (nf,) e."""
        jacobian, offset = split
        full = np.eye(len(load.static))
        full[:, :6] -= load.contact.T @ jacobian @ load.base  # forces - C^T (J B forces[:6] + offset)
        rows = self.torques.velocity[self._finite]
        return full[rows], -(load.contact.T @ offset)[rows]

    def compute_constraint_params(self, path: Any, gridpoints: FloatArray) -> tuple[Any, ...]:
        """The parameters toppra asks for: :meth:`affine`'s, each grid point bounded as its nearest reference point."""
        a, b, c, nearest = self.affine(path, gridpoints)
        matrices = np.repeat(self.constraint_F(path(gridpoints[0]))[None], len(gridpoints), axis=0)
        bounds = np.hstack([self._limit[nearest], self._limit[nearest]])  # (count, 2 nf)
        return toppra.constraint.canlinear_colloc_to_interpolate(a, b, c, matrices, bounds, None, None, gridpoints)

    def affine(self, path: Any, gridpoints: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """The torques of the finite-effort joints as ``a s'' + b s'^2 + c`` at each grid point.

        Args:
            path: The toppra path (joint angles rad as a function of the path parameter).
            gridpoints: (count,) path parameters.

        Returns:
            ``a``, ``b``, ``c`` (count, nf) N m, and (count,) the reference point whose split each used.

        Example:
            >>> a, b, c, _ = constraint.affine(path, gridpoints)  # exact at the reference timing's points

        """
        positions, first, second = path(gridpoints), path(gridpoints, 1), path(gridpoints, 2)
        after = np.clip(np.searchsorted(self._s, gridpoints), 0, len(self._s) - 1)
        before = np.maximum(after - 1, 0)
        closer = np.abs(self._s[before] - gridpoints) < np.abs(self._s[after] - gridpoints)
        nearest = np.where(closer, before, after)  # (count,) the reference point of each grid point
        zero = np.zeros(positions.shape[1])
        nf, count = len(self._finite), len(gridpoints)
        a, b, c = np.zeros((count, nf)), np.zeros((count, nf)), np.zeros((count, nf))
        for k, (q, qs, qss) in enumerate(zip(positions, first, second, strict=True)):
            accelerating = self.torques.load(q, zero, qs)  # static: gravity; dynamic: the s'' coefficient
            moving = self.torques.load(q, qs, qss)  # dynamic: the s'^2 coefficient
            linear, offset = self._torque_map(accelerating, self._linear[nearest[k]])
            a[k], b[k] = linear @ accelerating.dynamic, linear @ moving.dynamic
            c[k] = linear @ accelerating.static + offset
        return a, b, c, nearest
