"""The robot-and-table scene shared by every stage: model, stance, contact frames, table.

A :class:`Scene` is built once from a validated :class:`~posegen.robot.config.Config`
and hands each stage the typed sub-config it reads (``scene.margins``, ``scene.route``,
...). Its model is the augmented URDF of :mod:`posegen.robot.description`.
"""

from __future__ import annotations

from functools import cached_property
from typing import Any

import numpy as np
import pinocchio as pin

from posegen.errors import ArgumentError, ConfigError, InputError, unknown_name
from posegen.io import Pool, provenance
from posegen.robot.config import ChainConfig, Config, load_config, parse_config
from posegen.robot.description import frame_id
from posegen.robot.geometry import FloatArray, polygon_margin
from posegen.robot.scene_parts import (
    IntArray,
    Spot,
    actuated_joints,
    apply_additions,
    check_names,
    contact_placements,
    load_description,
    read_srdf_states,
    reference_configuration,
    stand,
    table_pose,
    table_spots,
)


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
        effort_limit: The URDF's joint effort limits (N m), shape (nj,); nan where it gives none.
        reference: The reference posture's joint angles (rad), shape (nj,).
        sole_poses: World pose of each sole, shape (4, 4) each.
        support_polygon: Clockwise support polygon in the floor plane (m), shape (h, 2).
        table_pose: World pose of the table's top face centre, shape (4, 4).
        spots: Contact target spots.

    Example:
        >>> scene = posegen.load_scene("configs/talos_table.yaml")
        >>> scene.joint_names[:1], scene.chain("left").contact_frame

    """

    def __init__(self, config: Config) -> None:
        """The scene of ``config``, built in the steps of :mod:`posegen.robot.scene_parts`.

        Raises:
            ConfigError: The config names what the robot lacks, or its files do not load.
            ArgumentError: ``config`` is not a :class:`Config` (a path: ``Scene(load_config(path))``).

        """
        if not isinstance(config, Config):
            raise ArgumentError(
                f"config must be a Config: Scene(load_config(path)) or posegen.load_scene(path), got {config!r}"
            )
        self.config = config
        self.stance = config.stance
        self.chains = config.chains
        self.table = config.table
        self.margins = config.margins
        self.sampling = config.sampling
        self.route = config.route
        self.calibration = config.calibration
        description = load_description(config)
        check_names(description.model, config)
        self.files = description.files
        self.urdf_xml, self.model = apply_additions(description, config)
        joints = actuated_joints(self.model, config)
        self.joint_names = joints.names
        self._q_index, self._v_index = joints.q_index, joints.v_index
        self.lower, self.upper, self.velocity_limit = joints.lower, joints.upper, joints.velocity_limit
        self.effort_limit = joints.effort_limit  # (nj,) N m, nan where the URDF gives none
        self.limit_margins = joints.limit_margin  # (nj,) rad kept from each limit (margins.joint_limit_rad or larger)
        self.locked, self.locked_values = joints.locked, joints.locked_values  # (nj,) held during sampling, rad
        self._data = self.model.createData()  # scratch space of configuration()
        self._closing: tuple[int, list[int], np.ndarray] | None = None  # see close_stance
        self._anchor_frame = self.model.getFrameId(config.stance.sole_frames[0])
        held = self.model_configuration(self.locked_values)  # fingertips are read with the fingers locked
        self.contact_placements, self.point_placements = contact_placements(self.model, self.chains, held)
        read_srdf_states(self.model, self.files)
        reference = reference_configuration(self.model, self.stance, joints)
        self.reference = reference[self._q_index].copy()
        self.sole_poses, self.support_polygon = stand(self.model, self.stance, reference)
        self.table_pose = table_pose(self.table)
        self.spots = table_spots(self.table, self.chains)

    @classmethod
    def from_config(cls, config: Config) -> Scene:
        """The scene of ``config``, the same as ``Scene(config)``.

        Its steps, in order, each a function of :mod:`posegen.robot.scene_parts` testable alone:
        ``load_description``, ``check_names``, ``apply_additions``, ``actuated_joints``,
        ``contact_placements``, ``read_srdf_states``, ``reference_configuration``, ``stand``,
        ``table_pose`` and ``table_spots``.

        Raises:
            ConfigError: The config names what the robot lacks, or its files do not load.

        """
        return cls(config)

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
        """Smallest distance (rad) of the free joints to their limits (against ``margins.joint_limit_rad``).

        A joint with a larger margin of its own (``margins.joint_limit_rad_by_joint``) counts
        its distance less the extra: the result is below ``margins.joint_limit_rad`` when any
        joint is closer to a limit than its margin.

        Args:
            joints: (nj,) or (m, nj) joint angles.

        Returns:
            A scalar array, or (m,); negative when a limit is exceeded.

        """
        extra = self.limit_margins - self.margins.joint_limit_rad  # (nj,) rad, 0 for most joints
        gap = np.minimum(joints - self.lower, self.upper - joints) - extra
        return np.asarray(gap[..., ~self.locked].min(axis=-1))

    def planning_limits(self, buffer_rad: float = 0.0) -> tuple[FloatArray, FloatArray]:
        """The joint limits (rad) a plan keeps within: each limit less the joint's margin and ``buffer_rad``.

        Returns:
            ``(lower, upper)``, each (nj,) rad (new arrays).

        Example:
            >>> lower, upper = scene.planning_limits()
            >>> bool(np.all(lower < upper))
            True

        """
        inset = self.limit_margins + buffer_rad
        return self.lower + inset, self.upper - inset

    def com_margin(self, q: FloatArray, data: pin.Data) -> float:
        """Signed distance (m) of the CoM ground projection inside the support polygon.

        Args:
            q: Full configuration, shape (nq,).
            data: pinocchio data to compute in.

        """
        com = pin.centerOfMass(self.model, data, q)
        return polygon_margin(self.support_polygon, com[:2])

    def leg_joints(self, sole_frame: str) -> list[int]:
        """Indices (in :attr:`joint_names`) of a leg's joints, sole first.

        The joints from the sole up to, not including, the first joint both soles hang from
        (the legs' branching joint: the root, or a pelvis below waist joints). The waist
        carries both legs: it is no leg's joint, so a leg's joints never move the other sole.
        """
        joint = self.model.frames[self.frame_id(sole_frame)].parentJoint
        shared = self._stance_ancestors
        out = []
        while joint not in shared:
            out.append(self.joint_index(str(self.model.names[joint])))
            joint = self.model.parents[joint]
        return out

    def moving_joints(self, frame: str) -> list[int]:
        """Indices (in :attr:`joint_names`) of the actuated joints that move ``frame`` relative to the root."""
        joint = self.model.frames[self.frame_id(frame)].parentJoint
        out = []
        while joint > 1:  # 0: the universe, 1: the floating base
            if self.model.joints[joint].nq == 1:
                out.append(self.joint_index(str(self.model.names[joint])))
            joint = self.model.parents[joint]
        return out

    def idle_joints(self, chain: str) -> list[int]:
        """Free joints that move neither ``chain``'s contact frame nor a sole (another arm, a head), sorted."""
        return list(self._idle_joints[self.chain(chain).name])

    @cached_property
    def _idle_joints(self) -> dict[str, tuple[int, ...]]:
        """Chain -> its idle joints (the pool asks for them at every sample: 40 us each to find)."""
        legs = set(self.stance_leg_joints())
        idle = {}
        for config in self.chains:
            busy = set(self.moving_joints(config.frame(config.contact_kind))) | legs
            idle[config.name] = tuple(i for i in range(len(self.joint_names)) if i not in busy and not self.locked[i])
        return idle

    @cached_property
    def _stance_ancestors(self) -> frozenset[int]:
        """The joints both soles hang from (their common ancestors, the universe and the floating base included)."""
        chains = []
        for sole in self.stance.sole_frames:
            joint = self.model.frames[self.frame_id(sole)].parentJoint
            chain = {0, 1}  # 0: universe, 1: the floating base
            while joint > 1:
                chain.add(joint)
                joint = self.model.parents[joint]
            chains.append(chain)
        return frozenset(set.intersection(*chains))

    def stance_leg_joints(self) -> list[int]:
        """Indices of the joints of both legs (from each sole up to their branching joint), sorted."""
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
            out[leg] += _least_squares(jac, error)
            if np.any(out[leg] < self.lower[leg]) or np.any(out[leg] > self.upper[leg]):
                return None
        return None

    def velocity_indices(self) -> IntArray:
        """Indices of the actuated joints in the velocity vector. Shape (nj,)."""
        return self._v_index.copy()


def _least_squares(matrix: FloatArray, rhs: FloatArray) -> FloatArray:
    """The least-squares solution of ``matrix x = rhs`` (a square one solved directly: 3x faster)."""
    if matrix.shape[0] == matrix.shape[1]:
        try:
            return np.asarray(np.linalg.solve(matrix, rhs))
        except np.linalg.LinAlgError:
            pass
    return np.asarray(np.linalg.lstsq(matrix, rhs, rcond=None)[0])


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


def scene_for_postures(postures: Pool, path: str, config_path: str | None) -> Scene:
    """The scene a pool or selection file was made for, checked against it (model hash, joints, limits).

    Args:
        postures: The file's postures (:func:`posegen.io.load_pool`, :func:`posegen.io.load_postures`).
        path: The file, named in errors.
        config_path: Scene config; None: the one saved in the file.

    Raises:
        PosegenError: The config cannot be read, or the postures are of another robot model,
            lack its joints or leave its limits.

    Example:
        >>> scene = scene_for_postures(load_pool("plans/pool.yaml"), "plans/pool.yaml", None)

    """
    scene = scene_for(postures.provenance, config_path)
    scene.check_made_for(postures.provenance, path)
    postures.check_joints(scene.joint_names, path)
    postures.check_names([c.name for c in scene.config.chains], [s.name for s in scene.spots], path)
    postures.check_limits(scene.joint_names, scene.lower, scene.upper, path)
    return scene
