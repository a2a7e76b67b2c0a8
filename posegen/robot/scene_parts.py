"""The parts a :class:`~posegen.robot.scene.Scene` is built from, one step each.

:meth:`Scene.from_config <posegen.robot.scene.Scene.from_config>` runs them in order:

1. :func:`load_description`: the URDF (and SRDF) the config names, with its declared frames;
2. :func:`check_names`: every frame and link the config names exists in it;
3. :func:`apply_additions`: the augmented URDF (contact frames) and its model;
4. :func:`actuated_joints`: joint limits, the locked joints and velocity limits, checked;
5. :func:`read_srdf_states` and :func:`reference_configuration`: the reference posture;
6. :func:`stand`: the soles' poses on the floor and the support polygon;
7. :func:`table_pose` and :func:`table_spots`: the table and its contact spots.

Each step is a function of what the previous ones made, testable alone; each raises
:class:`~posegen.errors.ConfigError` naming the config field at fault.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from posegen.errors import ConfigError, unknown_name
from posegen.io import native_output, read_text_file
from posegen.robot.collision_geometry import check_link_names
from posegen.robot.config import ChainConfig, Config, StanceConfig, TableConfig
from posegen.robot.config_sections import leaves_no_room
from posegen.robot.description import (
    RobotFiles,
    augmented_urdf,
    contact_placement,
    frame_id,
    locked_configuration,
    resolve_robot_files,
    with_declared_frames,
)
from posegen.robot.geometry import FloatArray, convex_hull_clockwise, flatten_on_floor, yaw_rotation

IntArray = npt.NDArray[np.int_]


@dataclass(frozen=True)
class Spot:
    """A contact target spot on the table."""

    name: str
    xy_table_m: tuple[float, float]  # in the table frame
    chains: tuple[str, ...]  # chains whose arm serves this spot


@dataclass(frozen=True, eq=False)
class Description:
    """The robot description the config names, with the frames it declares (before posegen's additions)."""

    files: RobotFiles
    urdf_text: str  # the URDF with the declared frames, mesh paths absolute
    model: pin.Model  # its model, with a free-flyer root


@dataclass(frozen=True, eq=False)
class Joints:
    """The actuated (1-dof) joints of a model, in model order, with their limits and locks."""

    names: tuple[str, ...]
    q_index: IntArray  # (nj,) their indices in the configuration vector
    v_index: IntArray  # (nj,) their indices in the velocity vector
    lower: FloatArray  # (nj,) rad
    upper: FloatArray  # (nj,) rad
    locked: npt.NDArray[np.bool_]  # (nj,) held during sampling
    locked_values: FloatArray  # (nj,) rad, where locked (0 elsewhere)
    velocity_limit: FloatArray  # (nj,) rad/s
    effort_limit: FloatArray  # (nj,) N m, the URDF's; nan where it gives none (0)
    limit_margin: FloatArray  # (nj,) rad kept from each limit: margins.joint_limit_rad, or the joint's own

    def index(self, name: str, field: str) -> int:
        """Index of joint ``name``.

        Raises:
            ConfigError: No actuated joint has that name (``field`` says which config field named it).

        """
        return _joint_index(self.names, name, field)


def _joint_index(names: tuple[str, ...], name: str, field: str) -> int:
    if name not in names:
        raise ConfigError(unknown_name("joint", name, names) + f" ({field})")
    return names.index(name)


def _model_from_xml(urdf_text: str) -> pin.Model:
    """The model of a URDF's text; urdfdom's own lines are kept off the terminal (the error gives their cause)."""
    failure: Exception
    with native_output() as printed:
        try:
            return pin.buildModelFromXML(urdf_text, pin.JointModelFreeFlyer())
        except (RuntimeError, ValueError) as exc:
            failure = exc
    cause = printed.cause()
    raise ValueError(f"{failure} ({cause})" if cause else str(failure)) from failure


def load_description(config: Config) -> Description:
    """Step 1: the URDF the config names, loaded, with ``robot.frames`` declared in it.

    Raises:
        ConfigError: The files are missing or the URDF does not load.

    """
    files = resolve_robot_files(config)
    nominal_text = files.urdf_text()
    try:
        nominal = _model_from_xml(nominal_text)
    except (RuntimeError, ValueError) as exc:
        raise ConfigError(f"cannot load URDF {files.urdf}: {exc}") from exc
    declared_text = with_declared_frames(nominal_text, nominal, config.frames)
    return Description(files, declared_text, _model_from_xml(declared_text))


def check_names(model: pin.Model, config: Config) -> None:
    """Step 2: every frame the chains and the stance name, and every link of ``robot.collision``, exists.

    Raises:
        ConfigError: A name the model lacks (the valid ones suggested), a contact frame
            posegen would add that the model already has, a fingertip the gripper does not
            carry, or a chain's sole the robot does not stand on.

    """
    for chain in config.chains:
        for field, frames in (
            ("sole_frame", [chain.sole_frame]),
            ("gripper_frame", [chain.gripper_frame]),
            ("fingertip_frames", chain.fingertip_frames),
            ("point_frame", [chain.point_frame] if chain.point_frame else []),
            ("touching_links", chain.touching_links),
            ("wrench_frame", [chain.wrench_frame] if chain.wrench_frame else []),
        ):
            for frame in frames:
                _named_frame(model, frame, f"chains.{chain.name}.{field}")
        if chain.fingertip_frames and model.existFrame(chain.contact_frame):
            raise ConfigError(f"chains.{chain.name}.contact_frame '{chain.contact_frame}' already exists")
    for field, frames in (
        ("sole_frames", config.stance.sole_frames),
        ("floor_contact_frames", config.stance.floor_contact_frames),
    ):
        for frame in frames:
            _named_frame(model, frame, f"stance.{field}")
    check_link_names(model, config.collision)
    for chain in config.chains:
        for field, frames in (("fingertip_frames", chain.fingertip_frames), ("point_frame", [chain.point_frame])):
            for frame in (f for f in frames if f and not _carried_by(model, f, chain.gripper_frame)):
                raise ConfigError(
                    f"chains.{chain.name}.{field}: '{frame}' is not carried by the chain's gripper_frame "
                    f"'{chain.gripper_frame}' (another arm's?)"
                )
        if chain.sole_frame not in config.stance.sole_frames:
            raise ConfigError(
                f"chains.{chain.name}.sole_frame: '{chain.sole_frame}' is not one of stance.sole_frames "
                f"({', '.join(config.stance.sole_frames)})"
            )


def _carried_by(model: pin.Model, frame: str, carrier: str) -> bool:
    """Whether ``frame`` moves with ``carrier``: its joint is ``carrier``'s or one after it."""
    joint, above = (model.frames[model.getFrameId(name)].parentJoint for name in (frame, carrier))
    while joint > above:
        joint = model.parents[joint]
    return bool(joint == above)


def _named_frame(model: pin.Model, name: str, field: str) -> None:
    if not model.existFrame(name):
        raise ConfigError(unknown_name("frame", name, (f.name for f in model.frames)) + f" ({field})")


def apply_additions(description: Description, config: Config) -> tuple[str, pin.Model]:
    """Step 3: the augmented URDF (a contact frame per flush chain, read with the fingers locked) and its model."""
    held = locked_configuration(description.model, config.locked_joints)
    urdf_xml = augmented_urdf(description.urdf_text, description.model, config, held)
    return urdf_xml, _model_from_xml(urdf_xml)


def actuated_joints(model: pin.Model, config: Config) -> Joints:
    """Step 4: the actuated joints, their limits, ``robot.locked_joints`` and velocity limits, checked.

    Raises:
        ConfigError: A locked joint unknown or outside its limits, or a free joint without
            a velocity limit.

    """
    for j in range(2, model.njoints):  # 1: the floating base
        if model.joints[j].nq != 1:
            raise ConfigError(
                f"robot: joint '{model.names[j]}' is a {model.joints[j].shortname()} ({model.joints[j].nq} values): "
                "posegen plans joints of one angle or length between limits; make it revolute (or fixed) with "
                "its limits in the URDF"
            )
    names = tuple(str(model.names[j]) for j in range(2, model.njoints))  # each of one value (checked above)
    q_index = np.array([model.joints[model.getJointId(n)].idx_q for n in names])
    v_index = np.array([model.joints[model.getJointId(n)].idx_v for n in names])
    lower = model.lowerPositionLimit[q_index].copy()
    upper = model.upperPositionLimit[q_index].copy()
    reversed_limits = np.flatnonzero(~(lower <= upper))
    if len(reversed_limits):
        i = reversed_limits[0]
        raise ConfigError(f"robot: joint '{names[i]}': its lower limit {lower[i]:g} is above its upper {upper[i]:g}")
    locked = np.zeros(len(names), dtype=bool)
    locked_values = np.zeros(len(names))
    for name, value in config.locked_joints.items():
        i = _joint_index(names, name, "robot.locked_joints")
        if not lower[i] <= value <= upper[i]:
            raise ConfigError(f"robot.locked_joints.{name}: {value} rad is outside [{lower[i]}, {upper[i]}]")
        locked[i] = True
        locked_values[i] = value
    limit = velocity_limits(model.velocityLimit[v_index], names, locked, config.velocity_limits)
    effort = np.array(model.effortLimit[v_index], dtype=float)
    effort[~(np.isfinite(effort) & (effort > 0))] = np.nan  # a URDF without an effort gives 0
    margin = limit_margins(names, lower, upper, config, locked)
    return Joints(names, q_index, v_index, lower, upper, locked, locked_values, limit, effort, margin)


def limit_margins(
    names: tuple[str, ...], lower: FloatArray, upper: FloatArray, config: Config, locked: npt.NDArray[np.bool_]
) -> FloatArray:
    """The margin (rad) kept from each joint's limits: ``margins.joint_limit_rad`` or the joint's own. Shape (nj,).

    ``margins.joint_limit_rad_by_joint`` gives a joint a larger margin, e.g. a stance knee
    kept bent so that its leg can still lengthen on a robot whose legs are not the model's.
    A locked joint (``locked``, (nj,)) whose range is narrower than twice the margin (a
    gripper's finger, 2 cm) keeps none: it never moves.

    Raises:
        ConfigError: An unknown joint, or a margin leaving no room between the limits.

    """
    margin = np.full(len(names), config.margins.joint_limit_rad)
    narrow = leaves_no_room(lower, upper, margin)  # (nj,)
    margin[narrow & locked] = 0.0
    narrow &= ~locked
    if narrow.any():
        i = int(np.flatnonzero(narrow)[0])
        raise ConfigError(
            f"margins.joint_limit_rad: {margin[i]:g} rad from both limits leaves no room for joint '{names[i]}' "
            f"in [{lower[i]:.3f}, {upper[i]:.3f}]: lock it (robot.locked_joints) or lower the margin"
        )
    field = "margins.joint_limit_rad_by_joint"
    for name, value in config.margins.joint_limit_rad_by_joint.items():
        i = _joint_index(names, name, field)
        if leaves_no_room(lower[i], upper[i], value):
            raise ConfigError(
                f"{field}.{name}: {value} rad from both limits leaves no room in [{lower[i]:.3f}, {upper[i]:.3f}] rad"
            )
        margin[i] = value
    return margin


def velocity_limits(
    urdf_limit: FloatArray, names: tuple[str, ...], locked: npt.NDArray[np.bool_], overrides: dict[str, float]
) -> FloatArray:
    """URDF velocity limits (rad/s) with the config's overrides. Shape (nj,).

    A free joint needs a positive limit. A locked one never moves: a missing limit
    (0 in some URDFs) is replaced by the largest free one, so that it never binds.

    Args:
        urdf_limit: The URDF's limits (rad/s), shape (nj,); not modified.
        names: The actuated joints' names, shape (nj,).
        locked: Which of them are locked, shape (nj,).
        overrides: ``robot.velocity_limits_rad_s``, joint name -> rad/s.

    Raises:
        ConfigError: An override names an unknown joint, or a free joint has no limit.

    """
    limit = np.array(urdf_limit, dtype=float)
    for name, value in overrides.items():
        limit[_joint_index(names, name, "robot.velocity_limits_rad_s")] = value
    missing = [n for i, n in enumerate(names) if not locked[i] and not limit[i] > 0]
    if missing:
        raise ConfigError(
            f"robot.velocity_limits_rad_s: the URDF gives no velocity limit (0 rad/s) for {', '.join(missing)}; "
            "declare one for each, or lock the joint"
        )
    free = limit[~locked]
    limit[locked & ~(limit > 0)] = float(free.max()) if len(free) else 1.0
    return limit


def contact_placements(
    model: pin.Model, chains: tuple[ChainConfig, ...], held: FloatArray
) -> tuple[dict[str, pin.SE3], dict[str, pin.SE3]]:
    """The flush contact frames and the point frames in their gripper frames, by chain, at ``held`` (nq,)."""
    flush = {chain.name: contact_placement(model, chain, held) for chain in chains if chain.fingertip_frames}
    data = model.createData()
    pin.framesForwardKinematics(model, data, held)

    def placement_in(parent: str, frame: str) -> pin.SE3:
        return data.oMf[frame_id(model, parent)].actInv(data.oMf[frame_id(model, frame)])

    point = {chain.name: placement_in(chain.gripper_frame, chain.point_frame) for chain in chains if chain.point_frame}
    return flush, point


def read_srdf_states(model: pin.Model, files: RobotFiles) -> None:
    """Step 5a: the SRDF's group states, added to ``model.referenceConfigurations`` (none without an SRDF).

    Raises:
        ConfigError: The SRDF is unreadable or malformed, or its states name none of the model's joints.

    """
    if files.srdf is None:
        return
    text = read_text_file(files.srdf, ConfigError)  # a clear error for a binary or unreadable SRDF
    try:
        named = {str(j.get("name")) for j in ET.fromstring(text).iter("joint") if j.get("name")}
        pin.loadReferenceConfigurations(model, str(files.srdf), False)
    except (ET.ParseError, RuntimeError, ValueError) as exc:
        raise ConfigError(f"cannot read SRDF {files.srdf}: {str(exc).strip().splitlines()[0]}") from exc
    moving = {n for n, j in zip(model.names, model.joints, strict=True) if j.nq == 1}  # not the world, the free flyer
    if named and not named & moving:
        raise ConfigError(
            f"SRDF {files.srdf} names none of this robot's joints (such as '{min(named)}'): another robot's SRDF?"
        )


def reference_configuration(model: pin.Model, stance: StanceConfig, joints: Joints) -> FloatArray:
    """Step 5b: the reference posture, an SRDF state (or every joint at 0) with the config's overrides. Shape (nq,).

    The root's orientation: the state's, or ``stance.root_rpy_deg`` (a model whose up axis is not z).

    Raises:
        ConfigError: The posture names no SRDF state, or an override names an unknown joint.

    """
    postures = {str(e.key()): np.array(e.data()) for e in model.referenceConfigurations}
    name = stance.reference_posture
    if name and not postures:
        raise ConfigError(
            f"stance.reference_posture: '{name}' names an SRDF state but the robot has no SRDF; "
            "give the posture as stance.reference_joints (and stance.root_rpy_deg), or name an SRDF"
        )
    if name and name not in postures:
        raise ConfigError(unknown_name("reference posture", name, postures) + " (stance.reference_posture)")
    q = postures[name].copy() if name else pin.neutral(model)
    for joint, value in stance.reference_joints.items():
        q[joints.q_index[joints.index(joint, "stance.reference_joints")]] = value
    if stance.root_rpy_deg is not None:
        rotation = pin.rpy.rpyToMatrix(*np.deg2rad(stance.root_rpy_deg))
        q[3:7] = pin.Quaternion(rotation).coeffs()
    return np.asarray(q)


def stand(model: pin.Model, stance: StanceConfig, reference: FloatArray) -> tuple[dict[str, FloatArray], FloatArray]:
    """Step 6: the soles' world poses at the reference, flattened on the floor, and the support polygon.

    Args:
        model: The scene's model.
        stance: The stance config (sole frames and footprint).
        reference: The reference configuration, shape (nq,).

    Returns:
        The pose (4, 4) of each sole frame, by name, and the clockwise support polygon (m), shape (h, 2).

    """
    data = model.createData()
    pin.framesForwardKinematics(model, data, reference)
    sole_poses = {f: flatten_on_floor(data.oMf[model.getFrameId(f)].homogeneous) for f in stance.sole_frames}
    corners = [
        (pose @ np.array([x, y, 0.0, 1.0]))[:2]
        for pose in sole_poses.values()
        for x in stance.foot_x_m
        for y in stance.foot_y_m
    ]
    return sole_poses, convex_hull_clockwise(np.array(corners))


def table_pose(table: TableConfig) -> FloatArray:
    """Step 7a: the world pose of the table's top face centre. Shape (4, 4)."""
    pose = np.eye(4)
    pose[:3, :3] = yaw_rotation(np.deg2rad(table.yaw_deg))
    pose[:3, 3] = table.top_center_m
    return pose


def table_spots(table: TableConfig, chains: tuple[ChainConfig, ...]) -> tuple[Spot, ...]:
    """Step 7b: the contact spots of the table's grid, x major, each with the chains whose y range covers it."""
    return tuple(
        Spot(
            name=f"contact_{i * len(table.spots_y_m) + j:02d}",
            xy_table_m=(x, y),
            chains=tuple(c.name for c in chains if c.spot_y_range_m[0] <= y <= c.spot_y_range_m[1]),
        )
        for i, x in enumerate(table.spots_x_m)
        for j, y in enumerate(table.spots_y_m)
    )
