"""Write a calibrated URDF: the robot's own file, its bodies at their calibrated places.

A stack that loads only this file (pinocchio, RViz, MoveIt, a controller) finds every
link where the calibration puts it, whatever the chain's layout:

* Each chain joint's origin is its identified placement (pinocchio's convention: in the
  parent *joint* frame) written back relative to the parent *link*, undoing the fixed
  joints pinocchio merged in between.
* A sole or gripper placement moves a *body*, never only a frame: it is written into the
  deepest fixed joint of the URDF above the frame that also carries everything the
  contact is read from (fingertip frames, the point frame). When there is none (the
  frame is the link of a moving joint, as iCub's hand, or the frames hang from that
  link), the joint's child becomes an empty link ``<link>_mount`` and a fixed joint
  ``<link>_calibration_joint`` holds the placement: the link, with its meshes, inertia
  and every frame on it, moves as a whole. A revolute joint's origin never receives a
  fixed frame's placement.
* The frames the config declares (``robot.frames``) are not written into the file: they
  stand for frames a user's stack defines its own way (a tool frame, a sole, a tip)
  relative to the same links, and ride on the moved links, so that the stack's own
  definitions stay valid and become calibrated. The calibrated scene config
  (:func:`calibrated_config`) declares them again, unchanged but for point frames.
* The flush contact offsets are folded into the gripper's placement (G C Off C^-1, C the
  contact frame in the gripper frame), so that posegen's contact frame, derived from the
  fingertips relative to the gripper, is the calibrated one; the contact frame itself is
  posegen's and is not written. A point contact's offsets (and the fold's effect on it)
  go to the point frame's own placement: its fixed joint when the URDF has it, the
  calibrated config's ``robot.frames`` when the config declares it.

The file is reloaded and checked against the model before it is returned: a layout
these rules cannot represent is an error naming the frame, never a silently wrong file;
:func:`check_exportable` runs that check before any work.
"""

from __future__ import annotations

import dataclasses
import enum
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from posegen.calibrate.urdf_placement import PlacementWriter, UrdfTree, inverse
from posegen.errors import ConfigError
from posegen.model import ChainModel, ContactModel, placement_matrix
from posegen.robot import ContactKind, FloatArray, Scene, with_declared_frames

TOLERANCE = 1e-9  # m and rad: the reloaded file against the model
CHECK_DEVIATION = 1e-3  # m and rad: the deviation of every parameter in check_exportable


class _Item(enum.Enum):
    """What the reloaded file is checked for."""

    JOINT = "joint"  # a moving joint's placement in its parent joint frame
    FRAME = "frame"  # a sole or gripper frame's placement in its parent joint frame
    TIP = "tip"  # a chain's contact frame of one kind (flush contact frame, point frame) in its gripper frame


@dataclass(frozen=True)
class _Expected:
    """What the reloaded file must give."""

    item: _Item
    name: str  # the joint or frame; the chain for TIP
    transform: FloatArray  # (4, 4)
    kind: ContactKind | None = None  # TIP: the contact kind

    @property
    def title(self) -> str:
        """What the item is, in an error message."""
        return f"the {self.kind.frame_title} of chain" if self.kind is not None else self.item.value


def _triple(values: FloatArray) -> tuple[float, float, float]:
    return float(values[0]), float(values[1]), float(values[2])


def _load(urdf_text: str) -> pin.Model:
    try:
        return pin.buildModelFromXML(urdf_text, pin.JointModelFreeFlyer())
    except (RuntimeError, ValueError) as exc:
        raise ConfigError(f"cannot load the URDF to calibrate: {str(exc).strip()}") from exc


@dataclass(frozen=True)
class _Export:
    """The calibrated file and the config's frames that go with it."""

    urdf: str  # without the config's frames
    frames: tuple[Any, ...]  # the config's frames (FrameConfig), point frames at their calibrated placement


def _export(urdf_text: str, model: ContactModel, theta: FloatArray) -> _Export:
    if theta.shape != (model.size,):
        raise ValueError(f"theta has shape {theta.shape}, the model {model.size} parameters")
    scene = model.scene
    declared = scene.config.frames
    root = ET.fromstring(with_declared_frames(urdf_text, _load(urdf_text), declared))
    tree = UrdfTree(root, {f.name for f in declared})
    writer = PlacementWriter(scene, tree)
    expected: list[_Expected] = []
    done: set[str] = set()
    for chain in model.chains.values():
        placements = {e.name: placement_matrix(theta[model.placement_columns(e.name)]) for e in chain.elements}
        for element in chain.elements[1:-1]:
            if element.name not in done:
                writer.joint(element.name, placements[element.name])
                expected.append(_Expected(_Item.JOINT, element.name, placements[element.name]))
                done.add(element.name)
        expected.extend(_write_ends(writer, model, chain, placements, theta))
    tree.drop_declared()
    ET.indent(root, space="  ")  # an added mount one element per line, like the rest
    text = ET.tostring(root, encoding="unicode", xml_declaration=True)
    frames = tuple(
        dataclasses.replace(
            f,
            xyz_m=_triple(writer.moved[f.name][:3, 3]),
            rpy_deg=_triple(np.rad2deg(pin.rpy.matrixToRpy(writer.moved[f.name][:3, :3]))),
        )
        if f.name in writer.moved
        else f
        for f in declared
    )
    _check(with_declared_frames(text, _load(text), frames), scene, expected)
    return _Export(text, frames)


def calibrated_urdf(urdf_text: str, model: ContactModel, theta: FloatArray) -> str:
    """The URDF text with every chain placement set from ``theta`` (the config's frames not in it).

    Args:
        urdf_text: The original (nominal) URDF.
        model: The measurement model the parameters belong to.
        theta: (p,) identified parameters.

    Raises:
        ConfigError: A chain's layout cannot carry its placements (the frame is named).

    """
    return _export(urdf_text, model, theta).urdf


def calibrated_config(model: ContactModel, theta: FloatArray, urdf_path: Path) -> dict[str, Any]:
    """The scene config of the calibrated robot: the file at ``urdf_path``, and the config's frames.

    The frames keep their placements (they ride on the calibrated links) but a point
    frame the config declares, which takes its contact's offsets.

    Args:
        model: The measurement model the parameters belong to.
        theta: (p,) identified parameters.
        urdf_path: Where the calibrated URDF (:func:`calibrated_urdf`) is written; the
            config is written beside it and names it relatively (the folder can move, or
            be written in a staging folder and swapped in).

    Raises:
        ConfigError: A chain's layout cannot carry its placements (the frame is named).

    """
    return calibrated_robot(model.scene.files.urdf.read_text(), model, theta, urdf_path)[1]


def calibrated_robot(
    urdf_text: str, model: ContactModel, theta: FloatArray, urdf_path: Path
) -> tuple[str, dict[str, Any]]:
    """:func:`calibrated_urdf` and :func:`calibrated_config` of one export (the URDF built and checked once).

    Args:
        urdf_text: The original (nominal) URDF.
        model: The measurement model the parameters belong to.
        theta: (p,) identified parameters.
        urdf_path: Where the calibrated URDF is written (the config names it relatively).

    Raises:
        ConfigError: A chain's layout cannot carry its placements (the frame is named).

    Example:
        >>> urdf, config = calibrated_robot(nominal_text, model.contact, theta, folder / "calibrated.urdf")

    """
    scene = model.scene
    export = _export(urdf_text, model, theta)
    config = dataclasses.replace(scene.config, frames=export.frames).to_dict()
    config["robot"]["source"] = {
        "urdf": urdf_path.name,  # relative: resolved against the config's own folder, where it is written
        **({"srdf": str(scene.files.srdf)} if scene.files.srdf is not None else {}),  # a robot may have none
        "package_dirs": list(scene.files.package_dirs),
    }
    return export.urdf, config


def _write_ends(
    writer: PlacementWriter,
    model: ContactModel,
    chain: ChainModel,
    placements: dict[str, FloatArray],
    theta: FloatArray,
) -> list[_Expected]:
    """Write a chain's sole, gripper (a folded kind's offsets in it) and the frames of its other kinds.

    A folded kind's frame is derived at load from frames on the gripper (the flush contact
    frame from the fingertips): its offsets move the gripper frame itself. Another kind's
    frame (a point frame) is written at its calibrated placement under the gripper.
    """
    cfg = chain.config
    where = f"chains.{chain.chain}"
    sole, grip = chain.elements[0].name, chain.elements[-1].name
    kinds = model.kinds[chain.chain]
    folded = [kind for kind in kinds if kind.folded]
    if len(folded) > 1:
        raise ValueError(f"{where}: kinds {', '.join(k.value for k in folded)} all fold into the gripper frame")
    gripper = placements[grip]  # in the file: with the folded offsets in it
    for kind in folded:
        offsets = theta[model.tip_columns(chain.chain, kind)]
        gripper = gripper @ chain.tip(offsets, kind) @ inverse(chain.tip_nominal(kind))
    carried = [frame for kind in cfg.kinds for frame in kind.carried_frames(cfg)]
    writer.frame(sole, writer.parent_joint_world(sole), placements[sole], [], f"{where}.sole_frame")
    writer.frame(grip, writer.parent_joint_world(grip), gripper, carried, f"{where}.gripper_frame")
    out = [_Expected(_Item.FRAME, sole, placements[sole]), _Expected(_Item.FRAME, grip, gripper)]
    for kind in kinds:
        if kind.folded:
            tip = chain.tip_nominal(kind)  # derived at load: it moved with the gripper
        else:
            offsets = theta[model.tip_columns(chain.chain, kind)]
            tip = inverse(gripper) @ placements[grip] @ chain.tip(offsets, kind)  # in the file's gripper
            writer.point(kind.frame(cfg), writer.frame_world(grip), tip, f"{where}.{kind.required_field}")
        out.append(_Expected(_Item.TIP, chain.chain, tip, kind))
    return out


def _check(text: str, scene: Scene, expected: list[_Expected]) -> None:
    """Reload the file: every placement and contact frame as the model has it, else a ConfigError."""
    model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    data = model.createData()
    q = pin.neutral(model)
    for name, value in scene.config.locked_joints.items():
        q[model.joints[model.getJointId(name)].idx_q] = value
    pin.framesForwardKinematics(model, data, q)
    nominal = scene.model
    for item in expected:
        if item.item == _Item.JOINT:
            found = model.jointPlacements[model.getJointId(item.name)].homogeneous
            same_parent = (
                model.names[model.parents[model.getJointId(item.name)]]
                == nominal.names[nominal.parents[nominal.getJointId(item.name)]]
            )
        elif item.item == _Item.FRAME:
            frame = model.frames[model.getFrameId(item.name)]
            found = frame.placement.homogeneous
            parent = nominal.frames[scene.frame_id(item.name)].parentJoint
            same_parent = model.names[frame.parentJoint] == nominal.names[parent]
        else:
            assert item.kind is not None, "a tip names its kind"
            found = item.kind.placement_in_gripper(model, data, scene.chain(item.name), q)
            same_parent = True
        gap = float(np.abs(found - item.transform).max())
        if not same_parent or gap > TOLERANCE:
            raise ConfigError(
                f"the calibrated URDF cannot hold the placement of {item.title} '{item.name}' "
                f"(this layout of frames and fixed joints: off by {gap:.3g})"
            )


def check_exportable(model: ContactModel) -> None:
    """Check, before any work, that a calibration of this model can be written as a URDF.

    Exports every parameter off its nominal value by :data:`CHECK_DEVIATION` and reloads.

    Raises:
        ConfigError: A chain's layout cannot carry its placements (the frame is named).

    """
    _export(model.scene.files.urdf.read_text(), model, model.nominal() + CHECK_DEVIATION)
