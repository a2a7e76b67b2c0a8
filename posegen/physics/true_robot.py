"""The perturbed robot and table a physics rehearsal runs: the robot ``posegen simulate`` makes.

The true parameters are drawn exactly as ``posegen simulate --bag`` draws them
(:func:`posegen.calibrate.perturbed_robot`, every chain of the config, one table
session), and the true robot is its URDF: every chain placement written at its true
value by the calibrated-URDF export (:func:`posegen.calibrate.calibrated_urdf`), so
that the bodies themselves are where the errors put them. A joint's zero offset is a
rotation of its placement about its own axis: MuJoCo's joint angle is then the angle
the calibration model reads, the one a real encoder reads. The flush contact offsets
are folded into the gripper's placement (the fingertips move with it); a point
contact's offsets move its point frame.

The table's top face is the true plane of the session: the plane parameters are the
plane's height, roll and pitch in the anchor sole frame, at the anchor sole's place of
the reference stance. Compliance, when drawn, becomes passive spring joints
(:mod:`posegen.physics.builder`).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from posegen.calibrate import Perturbation, calibrated_robot, floor_constants, perturbed_robot
from posegen.model import CalibrationModel, Parameter
from posegen.robot import FloatArray, Scene, offset_matrix, parse_config, with_declared_frames


@dataclass(frozen=True)
class TrueRobot:
    """A perturbed robot: its URDF, its parameters and where its table is."""

    urdf: str  # the robot's URDF, the config's frames declared in it
    model: CalibrationModel  # every chain of the config, one session
    x: FloatArray  # (nx,) true parameters of ``model``
    session: str
    table_top: FloatArray  # (4, 4) world pose of the table's top face centre (on the true plane)
    springs: dict[str, float]  # joint -> true compliance, rad/N m


def plane_in_anchor(model: CalibrationModel, x: FloatArray, session: str) -> FloatArray:
    """The true table plane's frame in the anchor sole frame: Trans(0, 0, z) Rot_rpy(roll, pitch, 0). Shape (4, 4)."""
    contact = model.contact
    z, roll, pitch = (float(x[contact.column(Parameter.plane(session, f))]) for f in ("z", "roll", "pitch"))
    return offset_matrix(z, roll, pitch)


def table_top_pose(scene: Scene, plane_world: FloatArray) -> FloatArray:
    """The table's top face centre on a plane (4, 4 world frame): below or above the config's centre.

    Its axes are the plane's, turned to the config's yaw about the plane normal.
    """
    normal = plane_world[:3, 2]
    centre = np.asarray(scene.table_pose[:3, 3], dtype=float)
    height = (normal @ (plane_world[:3, 3] - centre)) / normal[2]  # along world z, to the plane
    yaw = scene.table_pose[:3, :3]
    x_axis = yaw[:, 0] - (yaw[:, 0] @ normal) * normal
    x_axis /= np.linalg.norm(x_axis)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x_axis, np.cross(normal, x_axis), normal])
    pose[:3, 3] = centre + np.array([0.0, 0.0, height])
    return pose


def _springs(model: CalibrationModel, x: FloatArray) -> dict[str, float]:
    names = model.scene.joint_names
    out: dict[str, float] = {}
    for group, value in model.compliances(x).items():
        for index in model.compliance[group]:
            if value > 0:
                out[names[index]] = value
    return out


def perturbed_urdf(scene: Scene, model: CalibrationModel, x: FloatArray) -> str:
    """The URDF of a perturbed robot, with the config's frames declared in it.

    The config's frames ride on the perturbed links, but a declared point frame, which
    takes its contact's offsets (:func:`posegen.calibrate.calibrated_config`).
    """
    with tempfile.TemporaryDirectory() as folder:  # the export names the file; nothing is written
        text, config = calibrated_robot(scene.files.urdf_text(), model.contact, model.theta(x), Path(folder) / "t.urdf")
    frames = parse_config(config, "").frames
    return with_declared_frames(text, pin.buildModelFromXML(text, pin.JointModelFreeFlyer()), frames)


def draw_true_robot(scene: Scene, session: str, perturbation: Perturbation, seed: int) -> TrueRobot:
    """The robot ``posegen simulate --bag`` draws for a seed (every chain), as a URDF and a table.

    Args:
        scene: The nominal scene.
        session: Table session (names the true plane).
        perturbation: Error sizes (placements, plane tilt, compliance; the contact noise is not physical here).
        seed: Seed of the errors.

    Raises:
        PosegenError: A compliance group the config lacks, or a layout the URDF export cannot write.

    Example:
        >>> robot = draw_true_robot(scene, "sim", Perturbation(), seed=7)

    """
    chains = tuple(c.name for c in scene.config.chains)
    kinds = {c: (scene.chain(c).contact_kind,) for c in chains}
    model, x = perturbed_robot(scene, chains, [session], perturbation, seed, kinds)
    plane = scene.sole_poses[scene.anchor_sole] @ plane_in_anchor(model, x, session)
    return TrueRobot(
        perturbed_urdf(scene, model, x), model, x, session, table_top_pose(scene, plane), _springs(model, x)
    )


def plane_offsets(plane: FloatArray) -> tuple[float, float, float]:
    """A plane's height z (m, along the frame's z at its origin), roll and pitch (rad), from a frame on it (4, 4).

    The inverse of :func:`posegen.robot.offset_matrix` up to the frame's place and yaw in the
    plane: ``offset_matrix(*plane_offsets(frame))`` lies on the same plane.

    Example:
        >>> tuple(round(v, 9) for v in plane_offsets(offset_matrix(0.68, 0.01, -0.02)))
        (0.68, 0.01, -0.02)

    """
    normal, point = plane[:3, 2], plane[:3, 3]
    return float(normal @ point / normal[2]), float(-np.arcsin(normal[1])), float(np.arctan2(normal[0], normal[2]))


def as_stood(robot: TrueRobot, soles: tuple[FloatArray, ...]) -> FloatArray:
    """The true parameters (nx,) with the plane and the floor constants as the robot stood when the route started.

    The table is where it was put; the soles are where the robot put them down (the
    second leg closed on the floor, the run's settling): the plane's height, roll and
    pitch are read in the anchor sole's frame, the second sole's x, y and yaw in the
    anchor's, as :func:`posegen.calibrate.true_parameters` defines them.

    Args:
        robot: The true robot.
        soles: Each true sole frame's world pose (4, 4), stance order, when the route starts.

    """
    model, x = robot.model, robot.x.copy()
    anchor_inverse = np.linalg.inv(soles[0])
    values = plane_offsets(anchor_inverse @ robot.table_top)
    for name, value in zip(("z", "roll", "pitch"), values, strict=True):
        x[model.contact.column(Parameter.plane(robot.session, name))] = value
    x[model.floor_columns(robot.session)] = floor_constants(anchor_inverse @ soles[1])
    return x
