"""Joint torques along a timed motion, the floor's wrench shared by the soles as flat feet share it.

The static check holds each posture with the soles' least-size split
(:mod:`posegen.robot.statics`). At the planned speed the floor's wrench moves
(:mod:`posegen.robot.balance`): on a fast weight transfer its centre of pressure swings
toward one foot, and two flat feet can share it only so that each sole's own centre of
pressure stays on that sole, the share a humanoid's balance stabilizer asks of them
(:func:`posegen.robot.sole_split.split_wrench`: the least-size share, clamped to those the
feet can carry). The leg that takes the load then holds more than at rest: its hip can pass
its effort limit in a posture that holds well within it standing still.

Per point, gravity's and the motion's generalized forces are kept apart: stretching the
motion's time by ``l`` scales the motion's part by ``1 / l**2`` exactly, and the split
(piecewise linear) is redone at each stretch (:func:`torque_stretch`). A joint is held,
each torque with its spread over the CoM's uncertainty (:meth:`Statics.com_spread`),
within half the margin the static plan keeps (0.95 of its effort for
``margins.effort_ratio`` 0.9: the other half is the controllers'), or a little more than
the same point asks at rest (``REST_SLACK``), if that is more: slowing a motion down can
always bring it there.

Example:
    >>> torques = MotionTorques(scene)
    >>> loads = torques.loads(q, v, a)  # one per point of a timed motion
    >>> stretch = torque_stretch(scene, torques, loads, torques.spreads(q))  # 1.0: fast enough as timed

"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.robot.balance import MAX_STRETCH, Balance
from posegen.robot.geometry import FloatArray
from posegen.robot.scene import Scene
from posegen.robot.sole_split import least_size_map, split_wrench
from posegen.robot.statics import Statics

RATIO_TOL = 1e-6  # on an effort ratio, between the bisection's end and the check's
REST_SLACK = 0.02  # a motion may add this much (of the effort) to what its points ask at rest


@dataclass(frozen=True)
class PointLoad:
    """What one point of a timed motion asks of the robot, before the soles share the floor's wrench."""

    static: FloatArray  # (nv,) N, N m: gravity's generalized forces
    dynamic: FloatArray  # (nv,) the motion's (scales as 1 / l**2 when the motion's time is stretched by l)
    base: FloatArray  # (6, 6) the base's free-flyer wrench (its frame) -> the world wrench about the origin
    contact: FloatArray  # (6 k, nv) the soles' Jacobians (LOCAL), stacked
    poses: tuple[FloatArray, ...]  # (4, 4) each sole frame's world pose
    normal_map: FloatArray  # (2, 6) the least-size split's normal forces per unit of the total wrench


class MotionTorques:
    """Joint torques of timed motions with both soles on the floor (pinocchio workspaces reused).

    Example:
        >>> torques = MotionTorques(scene)
        >>> tau = torques.torques(torques.load(joints, velocity, acceleration))  # (nj,) N m

    """

    def __init__(self, scene: Scene, balance: Balance | None = None) -> None:
        self.scene = scene
        self.balance = balance or Balance(scene)
        self.statics = Statics(scene)
        self.soles = [scene.frame_id(frame) for frame in scene.stance.sole_frames]
        self.velocity = scene.velocity_indices()
        self._centre = np.array([*scene.stance.foot_centre_m, 0.0])  # the foot rectangle's centre, sole frame
        self._half = np.array(scene.stance.foot_half_m)

    def load(self, joints: FloatArray, velocity: FloatArray, acceleration: FloatArray) -> PointLoad:
        """One point's load: joints (nj,) rad, velocity (nj,) rad/s, acceleration (nj,) rad/s^2."""
        static, dynamic = self.balance.generalized(joints, velocity, acceleration)
        model, data = self.balance.model, self.balance.data
        pin.updateFramePlacements(model, data)
        poses = tuple(np.asarray(data.oMf[f].homogeneous) for f in self.soles)
        contact = np.vstack([pin.getFrameJacobian(model, data, f, pin.LOCAL) for f in self.soles])
        base = np.asarray(data.oMi[1].toDualActionMatrix())
        return PointLoad(static, dynamic, base, contact, poses, least_size_map(list(poses)))

    def loads(self, q: FloatArray, v: FloatArray, a: FloatArray) -> list[PointLoad]:
        """Every point's load: (m, nj) angles rad, velocities rad/s, accelerations rad/s^2."""
        return [self.load(q[k], v[k], a[k]) for k in range(len(q))]

    def torques(self, load: PointLoad, stretch: float = 1.0) -> FloatArray:
        """The joint torques (nj,) N m of a point, its motion's time stretched by ``stretch`` (inf: at rest)."""
        forces = load.static + load.dynamic / stretch**2  # (nv,)
        total = load.base @ forces[:6]  # the floor's wrench on the robot, world, about the origin
        return np.asarray((forces - load.contact.T @ self.sole_wrenches(load, total))[self.velocity])

    def sole_wrenches(self, load: PointLoad, total: FloatArray) -> FloatArray:
        """(12,) both soles' wrenches (LOCAL, stacked) sharing the floor's wrench ``total`` (6,) at a point's posture.

        Example:
            >>> soles = torques.sole_wrenches(load, load.base @ load.static[:6])  # at rest

        """
        return np.concatenate(split_wrench(total, list(load.poses), self._centre, self._half, load.normal_map))

    def spreads(self, q: FloatArray) -> FloatArray:
        """(m, nj) N m: each point's torques' spread over the CoM's uncertainty (:meth:`Statics.com_spread`)."""
        return np.array([self.statics.com_spread(joints) for joints in q]).reshape(len(q), len(self.velocity))


def effort_ratios_at(
    scene: Scene, torques: MotionTorques, loads: Sequence[PointLoad], spreads: FloatArray, stretch: float
) -> FloatArray:
    """(m, nj) each point's torques, with their spreads, over the joints' efforts (0 where the URDF gives none).

    Example:
        >>> moving = effort_ratios_at(scene, torques, loads, spreads, 1.0)  # at rest: np.inf

    """
    effort = np.where(np.isfinite(scene.effort_limit), scene.effort_limit, np.inf)
    moved = np.array([np.abs(torques.torques(load, stretch)) for load in loads]).reshape(spreads.shape)
    return np.asarray((moved + spreads) / effort)


def allowed_ratios(scene: Scene, at_rest: FloatArray) -> FloatArray:
    """(m, nj) the effort ratio each joint may reach at speed.

    Half the margin the static plan keeps (``(1 + effort_ratio) / 2``: 0.95 for 0.9),
    or, where the point at rest asks more (the flat feet's split is not the least-size
    one the pool checked), its ratio at rest plus ``REST_SLACK``.

    Example:
        >>> allowed = allowed_ratios(scene, effort_ratios_at(scene, torques, loads, spreads, np.inf))

    """
    return np.maximum(0.5 * (1.0 + scene.margins.effort_ratio), at_rest + REST_SLACK)


def torque_stretch(scene: Scene, torques: MotionTorques, loads: Sequence[PointLoad], spreads: FloatArray) -> float:
    """The least time stretch ``l >= 1`` that keeps every torque at speed within its allowed ratio.

    Args:
        scene: Scene (``margins.effort_ratio``, the URDF's efforts).
        torques: The workspace the loads were computed with.
        loads: One per point of a rest-to-rest motion at its present timing.
        spreads: (m, nj) N m, the points' spreads over the CoM's uncertainty.

    Returns:
        1 when the motion already keeps them; otherwise the stretch found by bisection
        (at most ``MAX_STRETCH``, where the motion is all but at rest).

    Example:
        >>> stretch = torque_stretch(scene, torques, torques.loads(q, v, a), torques.spreads(q))

    """
    if not loads or not np.any(np.isfinite(scene.effort_limit)):
        return 1.0
    allowed = allowed_ratios(scene, effort_ratios_at(scene, torques, loads, spreads, np.inf)) + RATIO_TOL

    def holds(stretch: float) -> bool:
        return bool(np.all(effort_ratios_at(scene, torques, loads, spreads, stretch) <= allowed))

    if holds(1.0):
        return 1.0
    low, high = 1.0, MAX_STRETCH
    while high - low > 1e-3 * low:
        middle = 0.5 * (low + high)
        low, high = (low, middle) if holds(middle) else (middle, high)
    return high
