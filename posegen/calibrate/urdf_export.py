"""Write a calibrated URDF: the original file with calibrated joint origins.

Link and joint names are unchanged. A placement identified in pinocchio's convention
(relative to the parent *joint* frame) is written back as the URDF origin relative to
the parent *link*, undoing any fixed joints pinocchio merged in between. The contact
offsets are folded into the gripper frame's fixed joint, so that posegen's contact
frame (derived from the fingertips) of the calibrated URDF is the calibrated one.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

from posegen.errors import InputError
from posegen.model import ContactModel, offset_matrix, placement_matrix
from posegen.robot import ContactKind, FloatArray


def _format(values: FloatArray) -> str:
    return " ".join(f"{float(v):.12g}" for v in values)


def _joint_element(root: ET.Element, *, name: str | None = None, child: str | None = None) -> ET.Element:
    for joint in root.findall("joint"):
        if name is not None and joint.get("name") == name:
            return joint
        child_el = joint.find("child")
        if child is not None and child_el is not None and child_el.get("link") == child:
            return joint
    raise InputError(f"the URDF has no joint {'named ' + name if name else 'with child ' + str(child)}")


def _set_origin(joint: ET.Element, transform: FloatArray) -> None:
    origin = joint.find("origin")
    if origin is None:
        origin = ET.SubElement(joint, "origin")
    origin.set("xyz", _format(transform[:3, 3]))
    origin.set("rpy", _format(pin.rpy.matrixToRpy(transform[:3, :3])))


def calibrated_urdf(urdf_text: str, model: ContactModel, theta: FloatArray) -> str:
    """The URDF text with every chain placement set from ``theta``.

    Args:
        urdf_text: The original (nominal) URDF.
        model: The measurement model the parameters belong to.
        theta: (p,) identified parameters.

    """
    root = ET.fromstring(urdf_text)
    pin_model = model.scene.model
    for chain in model.chains.values():
        for element in chain.elements:
            params = theta[model.placement_columns(element.name)]
            placement = placement_matrix(params)
            if element.axis is not None:  # a revolute joint: its placement in the parent joint frame
                joint = _joint_element(root, name=element.name)
                parent_link = joint.find("parent")
                assert parent_link is not None
                parent_frame = pin_model.frames[pin_model.getFrameId(parent_link.get("link"))]
            else:  # a fixed frame (sole, gripper): the fixed joint whose child it is
                joint = _joint_element(root, child=element.name)
                parent_link = joint.find("parent")
                assert parent_link is not None
                parent_frame = pin_model.frames[pin_model.getFrameId(parent_link.get("link"))]
                c_nom = chain.contact_nominal
                if element.name == chain.elements[-1].name and model.kinds[chain.chain] == (ContactKind.FLUSH,):
                    # gripper: absorb the flush contact offsets (with point contacts too, they
                    # would move the point: the offsets stay in calibration.yaml)
                    assert c_nom is not None
                    offsets = theta[model.contact_columns(chain.contact_frame)]
                    placement = placement @ c_nom @ offset_matrix(*offsets) @ np.linalg.inv(c_nom)
            # origin = (parent link in parent joint frame)^-1 * placement in parent joint frame
            _set_origin(joint, np.linalg.inv(parent_frame.placement.homogeneous) @ placement)
    return ET.tostring(root, encoding="unicode", xml_declaration=True)
