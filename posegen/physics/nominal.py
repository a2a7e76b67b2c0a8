"""What the robot's controllers know: the nominal model, its anchor sole flat on the floor.

The controllers never see the true robot. They read the encoders and the force/torque
sensors and compute, on the nominal URDF (pinocchio) with the anchor sole at its
reference place (``Scene.configuration``), the frames and their Jacobians, the centre of mass,
and the static torques of the posture: gravity held by both soles and, in contact, the
hand's target force (the soles' share split by least size, as
:mod:`posegen.robot.statics` splits it). Wrenches are (force, torque) in N and N m.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from posegen.physics.tool import Tool
from posegen.robot import FloatArray, Scene, cross, least_size_map, split_wrench

GRAVITY = np.array([0.0, 0.0, -9.81])  # m/s^2, world
SPLIT_EVERY = 25  # updates between two computations of the least-size split's map (the soles barely move)


class NominalRobot:
    """The nominal model at the encoders' angles; call :meth:`update` first.

    Frames are read in the world the robot believes in (its anchor sole at its place);
    Jacobians have the base's six columns, then one per actuated joint (scene order).

    Example:
        >>> robot = NominalRobot(scene, {"left": wrist_tool(scene, "wrist_left_ft_link")})
        >>> robot.update(scene.reference)
        >>> robot.com()[:2]  # the centre of mass over the floor, m

    """

    def __init__(self, scene: Scene, tools: dict[str, Tool]) -> None:
        self.scene = scene
        self.model = scene.model
        self.data = self.model.createData()
        self._scratch = self.model.createData()  # kinematics that must not disturb ``data``
        self.imu: FloatArray | None = None
        self.sole_poses: list[FloatArray] = []  # (4, 4) each, stance order: set by update()
        self.sole_centres: list[FloatArray] = []  # (3,) each, the foot rectangles' centres
        self.tools = tools
        self._velocity = scene.velocity_indices()
        self._joint_columns: dict[tuple[int, ...], NDArray[np.intp]] = {}  # joints (scene order) -> velocity columns
        self.soles = [scene.frame_id(s) for s in scene.stance.sole_frames]
        self.contact_frames = {c.name: scene.frame_id(c.frame(c.contact_kind)) for c in scene.chains}
        self.wrench_frames = {c: scene.frame_id(t.frame) for c, t in tools.items()}
        self.mass_kg = float(pin.computeTotalMass(self.model))
        self._foot_centre = np.array([*scene.stance.foot_centre_m, 0.0])  # in a sole frame
        self._foot_half = np.array(scene.stance.foot_half_m)
        self._normal_map: FloatArray | None = None  # the least-size split's, renewed every SPLIT_EVERY updates
        self._updates = 0
        # computed at most once per update, when first asked (update() forgets them)
        self._gravity: FloatArray | None = None  # (nv,) the generalized gravity
        self._com: FloatArray | None = None  # (3,) m, the centre of mass
        self._sole_jacobians: list[FloatArray] | None = None  # (6, nv) LOCAL each
        self.q = scene.configuration(scene.reference)

    def _configuration(self, joints: FloatArray, imu: FloatArray | None) -> FloatArray:
        """The configuration (nq,) the robot believes in: its anchor sole's origin at its place, as the IMU tilts it."""
        q = self.scene.configuration(joints)
        if imu is None:
            return q
        kinematic = pin.Quaternion(q[3:7]).toRotationMatrix()
        yaw = np.arctan2(kinematic[1, 0], kinematic[0, 0]) - np.arctan2(imu[1, 0], imu[0, 0])
        rotation = pin.rpy.rpyToMatrix(0.0, 0.0, yaw) @ imu
        origin = self.scene.sole_poses[self.scene.anchor_sole][:3, 3]  # where the configuration puts the anchor
        local = pin.XYZQUATToSE3(q[:7]).actInv(origin)  # the anchor origin in the base frame
        q[:3] = origin - rotation @ local
        q[3:7] = pin.Quaternion(rotation).coeffs()
        return q

    def update(self, joints: FloatArray, imu: FloatArray | None = None) -> None:
        """Kinematics and Jacobians at these joint angles (nj,) rad, the base tilted as the IMU reads it.

        Args:
            joints: The encoders' angles (nj,) rad.
            imu: The base's world orientation (3, 3) the IMU reads: its roll and pitch replace
                the ones the flat anchor sole gives (the yaw stays the kinematics'), the anchor
                sole's origin kept at its place. None: the anchor sole flat.

        """
        self.imu = imu
        self._updates += 1
        self._gravity = self._com = self._sole_jacobians = None
        self.q = self._configuration(joints, imu)
        pin.computeJointJacobians(self.model, self.data, self.q)
        pin.updateFramePlacements(self.model, self.data)
        self.sole_poses = [self.pose(sole) for sole in self.soles]
        self.sole_centres = [pose[:3, :3] @ self._foot_centre + pose[:3, 3] for pose in self.sole_poses]

    def commanded_poses(self, joints: FloatArray, frames: list[int]) -> list[FloatArray]:
        """Frames' world poses (4, 4) at commanded angles (nj,), the base as :meth:`update` last estimated it."""
        q = self._configuration(joints, self.imu)
        pin.forwardKinematics(self.model, self._scratch, q)
        return [np.asarray(pin.updateFramePlacement(self.model, self._scratch, f).homogeneous) for f in frames]

    def pose(self, frame: int) -> FloatArray:
        """World pose of a frame (4, 4)."""
        return np.asarray(self.data.oMf[frame].homogeneous)

    def _columns(self, full: FloatArray) -> FloatArray:
        return np.hstack([full[:, :6], full[:, 6:][:, self._velocity - 6]])

    def frame_jacobian(self, frame: int) -> FloatArray:
        """(6, 6 + nj) a frame's twist (linear, angular; world axes at its origin) per base twist and joint rate.

        The base's six columns are its local twist; the others one per actuated joint (scene order).
        """
        return self._columns(pin.getFrameJacobian(self.model, self.data, frame, pin.LOCAL_WORLD_ALIGNED))

    def joint_jacobian(self, frame: int, joints: list[int]) -> FloatArray:
        """(6, len(joints)) a frame's twist (world axes at its origin) per rate of these joints (scene indices).

        The columns :meth:`frame_jacobian` has for them, without building the others.
        """
        key = tuple(joints)
        columns = self._joint_columns.get(key)
        if columns is None:
            columns = self._joint_columns[key] = self._velocity[list(joints)]
        return np.asarray(pin.getFrameJacobian(self.model, self.data, frame, pin.LOCAL_WORLD_ALIGNED)[:, columns])

    def base_jacobian(self) -> FloatArray:
        """(6, 6 + nj) the free base's twist (world axes at its origin), as :meth:`frame_jacobian`."""
        return self._columns(pin.getJointJacobian(self.model, self.data, 1, pin.LOCAL_WORLD_ALIGNED))

    def com(self) -> FloatArray:
        """World centre of mass (3,), m (a new array: computed once per :meth:`update`)."""
        if self._com is None:
            self._com = np.array(pin.centerOfMass(self.model, self.data, self.q, False))
        return self._com.copy()

    def com_jacobian(self) -> FloatArray:
        """(3, 6 + nj) CoM velocity per base twist and joint rate, as :meth:`frame_jacobian`."""
        return self._columns(pin.jacobianCenterOfMass(self.model, self.data, self.q, False))

    def tool_wrench(self, chain: str) -> FloatArray:
        """The wrench (6,) the tool's weight puts on its wrist sensor, in the sensor's frame."""
        tool = self.tools[chain]
        rotation = self.data.oMf[self.wrench_frames[chain]].rotation
        force = rotation.T @ (tool.mass_kg * GRAVITY)
        return np.concatenate([force, cross(tool.com_m, force)])

    def at_contact(self, chain: str, wrench: FloatArray) -> FloatArray:
        """A wrench (6,) read in a chain's wrench frame, as world axes at its contact frame's origin."""
        sensor = self.data.oMf[self.wrench_frames[chain]]
        force = sensor.rotation @ wrench[:3]
        torque = sensor.rotation @ wrench[3:]
        lever = self.data.oMf[self.contact_frames[chain]].translation - sensor.translation
        return np.concatenate([force, torque - cross(lever, force)])

    def sole_split(self, total: FloatArray) -> list[FloatArray]:
        """A world wrench (6,) at the world origin, shared by the soles: each (6,) LOCAL (see :func:`split_wrench`)."""
        if self._normal_map is None or self._updates % SPLIT_EVERY == 0:
            self._normal_map = least_size_map(self.sole_poses)
        return split_wrench(total, self.sole_poses, self._foot_centre, self._foot_half, self._normal_map)

    def soles_total(self, wrenches: tuple[FloatArray, ...]) -> FloatArray:
        """The soles' wrenches (6,) each, in their frames, as one world wrench (6,) at the world origin."""
        total = np.zeros(6)
        for pose, wrench in zip(self.sole_poses, wrenches, strict=True):
            force = pose[:3, :3] @ wrench[:3]
            total[:3] += force
            total[3:] += pose[:3, :3] @ wrench[3:] + cross(pose[:3, 3], force)
        return total

    def _gravity_now(self) -> FloatArray:
        """(nv,) the generalized gravity at the last :meth:`update` (computed once per update; do not modify)."""
        if self._gravity is None:
            self._gravity = np.array(pin.computeGeneralizedGravity(self.model, self.data, self.q))
        return self._gravity

    def _held_by_soles(self, load: FloatArray, wrenches: list[FloatArray]) -> FloatArray:
        """The joint torques (nj,) that hold generalized forces ``load`` (nv,), the soles carrying ``wrenches``."""
        if self._sole_jacobians is None:
            self._sole_jacobians = [pin.getFrameJacobian(self.model, self.data, s, pin.LOCAL) for s in self.soles]
        torques = load.copy()
        for jacobian, wrench in zip(self._sole_jacobians, wrenches, strict=True):
            torques -= jacobian.T @ wrench
        return np.asarray(torques[self._velocity])

    def sole_torques(self, wrenches: list[FloatArray]) -> FloatArray:
        """Joint torques (nj,) N m that hold the posture, its weight carried by the soles' wrenches (6,) LOCAL each.

        The hands are unloaded.
        """
        return self._held_by_soles(self._gravity_now(), wrenches)

    def static_torques(self, hand: dict[str, FloatArray]) -> FloatArray:
        """Joint torques (nj,) N m that hold the posture: gravity, the hands' wrenches, the soles' shares.

        Args:
            hand: Chain -> the table's wrench on its hand (6,), world axes at its contact frame.

        """
        load = self._gravity_now().copy()  # (nv,)
        for chain, wrench in hand.items():
            jacobian = pin.getFrameJacobian(self.model, self.data, self.contact_frames[chain], pin.LOCAL_WORLD_ALIGNED)
            load -= jacobian.T @ wrench
        base = self.data.oMi[1].toDualActionMatrix() @ load[:6]  # base wrench -> world origin
        return self._held_by_soles(load, self.sole_split(base))
