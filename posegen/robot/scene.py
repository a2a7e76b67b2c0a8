"""The robot-and-table scene shared by every stage: model, stance, contact frames, table.

A :class:`Scene` is built once from a validated :class:`~posegen.robot.config.Config`
and hands each stage the typed sub-config it reads (``scene.margins``, ``scene.route``,
...). Its model is the augmented URDF of :mod:`posegen.robot.description`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError, InputError, unknown_name
from posegen.io import provenance, read_text_file
from posegen.robot.collision_geometry import check_link_names
from posegen.robot.config import ChainConfig, Config, load_config, parse_config
from posegen.robot.description import (
    augmented_urdf,
    contact_placement,
    frame_id,
    locked_configuration,
    resolve_robot_files,
    with_declared_frames,
)
from posegen.robot.geometry import FloatArray, convex_hull_clockwise, flatten_on_floor, polygon_margin, yaw_rotation


@dataclass(frozen=True)
class Spot:
    """A contact target spot on the table."""

    name: str
    xy_table_m: tuple[float, float]  # in the table frame
    chains: tuple[str, ...]  # chains whose arm serves this spot


class Scene:
    """Robot model, stance, contact frames and table of one configuration.

    Attributes:
        config: The validated configuration (saved with every artefact).
        stance, chains, table, margins, sampling, route, calibration: Its typed sub-configs, which
            the stages read.
        files: The robot description files.
        urdf_xml: The augmented URDF (with contact frames).
        model: pinocchio model with a free-flyer root.
        joint_names: The actuated (1-dof) joints, in model order.
        lower, upper: Joint limits (rad), shape (nj,).
        velocity_limit: Joint velocity limits (rad/s), shape (nj,).
        reference: The reference posture's joint angles (rad), shape (nj,).
        sole_poses: World pose of each sole, shape (4, 4) each.
        support_polygon: Clockwise support polygon in the floor plane (m), shape (h, 2).
        table_pose: World pose of the table's top face centre, shape (4, 4).
        spots: Contact target spots.

    """

    def __init__(self, config: Config) -> None:
        self.config = config
        self.stance = config.stance
        self.chains = config.chains
        self.table = config.table
        self.margins = config.margins
        self.sampling = config.sampling
        self.route = config.route
        self.calibration = config.calibration
        self.files = resolve_robot_files(config)
        nominal_text = self.files.urdf_text()
        try:
            nominal = pin.buildModelFromXML(nominal_text, pin.JointModelFreeFlyer())
        except (RuntimeError, ValueError) as exc:
            raise ConfigError(f"cannot load URDF {self.files.urdf}: {exc}") from exc
        declared_text = with_declared_frames(nominal_text, nominal, config.frames)
        declared = pin.buildModelFromXML(declared_text, pin.JointModelFreeFlyer())
        for chain in self.chains:
            for field, frames in (
                ("sole_frame", [chain.sole_frame]),
                ("gripper_frame", [chain.gripper_frame]),
                ("fingertip_frames", chain.fingertip_frames),
                ("point_frame", [chain.point_frame] if chain.point_frame else []),
                ("touching_links", chain.touching_links),
            ):
                for frame in frames:
                    _named_frame(declared, frame, f"chains.{chain.name}.{field}")
            if chain.fingertip_frames and declared.existFrame(chain.contact_frame):
                raise ConfigError(f"chains.{chain.name}.contact_frame '{chain.contact_frame}' already exists")
        for field, frames in (
            ("sole_frames", self.stance.sole_frames),
            ("floor_contact_frames", self.stance.floor_contact_frames),
        ):
            for frame in frames:
                _named_frame(declared, frame, f"stance.{field}")
        check_link_names(declared, config.collision)
        held = locked_configuration(declared, config.locked_joints)  # fingertips are read with the fingers locked
        self.urdf_xml = augmented_urdf(declared_text, declared, config, held)
        self.model = pin.buildModelFromXML(self.urdf_xml, pin.JointModelFreeFlyer())
        self._data = self.model.createData()  # scratch space of configuration()
        self._closing: tuple[int, list[int], np.ndarray] | None = None  # see close_stance
        self._anchor_frame = self.model.getFrameId(config.stance.sole_frames[0])
        self.joint_names = tuple(
            str(self.model.names[j]) for j in range(1, self.model.njoints) if self.model.joints[j].nq == 1
        )
        self._q_index = np.array([self.model.joints[self.model.getJointId(n)].idx_q for n in self.joint_names])
        self._v_index = np.array([self.model.joints[self.model.getJointId(n)].idx_v for n in self.joint_names])
        self.lower = self.model.lowerPositionLimit[self._q_index].copy()
        self.upper = self.model.upperPositionLimit[self._q_index].copy()
        self.locked = np.zeros(len(self.joint_names), dtype=bool)  # (nj,) held during sampling
        self.locked_values = np.zeros(len(self.joint_names))  # (nj,) rad, where locked
        for name, value in config.locked_joints.items():
            i = self._joint(name, "robot.locked_joints")
            if not self.lower[i] <= value <= self.upper[i]:
                raise ConfigError(
                    f"robot.locked_joints.{name}: {value} rad is outside [{self.lower[i]}, {self.upper[i]}]"
                )
            self.locked[i] = True
            self.locked_values[i] = value
        self.velocity_limit = self._velocity_limits()
        held = self.model_configuration(self.locked_values)
        self.contact_placements = {  # flush contact frames in their gripper frames
            chain.name: contact_placement(self.model, chain, held) for chain in self.chains if chain.fingertip_frames
        }
        self.point_placements = {  # point frames in their gripper frames, the fingers locked
            chain.name: self._placement_in(chain.gripper_frame, chain.point_frame, held)
            for chain in self.chains
            if chain.point_frame
        }

        if self.files.srdf is not None:
            read_text_file(self.files.srdf, ConfigError)  # a clear error for a binary or unreadable SRDF
            try:
                pin.loadReferenceConfigurations(self.model, str(self.files.srdf), False)
            except (RuntimeError, ValueError) as exc:
                raise ConfigError(f"cannot read SRDF {self.files.srdf}: {str(exc).strip().splitlines()[0]}") from exc
        reference = self._reference_configuration()
        self.reference = reference[self._q_index].copy()

        data = self.model.createData()
        pin.framesForwardKinematics(self.model, data, reference)
        self.sole_poses = {
            f: flatten_on_floor(data.oMf[self.model.getFrameId(f)].homogeneous) for f in self.stance.sole_frames
        }
        corners = [
            (pose @ np.array([x, y, 0.0, 1.0]))[:2]
            for pose in self.sole_poses.values()
            for x in self.stance.foot_x_m
            for y in self.stance.foot_y_m
        ]
        self.support_polygon = convex_hull_clockwise(np.array(corners))

        table = self.table
        self.table_pose = np.eye(4)
        self.table_pose[:3, :3] = yaw_rotation(np.deg2rad(table.yaw_deg))
        self.table_pose[:3, 3] = table.top_center_m
        self.spots = tuple(
            Spot(
                name=f"contact_{i * len(table.spots_y_m) + j:02d}",
                xy_table_m=(x, y),
                chains=tuple(c.name for c in self.chains if c.spot_y_range_m[0] <= y <= c.spot_y_range_m[1]),
            )
            for i, x in enumerate(table.spots_x_m)
            for j, y in enumerate(table.spots_y_m)
        )

    def _joint(self, name: str, field: str) -> int:
        if name not in self.joint_names:
            raise ConfigError(unknown_name("joint", name, self.joint_names) + f" ({field})")
        return self.joint_names.index(name)

    def _velocity_limits(self) -> FloatArray:
        """URDF velocity limits (rad/s) with the config's overrides. Shape (nj,).

        A free joint needs a positive limit. A locked one never moves: a missing limit
        (0 in some URDFs) is replaced by the largest free one, so that it never binds.
        """
        limit = self.model.velocityLimit[self._v_index].copy()
        for name, value in self.config.velocity_limits.items():
            limit[self._joint(name, "robot.velocity_limits_rad_s")] = value
        missing = [n for i, n in enumerate(self.joint_names) if not self.locked[i] and not limit[i] > 0]
        if missing:
            raise ConfigError(
                f"robot.velocity_limits_rad_s: the URDF gives no velocity limit (0 rad/s) for {', '.join(missing)}; "
                "declare one for each, or lock the joint"
            )
        free = limit[~self.locked]
        limit[self.locked & ~(limit > 0)] = float(free.max()) if len(free) else 1.0
        return np.asarray(limit)

    def _reference_configuration(self) -> FloatArray:
        """The reference posture: an SRDF state (or every joint at 0) with the config's overrides.

        The root's orientation: the state's, or ``stance.root_rpy_deg`` (a model whose up axis is not z).
        """
        postures = {str(e.key()): np.array(e.data()) for e in self.model.referenceConfigurations}
        name = self.stance.reference_posture
        if name and not postures:
            raise ConfigError(
                f"stance.reference_posture: '{name}' names an SRDF state but the robot has no SRDF; "
                "give the posture as stance.reference_joints (and stance.root_rpy_deg), or name an SRDF"
            )
        if name and name not in postures:
            raise ConfigError(unknown_name("reference posture", name, postures) + " (stance.reference_posture)")
        q = postures[name].copy() if name else pin.neutral(self.model)
        for joint, value in self.stance.reference_joints.items():
            q[self._q_index[self._joint(joint, "stance.reference_joints")]] = value
        if self.stance.root_rpy_deg is not None:
            rotation = pin.rpy.rpyToMatrix(*np.deg2rad(self.stance.root_rpy_deg))
            q[3:7] = pin.Quaternion(rotation).coeffs()
        return np.asarray(q)

    def _placement_in(self, parent: str, frame: str, q: FloatArray) -> pin.SE3:
        data = self.model.createData()
        pin.framesForwardKinematics(self.model, data, q)
        return data.oMf[self.frame_id(parent)].actInv(data.oMf[self.frame_id(frame)])

    def model_configuration(self, joints: FloatArray) -> FloatArray:
        """The model's configuration with these joint angles and the base at the origin. Shape (nq,)."""
        q = pin.neutral(self.model)
        q[self._q_index] = joints
        return np.asarray(q)

    @property
    def anchor_sole(self) -> str:
        """The sole frame the floating base is solved from."""
        return self.stance.sole_frames[0]

    @property
    def second_sole(self) -> str:
        """The other sole frame, whose leg closes the stance."""
        return self.stance.sole_frames[1]

    @property
    def contact_collision_margin_m(self) -> float:
        """Collision margin during contact segments: the margin less the commanded overshoot."""
        return self.config.contact_collision_margin_m

    def chain(self, name: str) -> ChainConfig:
        """The chain called ``name``.

        Raises:
            ConfigError: No chain has that name (the valid ones are listed).

        """
        return self.config.chain(name)

    def provenance(self, seed: int | None) -> dict[str, Any]:
        """Provenance of an artefact made with this scene: config, model hash, seed, version."""
        return provenance(self.config.to_dict(), self.files.sha256(), seed)

    def check_made_for(self, recorded: dict[str, Any], where: str) -> None:
        """Check that an artefact's provenance names this robot model.

        Raises:
            InputError: The artefact was made for another robot model.

        """
        sha = recorded.get("robot_model_sha256")
        if sha is not None and not isinstance(sha, str):
            raise InputError(f"{where}: provenance: robot_model_sha256 is not a hash ({sha!r})")
        if sha and sha != self.files.sha256():
            raise InputError(f"{where} was made for another robot model (sha256 {sha[:12]}...)")

    def joint_index(self, name: str) -> int:
        """Index of an actuated joint in :attr:`joint_names`.

        Raises:
            ConfigError: The joint does not exist.

        """
        try:
            return self.joint_names.index(name)
        except ValueError:
            raise ConfigError(unknown_name("joint", name, self.joint_names)) from None

    def frame_id(self, name: str) -> int:
        """Pinocchio id of a frame, with a clear error listing the valid frames."""
        return frame_id(self.model, name)

    def spot_world(self, spot: Spot) -> FloatArray:
        """World position (m) of a spot on the table top. Shape (3,)."""
        return (self.table_pose @ np.array([*spot.xy_table_m, 0.0, 1.0]))[:3]

    def configuration(self, joints: FloatArray) -> FloatArray:
        """Full pinocchio configuration with the floating base placing the anchor sole.

        Args:
            joints: Actuated joint angles (rad), shape (nj,).

        Returns:
            Configuration, shape (nq,): free-flyer pose such that the anchor sole is at
            its fixed pose, then the joint angles.

        """
        q = pin.neutral(self.model)
        q[self._q_index] = joints
        data = self._data
        pin.forwardKinematics(self.model, data, q)
        base_to_sole = pin.updateFramePlacement(self.model, data, self._anchor_frame)  # the one frame needed
        base = pin.SE3(self.sole_poses[self.anchor_sole]) * base_to_sole.inverse()
        q[:7] = pin.SE3ToXYZQUAT(base)
        return q

    def joints_of(self, q: FloatArray) -> FloatArray:
        """Actuated joint angles (rad) of a full configuration. Shape (nj,)."""
        return np.array(q[self._q_index], dtype=float)

    def limit_margin(self, joints: FloatArray) -> FloatArray:
        """Smallest distance (rad) of the free (not locked) joints to their limits.

        Args:
            joints: (nj,) or (m, nj) joint angles.

        Returns:
            A scalar array, or (m,); negative when a limit is exceeded.

        """
        gap = np.minimum(joints - self.lower, self.upper - joints)
        return np.asarray(gap[..., ~self.locked].min(axis=-1))

    def com_margin(self, q: FloatArray, data: pin.Data) -> float:
        """Signed distance (m) of the CoM ground projection inside the support polygon.

        Args:
            q: Full configuration, shape (nq,).
            data: pinocchio data to compute in.

        """
        com = pin.centerOfMass(self.model, data, q)
        return polygon_margin(self.support_polygon, com[:2])

    def leg_joints(self, sole_frame: str) -> list[int]:
        """Indices (in :attr:`joint_names`) of the joints from a sole up to the root, sole first."""
        joint = self.model.frames[self.frame_id(sole_frame)].parentJoint
        out = []
        while joint > 1:  # 0: universe, 1: the floating base
            out.append(self.joint_index(str(self.model.names[joint])))
            joint = self.model.parents[joint]
        return out

    def stance_leg_joints(self) -> list[int]:
        """Indices of the joints of both legs (from each sole up to the root), sorted."""
        return sorted({j for sole in self.stance.sole_frames for j in self.leg_joints(sole)})

    def close_stance(self, joints: FloatArray, iterations: int = 30) -> FloatArray | None:
        """Move the second leg so that its sole meets its fixed pose (Gauss-Newton).

        Args:
            joints: (nj,) joint angles; the anchor sole is placed by :meth:`configuration`.
            iterations: Cap on Gauss-Newton steps.

        Returns:
            New joint angles with both soles at their poses (1e-10 m/rad), or None if the
            second sole cannot be reached.

        """
        frame = self.second_sole
        if self._closing is None:  # (frame id, leg joint indices, their velocity indices), found once
            leg = self.leg_joints(frame)
            self._closing = (self.frame_id(frame), leg, self._v_index[leg])
        frame_id, leg, columns = self._closing
        out = np.array(joints, dtype=float)
        target = pin.SE3(self.sole_poses[frame])
        data = self._data
        for _ in range(iterations):
            q = self.configuration(out)
            pin.computeJointJacobians(self.model, data, q)  # placements and Jacobians in one pass
            pin.updateFramePlacements(self.model, data)
            error = pin.log6(data.oMf[frame_id].actInv(target)).vector
            if np.linalg.norm(error) < 1e-10:
                return out
            jac = pin.getFrameJacobian(self.model, data, frame_id, pin.LOCAL)[:, columns]
            out[leg] += np.linalg.lstsq(jac, error, rcond=None)[0]
            if np.any(out[leg] < self.lower[leg]) or np.any(out[leg] > self.upper[leg]):
                return None
        return None

    def velocity_indices(self) -> FloatArray:
        """Indices of the actuated joints in the velocity vector. Shape (nj,)."""
        return self._v_index.copy()


def _named_frame(model: pin.Model, name: str, field: str) -> None:
    if not model.existFrame(name):
        raise ConfigError(unknown_name("frame", name, (f.name for f in model.frames)) + f" ({field})")


def scene_for(recorded: dict[str, Any], config_path: str | None) -> Scene:
    """The scene an artefact was made for: the config in its provenance, or ``config_path``.

    Raises:
        ConfigError: The config is missing, malformed or names what the robot lacks.
        InputError: The provenance is not a mapping.

    """
    if not isinstance(recorded, dict):
        raise InputError(f"the provenance must be a mapping, not {type(recorded).__name__}")
    config = load_config(config_path) if config_path else parse_config(recorded.get("config"), "")
    return Scene(config)
