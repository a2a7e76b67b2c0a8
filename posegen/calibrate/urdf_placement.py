"""Where a placement goes in a URDF: the fixed joint above a frame, or a mount under a moving joint.

The URDF is edited as an element tree. Every transform is read from the scene's nominal
model at the locked configuration (fingertips and points where the model has them); a
placement is given in a reference frame (its parent joint's, or the gripper's) and
written relative to the URDF element that holds it (see :mod:`posegen.calibrate.urdf_export`).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.robot import FloatArray, Scene


def _format(values: FloatArray) -> str:
    return " ".join(f"{float(v):.12g}" for v in values)


def _set_origin(joint: ET.Element, transform: FloatArray) -> None:
    origin = joint.find("origin")
    if origin is None:
        origin = ET.SubElement(joint, "origin")
    origin.set("xyz", _format(transform[:3, 3]))
    origin.set("rpy", _format(pin.rpy.matrixToRpy(transform[:3, :3])))


def inverse(transform: FloatArray) -> FloatArray:
    """Inverse of a (4, 4) transform."""
    return np.asarray(np.linalg.inv(transform))


class UrdfTree:
    """The URDF's links and joints, edited in place."""

    def __init__(self, root: ET.Element, declared: set[str]) -> None:
        self.root = root
        self.declared = declared  # the config's frames: links under fixed joints, never written
        self.links = {str(link.get("name")) for link in root.findall("link")}
        self.joints = {str(joint.get("name")): joint for joint in root.findall("joint")}
        self.above: dict[str, ET.Element] = {}  # link -> the joint whose child it is
        for joint in self.joints.values():
            self.above[self._end(joint, "child")] = joint

    @staticmethod
    def _end(joint: ET.Element, tag: str) -> str:
        end = joint.find(tag)
        return "" if end is None else str(end.get("link"))

    def parent(self, joint: ET.Element) -> str:
        """A joint's parent link."""
        return self._end(joint, "parent")

    def link_of(self, frame: str) -> str:
        """The link a frame names: a link, or the child of a joint of that name."""
        if frame in self.links:
            return frame
        return self._end(self.joints[frame], "child")

    def fixed_path(self, link: str) -> list[str]:
        """Links from the child link of the nearest moving joint (or the root) down to ``link``."""
        path = [link]
        while path[0] in self.above and self.above[path[0]].get("type") == "fixed":
            path.insert(0, self.parent(self.above[path[0]]))
        return path

    def is_below(self, link: str, ancestor: str) -> bool:
        """Whether ``link`` is ``ancestor`` or in its subtree."""
        while link != ancestor and link in self.above:
            link = self.parent(self.above[link])
        return link == ancestor

    def drop_declared(self) -> None:
        """Remove the config's frames (their calibrated scene config declares them)."""
        for link in self.root.findall("link"):
            if link.get("name") in self.declared:
                self.root.remove(link)
                self.root.remove(self.above[str(link.get("name"))])

    def insert_mount(self, link: str, where: str) -> ET.Element:
        """Make the moving joint above ``link`` end at a new empty link, fixed to ``link`` by a new joint."""
        mount, name = f"{link}_mount", f"{link}_calibration_joint"
        if link not in self.above:
            raise ConfigError(f"{where}: '{link}' is the root link: no joint of the URDF can carry its placement")
        if mount in self.links or name in self.joints:
            raise ConfigError(f"{where}: the calibrated URDF needs a link '{mount}' and a joint '{name}': taken")
        moving = self.above[link]
        child = moving.find("child")
        assert child is not None
        child.set("link", mount)
        ET.SubElement(self.root, "link", name=mount)
        joint = ET.SubElement(self.root, "joint", name=name, type="fixed")
        ET.SubElement(joint, "parent", link=mount)
        ET.SubElement(joint, "child", link=link)
        self.links.add(mount)
        self.joints[name] = joint
        self.above[mount], self.above[link] = moving, joint
        return joint


class PlacementWriter:
    """Writes placements into the tree, every transform read from the scene's nominal model."""

    def __init__(self, scene: Scene, tree: UrdfTree) -> None:
        self.scene = scene
        self.tree = tree
        self.moved: dict[str, FloatArray] = {}  # a declared frame -> its calibrated placement in its parent link
        self.data = scene.model.createData()  # at the locked configuration: fingertips and points as modelled
        pin.framesForwardKinematics(scene.model, self.data, scene.model_configuration(scene.locked_values))

    def frame_world(self, name: str) -> FloatArray:
        """A frame's nominal world placement. Shape (4, 4)."""
        return np.array(self.data.oMf[self.scene.frame_id(name)].homogeneous)

    def joint_world(self, joint: int) -> FloatArray:
        """A joint frame's nominal world placement (pinocchio joint id). Shape (4, 4)."""
        return np.array(self.data.oMi[joint].homogeneous)

    def parent_joint_world(self, frame: str) -> FloatArray:
        """Nominal world placement of the moving joint a frame hangs from. Shape (4, 4)."""
        return self.joint_world(self.scene.model.frames[self.scene.frame_id(frame)].parentJoint)

    def joint(self, name: str, placement: FloatArray) -> None:
        """A moving joint's origin from its placement in its parent joint frame."""
        model = self.scene.model
        joint = self.tree.joints[name]
        reference = self.joint_world(model.parents[model.getJointId(name)])
        _set_origin(joint, inverse(inverse(reference) @ self.frame_world(self.tree.parent(joint))) @ placement)

    def frame(self, frame: str, reference: FloatArray, target: FloatArray, carried: list[str], where: str) -> None:
        """Place ``frame`` at ``target`` in the frame at world ``reference`` (4, 4), moving ``carried`` with it."""
        tree = self.tree
        if frame not in tree.links and (frame not in tree.joints or tree.joints[frame].get("type") != "fixed"):
            raise ConfigError(f"{where}: '{frame}' is neither a link nor a fixed joint: no URDF origin places it")
        path = tree.fixed_path(tree.link_of(frame))
        carried_links = [tree.link_of(f) for f in carried]
        deepest = max(
            (
                i
                for i in range(1, len(path))
                if path[i] not in tree.declared and all(tree.is_below(c, path[i]) for c in carried_links)
            ),
            default=0,
        )
        if deepest:
            joint = tree.above[path[deepest]]
            parent = self.frame_world(path[deepest - 1])
        else:
            parent = self.frame_world(path[0])  # the moving joint's frame, where the mount sits
            joint = tree.insert_mount(path[0], where)
        below = inverse(self.frame_world(path[deepest])) @ self.frame_world(frame)  # fixed, moved along
        _set_origin(joint, inverse(inverse(reference) @ parent) @ target @ inverse(below))

    def point(self, frame: str, reference: FloatArray, target: FloatArray, where: str) -> None:
        """Place a point frame at ``target`` in the frame at world ``reference``: its own placement only."""
        if frame not in self.tree.declared:
            self.frame(frame, reference, target, [], where)
            return
        parent = self.frame_world(self.tree.parent(self.tree.above[frame]))
        self.moved[frame] = inverse(inverse(reference) @ parent) @ target
