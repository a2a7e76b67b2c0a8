"""Balance at speed: the centre of pressure the floor must supply along a timed motion (the ZMP).

The model is the whole multibody robot (not a point mass): at each point of a motion,
the wrench the contacts must apply to the robot is the free-flyer rows of its inverse
dynamics (pinocchio's RNEA: the rate of change of the linear and angular momentum, the
weight included), with the floating base moving so that the anchor sole stays still
(its velocity and acceleration zero). Where a hand presses the table, the table supplies
its normal force (``route.contact_force_n``) and the floor the rest. The floor's part is
a force and a moment; the point of the floor about which its horizontal moment vanishes
is the zero-moment point (ZMP), the soles' centre of pressure. It must lie inside the
support polygon, by ``margins.zmp_m``, or the feet start to roll over an edge.

Stretching a motion's time by ``l`` (``t -> l t``) divides its velocities by ``l`` and its
accelerations by ``l**2``: the motion's part of the wrench (``dynamic``) scales as
``1 / l**2`` exactly, the static part not at all (:func:`stretch_for_margin`).

Example:
    >>> balance = Balance(scene)
    >>> wrench = balance.floor_wrenches(q, v, a, [None] * len(q))
    >>> margins = zmp_margins(scene.support_polygon, wrench.static + wrench.dynamic)  # (m,) m

"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.robot.geometry import FloatArray, cross, polygon_margin
from posegen.robot.scene import Scene

MIN_NORMAL_N = 1e-6  # a floor force below this lifts the feet: the centre of pressure is undefined
MAX_STRETCH = 64.0  # the slowest a segment is made (ratio of its times)


@dataclass(frozen=True)
class FloorWrenches:
    """The wrench the floor applies to the robot at each point, in the world frame about its origin."""

    static: FloatArray  # (m, 6) force N, moment N m: the robot at rest in the same postures (hand force included)
    dynamic: FloatArray  # (m, 6) the motion's part (scales as 1 / l**2 when the motion's time is stretched by l)


class Balance:
    """The robot's inverse dynamics with both soles on the floor (pinocchio workspace reused).

    Example:
        >>> wrench = Balance(scene).floor_wrenches(positions, velocities, accelerations, chains)

    """

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.model = scene.model
        self.data = scene.model.createData()
        self.anchor = scene.frame_id(scene.anchor_sole)
        self.velocity = scene.velocity_indices()
        self.normal = np.array(scene.table_pose, dtype=float)[:3, 2]
        self.hands = {c.name: scene.frame_id(c.frame(c.contact_kind)) for c in scene.config.chains}

    def floor_wrenches(
        self,
        positions: FloatArray,
        velocities: FloatArray,
        accelerations: FloatArray,
        contacts: Sequence[str | None],
        force_n: float = 0.0,
    ) -> FloorWrenches:
        """The floor's wrench at each point of a motion.

        Args:
            positions: (m, nj) rad.
            velocities: (m, nj) rad/s.
            accelerations: (m, nj) rad/s^2.
            contacts: Per point, the chain whose hand presses on the table, or None.
            force_n: The table's normal force on a pressing hand, N.

        Returns:
            The static and dynamic parts, (m, 6) each.

        """
        m = len(positions)
        static, dynamic = np.zeros((m, 6)), np.zeros((m, 6))
        for k in range(m):
            static[k], dynamic[k] = self.point(positions[k], velocities[k], accelerations[k], contacts[k], force_n)
        return FloorWrenches(static, dynamic)

    def point(
        self, joints: FloatArray, velocity: FloatArray, acceleration: FloatArray, chain: str | None, force_n: float
    ) -> tuple[FloatArray, FloatArray]:
        """The floor's wrench at one point: its static and dynamic parts, (6,) each (see :meth:`floor_wrenches`)."""
        gravity, motion = self.generalized(joints, velocity, acceleration)
        base = self.data.oMi[1]
        static = _world(base, gravity[:6])
        if chain is not None and force_n != 0.0:
            pin.updateFramePlacements(self.model, self.data)
            force = force_n * self.normal
            static -= np.concatenate([force, cross(self.data.oMf[self.hands[chain]].translation, force)])
        return static, _world(base, motion[:6])

    def generalized(
        self, joints: FloatArray, velocity: FloatArray, acceleration: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The generalized forces (nv,) of one point: gravity's, and the motion's (RNEA less gravity).

        The floating base moves so that the anchor sole stays still. The kinematics and the
        joint Jacobians of the point stay in the workspace (``data``).

        Example:
            >>> gravity, motion = Balance(scene).generalized(joints, velocity, acceleration)

        """
        model, data = self.model, self.data
        q = self.scene.configuration(joints)
        v, a = np.zeros(model.nv), np.zeros(model.nv)
        v[self.velocity], a[self.velocity] = velocity, acceleration
        pin.computeJointJacobians(model, data, q)
        anchor = pin.getFrameJacobian(model, data, self.anchor, pin.LOCAL)  # (6, nv)
        v[:6] = -np.linalg.solve(anchor[:, :6], anchor[:, 6:] @ v[6:])  # the anchor sole still
        pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
        drift = pin.getFrameAcceleration(model, data, self.anchor, pin.LOCAL).vector  # (6,) J-dot v
        a[:6] = -np.linalg.solve(anchor[:, :6], anchor[:, 6:] @ a[6:] + drift)
        gravity = np.array(pin.computeGeneralizedGravity(model, data, q))
        total = np.array(pin.rnea(model, data, q, v, a))
        return gravity, total - gravity


def _world(base: pin.SE3, wrench: FloatArray) -> FloatArray:
    """A free-flyer wrench (base frame, about the base origin) in the world frame about its origin. Shape (6,)."""
    return np.asarray(base.act(pin.Force(wrench)).vector)


def pressed_zmp_margin(scene: Scene, com_m: FloatArray, mass_kg: float, hand_m: FloatArray, force_n: float) -> float:
    """Signed distance (m) of the soles' centre of pressure inside the support polygon, at rest, the hand pressing.

    The table pushes the hand at ``hand_m`` along its normal with ``force_n``; the floor
    carries the rest of the weight.

    Args:
        scene: Scene (its gravity, the floor at z = 0, the table's normal).
        com_m: (3,) the CoM, world frame.
        mass_kg: The robot's mass.
        hand_m: (3,) where the table pushes the hand, world frame.
        force_n: The table's normal force on the hand.

    Example:
        >>> pressed_zmp_margin(scene, data.com[0], data.mass[0], data.oMf[contact].translation, 30.0)

    """
    weight = -mass_kg * np.array(scene.model.gravity.linear, dtype=float)  # the floor's share before the hand's
    hand = force_n * np.array(scene.table_pose, dtype=float)[:3, 2]
    force = weight - hand
    moment = cross(com_m, weight) - cross(hand_m, hand)
    wrench = np.concatenate([force, moment])[None, :]
    return float(zmp_margins(scene.support_polygon, wrench)[0])


def centre_of_pressure(force_n: float, torque_nm: FloatArray) -> FloatArray:
    """(2,) m: where a push ``force_n`` (N, > 0) along a plane's normal acts, from its torques about the origin.

    ``torque_nm`` (2,) N m the push's torques about the plane's x and y axes (a wrench's
    ``[3:5]``), in the plane's frame: the point ``p`` with ``tau = p x f`` on the plane ``z = 0``.

    Example:
        >>> centre_of_pressure(100.0, np.array([2.0, -1.0]))  # 1 cm ahead, 2 cm to the left
        array([0.01, 0.02])

    """
    return np.array([-torque_nm[1], torque_nm[0]]) / force_n


def centres_of_pressure(wrenches: FloatArray, floor_z_m: float = 0.0) -> FloatArray:
    """The floor point (m, 2) about which each floor wrench (m, 6) has no horizontal moment, m (nan if lifted).

    :func:`centre_of_pressure` for many wrenches, on a floor at any height.
    """
    force, moment = wrenches[:, :3], wrenches[:, 3:]
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (floor_z_m * force[:, 0] - moment[:, 1]) / force[:, 2]
        y = (floor_z_m * force[:, 1] + moment[:, 0]) / force[:, 2]
    lifted = force[:, 2] < MIN_NORMAL_N
    return np.where(lifted[:, None], np.nan, np.column_stack([x, y]))


def zmp_margins(polygon_cw: FloatArray, wrenches: FloatArray) -> FloatArray:
    """Signed distance (m,) of each centre of pressure inside the support polygon, m (-inf: the feet lift)."""
    points = centres_of_pressure(wrenches)
    return np.array([-np.inf if np.isnan(p[0]) else polygon_margin(polygon_cw, p) for p in points])


def stretch_for_margin(polygon_cw: FloatArray, wrenches: FloorWrenches, margin_m: float) -> float:
    """The least time stretch ``l >= 1`` that keeps every ZMP inside the polygon by ``margin_m``.

    Args:
        polygon_cw: Clockwise support polygon, (h, 2) m.
        wrenches: The motion's floor wrenches at its present timing.
        margin_m: Required distance inside the polygon, m.

    Returns:
        1 when the motion already keeps the margin; ``inf`` when even the robot at rest
        does not (its static ZMP is outside), or when ``MAX_STRETCH`` is not enough.

    """
    if np.any(zmp_margins(polygon_cw, wrenches.static) < margin_m):
        return float("inf")

    def holds(stretch: float) -> bool:
        return bool(np.all(zmp_margins(polygon_cw, wrenches.static + wrenches.dynamic / stretch**2) >= margin_m))

    if holds(1.0):
        return 1.0
    if not holds(MAX_STRETCH):
        return float("inf")
    low, high = 1.0, MAX_STRETCH
    while high - low > 1e-3 * low:
        middle = 0.5 * (low + high)
        low, high = (low, middle) if holds(middle) else (middle, high)
    return high
