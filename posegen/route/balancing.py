"""Balance at the planned speed: the ZMP kept inside the support polygon by ``margins.zmp_m``.

toppra times a path within joint velocity and acceleration limits; at that speed the
whole body's motion moves the soles' centre of pressure (the ZMP, from the robot's
inverse dynamics: :mod:`posegen.robot.balance`) tens of millimetres away from the CoM's
ground projection on a fast reach. Two pieces keep it inside:

* :class:`ZmpConstraint`, a toppra second-order constraint: the floor's wrench is affine
  in the path acceleration and the squared path speed (``a s'' + b s'^2 + c``), and the
  centre of pressure lies inside the polygon shrunk by the margin exactly when that
  wrench satisfies one linear inequality per edge (``F w <= 0``). toppra then times the
  path as fast as the joints and the balance allow together: slow only where balance
  binds (leaving and reaching a leaning posture), not over the whole segment.
* :func:`balanced`, the check at every timed point afterwards (toppra enforces its
  constraints on its grid): where the margin is still not kept, the whole segment is
  slowed down uniformly by the least stretch that keeps it (its accelerations fall as
  its square).
* :func:`within_torques`, the joint torques at that speed, the floor's wrench shared as
  flat feet share it (:mod:`posegen.robot.motion_torques`): a fast weight transfer loads
  one leg past what it holds at rest; where a joint passes half the static margin (0.95 of
  its effort for ``margins.effort_ratio`` 0.9, or its ratio at rest plus 0.02, if more),
  the segment is timed again with the torques as a toppra constraint too
  (:func:`slowed_locally`: slow only where a joint binds), and that timing checked; a
  uniform slow-down, the same way as the ZMP's, is kept where it is faster.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import toppra.constraint

from posegen.errors import InfeasibleError
from posegen.robot import Balance, FloatArray, MotionTorques, Scene, stretch_for_margin, torque_stretch
from posegen.route.timing import Timed, parameterize
from posegen.route.torque_constraint import TimedLoads, TorqueConstraint

LOG = logging.getLogger(__name__)

GRID_SLACK_M = 0.002  # toppra keeps this much more margin on its grid, for the points between grid points
MIN_FLOOR_FORCE_N = 1.0  # the feet stay loaded


class ZmpConstraint(toppra.constraint.SecondOrderConstraint):
    """toppra constraint: the ZMP inside the support polygon by ``margin_m`` (hand unloaded).

    The constrained vector ``w`` is the floor's wrench on the robot (world frame, about
    the origin; :class:`posegen.robot.Balance`). For an edge of the clockwise polygon with
    inward normal ``n`` through point ``p``, the centre of pressure ``(-M_y, M_x) / f_z``
    is at least ``d`` inside when ``(d + n.p) f_z - n_y M_x + n_x M_y <= 0``.

    Example:
        >>> constraint = ZmpConstraint(scene, Balance(scene), scene.margins.zmp_m)
        >>> toppra.algorithm.TOPPRA([velocity, acceleration, constraint], path)

    """

    def __init__(self, scene: Scene, balance: Balance, margin_m: float) -> None:
        rows = []
        polygon = scene.support_polygon
        for i in range(len(polygon)):
            a, b = polygon[i], polygon[(i + 1) % len(polygon)]
            edge = b - a
            inward = np.array([edge[1], -edge[0]]) / np.linalg.norm(edge)  # clockwise: interior on the right
            rows.append([0.0, 0.0, margin_m + inward @ a, -inward[1], inward[0], 0.0])
        rows.append([0.0, 0.0, -1.0, 0.0, 0.0, 0.0])  # f_z >= MIN_FLOOR_FORCE_N
        matrix = np.array(rows)  # (h + 1, 6)
        bound = np.zeros(len(rows))
        bound[-1] = -MIN_FLOOR_FORCE_N
        dof = len(scene.joint_names)
        super().__init__(self._wrench, lambda _q: matrix, lambda _q: bound, dof)
        self.balance = balance

    def _wrench(self, q: FloatArray, v: FloatArray, a: FloatArray) -> FloatArray:
        static, dynamic = self.balance.point(q, v, a, None, 0.0)
        return np.asarray(static + dynamic)

    def compute_constraint_params(self, path: Any, gridpoints: FloatArray) -> tuple[Any, ...]:
        """a, b, c of ``a s'' + b s'^2 + c = w`` at every grid point: two inverse dynamics each (not toppra's three)."""
        positions, first, second = path(gridpoints), path(gridpoints, 1), path(gridpoints, 2)
        zero = np.zeros(positions.shape[1])
        c = np.zeros((len(gridpoints), 6))
        a, b = np.zeros_like(c), np.zeros_like(c)
        for k, (q, qs, qss) in enumerate(zip(positions, first, second, strict=True)):
            c[k], a[k] = self.balance.point(q, zero, qs, None, 0.0)  # the dynamic part of (v 0, acc p') is a
            _, b[k] = self.balance.point(q, qs, qss, None, 0.0)
        matrix = self.constraint_F(positions[0])
        bound = self.constraint_g(positions[0])
        count = len(gridpoints)
        matrices, bounds = np.repeat(matrix[None], count, axis=0), np.repeat(bound[None], count, axis=0)
        return toppra.constraint.canlinear_colloc_to_interpolate(a, b, c, matrices, bounds, None, None, gridpoints)


def timed_in_balance(
    scene: Scene,
    balance: Balance,
    zmp: ZmpConstraint,
    waypoints: FloatArray,
    velocity_limit: FloatArray,
    acceleration_limit: FloatArray,
    torques: MotionTorques | None = None,
) -> Timed:
    """The fastest timing of a path that keeps the joints' limits, the ZMP's margin and the torques.

    toppra times the path within the joint limits first; only when that timing misses
    the ZMP's margin is it timed again with :class:`ZmpConstraint` (its inverse dynamics
    at every grid point cost 3-4 times the plain timing), and then checked (:func:`balanced`).
    Where the torques at speed pass their ratio, it is timed again with them as a
    constraint too (:func:`slowed_locally`).

    Args:
        scene: Scene.
        balance: The inverse dynamics workspace.
        zmp: The ZMP constraint (its margin a little above ``margins.zmp_m``).
        waypoints: (m, nj) rad.
        velocity_limit: (nj,) or (m, nj) rad/s.
        acceleration_limit: (nj,) rad/s^2.
        torques: The workspace of the torques at speed (:func:`within_torques`); None: not checked.

    Raises:
        InfeasibleError: No timing (toppra's, or the ZMP outside even at rest).

    Example:
        >>> timed = timed_in_balance(scene, balance, zmp, path, scene.velocity_limit * 0.5, accelerations)

    """
    timed = parameterize(waypoints, velocity_limit, acceleration_limit)
    if len(timed.times) < 2:
        return timed
    constraints: list[toppra.constraint.Constraint] = []
    wrenches = balance.floor_wrenches(timed.positions, timed.velocities, timed.accelerations, [None] * len(timed.times))
    if stretch_for_margin(scene.support_polygon, wrenches, scene.margins.zmp_m) != 1.0:
        constraints.append(zmp)
        timed = balanced(scene, balance, parameterize(waypoints, velocity_limit, acceleration_limit, constraints))
    if torques is None:
        return timed
    loaded = TimedLoads.of(torques, timed)
    uniform = within_torques(scene, torques, loaded)
    if uniform is timed or len(timed.times) < 3:
        return timed
    try:
        local = slowed_locally(
            scene, balance, torques, waypoints, velocity_limit, acceleration_limit, constraints, loaded
        )
    except InfeasibleError:  # the linearised split admits no timing: keep the uniform one
        return uniform
    LOG.debug("torques at speed: %.3f s slowed locally, %.3f s uniformly", local.times[-1], uniform.times[-1])
    return local if local.times[-1] < uniform.times[-1] else uniform


def slowed_locally(
    scene: Scene,
    balance: Balance,
    torques: MotionTorques,
    waypoints: FloatArray,
    velocity_limit: FloatArray,
    acceleration_limit: FloatArray,
    constraints: list[toppra.constraint.Constraint],
    missed: TimedLoads,
) -> Timed:
    """A path timed again with its torques at speed as a toppra constraint, then checked as any timing is.

    Slower only where a joint binds, not the whole transfer: the constraint's split is
    linearised at ``missed``, the timing whose torques passed their ratio
    (:class:`posegen.route.torque_constraint.TorqueConstraint`). The result is then
    checked exactly, ZMP (:func:`balanced`) and torques (:func:`within_torques`).

    Raises:
        InfeasibleError: toppra finds no timing with the linearised torques.

    Example:
        >>> missed = TimedLoads.of(torques, timed)
        >>> local = slowed_locally(scene, balance, torques, path, limit, accelerations, [], missed)

    """
    constraint = TorqueConstraint(scene, torques, missed)
    local = parameterize(waypoints, velocity_limit, acceleration_limit, [*constraints, constraint])
    return within_torques(scene, torques, TimedLoads.of(torques, balanced(scene, balance, local)))


def balanced(scene: Scene, balance: Balance, timed: Timed) -> Timed:
    """``timed`` slowed down uniformly just enough to keep the ZMP inside the polygon by the margin.

    The hand is unloaded: where it presses the table, it does so at rest (the force builds
    and is released while the robot holds still), and the pool keeps the posture's centre
    of pressure inside by the margin then (:func:`posegen.robot.pressed_zmp_margin`).

    Args:
        scene: Scene (its support polygon and ``margins.zmp_m``).
        balance: The inverse dynamics workspace.
        timed: A rest-to-rest segment.

    Raises:
        InfeasibleError: Even at rest (or ``MAX_STRETCH`` times slower) the ZMP is outside the margin.

    """
    if len(timed.times) < 2:
        return timed
    margin = scene.margins.zmp_m
    chains = [None] * len(timed.times)
    wrenches = balance.floor_wrenches(timed.positions, timed.velocities, timed.accelerations, chains)
    stretch = stretch_for_margin(scene.support_polygon, wrenches, margin)
    if not np.isfinite(stretch):
        raise InfeasibleError(f"the ZMP leaves the support polygon by {margin} m even when slowed down")
    if stretch == 1.0:
        return timed
    LOG.debug("slowed by %.3f to keep the ZMP %.3f m inside the support polygon", stretch, margin)
    return Timed(timed.times * stretch, timed.positions, timed.velocities / stretch, timed.accelerations / stretch**2)


def within_torques(scene: Scene, torques: MotionTorques, loaded: TimedLoads) -> Timed:
    """``timed`` slowed down uniformly just enough to keep every joint torque at speed within its allowed ratio.

    The torques hold the points at their speed, the floor's wrench shared as flat feet share
    it, each with its spread over the CoM's uncertainty: within half the static margin
    (0.95 of the effort for ``margins.effort_ratio`` 0.9), or within the ratio of the same
    point at rest plus 0.02, if more (:func:`posegen.robot.torque_stretch`).

    Args:
        scene: Scene.
        torques: The workspace the loads were computed on.
        loaded: A rest-to-rest segment and its points' loads.

    Example:
        >>> timed = within_torques(scene, torques, TimedLoads.of(torques, timed))

    """
    timed = loaded.timed
    if len(timed.times) < 2:
        return timed
    stretch = torque_stretch(scene, torques, loaded.loads, loaded.spreads)
    if stretch == 1.0:
        return timed
    LOG.debug("slowed by %.3f to keep the torques at speed within the effort limits", stretch)
    return Timed(timed.times * stretch, timed.positions, timed.velocities / stretch, timed.accelerations / stretch**2)
