"""An MJCF element's attributes through its class, its body's ``childclass`` and ``main``, as MuJoCo resolves them."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from posegen.draft.mjcf_classes import class_defaults, resolved, write_resolved
from posegen.errors import ConfigError

DEFAULTS = """<default>
    <joint damping="1"/><geom type="box" size="0.1 0.1 0.1"/>
    <default class="limb"><joint ref="0.2" pos="0 0 0.1"/><geom pos="0.05 0 0" contype="0"/>
      <default class="bent"><joint ref="0.4" axis="1 0 0"/></default>
    </default>
  </default>"""


def _parse(body: str) -> ET.Element:
    return ET.fromstring(f"<mujoco>{DEFAULTS}<worldbody>{body}</worldbody></mujoco>")


def test_a_class_default_is_inherited_through_nested_classes():
    classes = class_defaults(_parse(""), "joint")
    assert classes["main"] == {"damping": "1"}
    assert classes["limb"] == {"damping": "1", "ref": "0.2", "pos": "0 0 0.1"}
    assert classes["bent"] == {"damping": "1", "ref": "0.4", "pos": "0 0 0.1", "axis": "1 0 0"}
    assert class_defaults(_parse(""), "geom")["bent"] == {
        "type": "box", "size": "0.1 0.1 0.1", "pos": "0.05 0 0", "contype": "0",
    }  # fmt: skip


def test_an_element_reads_its_class_else_the_nearest_childclass_else_main():
    body = """<body name="trunk" childclass="bent">
        <joint name="own" class="main"/><joint name="inherited"/>
        <body name="arm"><joint name="deeper" class="limb"/><geom name="g"/></body>
      </body>"""
    joints = {e.get("name"): a for _, e, a in resolved(_parse(body), Path("robot.xml"), "joint")}
    assert joints["own"] == {"damping": "1", "class": "main", "name": "own"}
    assert joints["inherited"]["axis"] == "1 0 0"
    assert "axis" not in joints["deeper"] and joints["deeper"]["ref"] == "0.2"
    ((body_element, _, geom),) = resolved(_parse(body), Path("robot.xml"), "geom")
    assert body_element.get("name") == "arm" and geom["contype"] == "0"  # the childclass reaches the arm's geom


def test_what_a_class_gives_is_written_on_the_element_and_what_no_class_gives_is_mujocos_default():
    """pinocchio skipped a class's ``pos`` and laid the body's ``childclass`` over an element's own ``class``."""
    body = """<body name="trunk" childclass="bent">
        <joint name="own" class="main"/><joint name="inherited" axis="0 1 0"/>
        <geom name="box" class="main"/><geom name="tube" type="capsule" fromto="0 0 0 0 0 1" size="0.02"/>
      </body>"""
    root = _parse(body)
    write_resolved(root, Path("robot.xml"))
    own, inherited = root.find("worldbody").iter("joint")
    assert own.attrib == {"class": "main", "name": "own", "type": "hinge", "axis": "0 0 1", "pos": "0 0 0", "ref": "0"}
    assert (inherited.get("axis"), inherited.get("pos"), inherited.get("ref")) == ("0 1 0", "0 0 0.1", "0.4")
    box, tube = root.find("worldbody").iter("geom")
    assert (box.get("contype"), box.get("pos"), box.get("size")) == ("1", "0 0 0", "0.1 0.1 0.1")
    assert tube.get("pos") is None and tube.get("quat") is None  # placed by its fromto
    assert tube.get("contype") == "0"


def test_a_class_no_default_defines_is_one_line():
    with pytest.raises(ConfigError, match=r"robot\.xml: geom class 'none' has no <default class=\"none\">"):
        list(resolved(_parse('<body><geom class="none"/></body>'), Path("robot.xml"), "geom"))


def test_a_ball_joint_is_left_as_written():
    """An axis written on a ball joint makes pinocchio refuse the file before posegen names the joint."""
    root = _parse('<body childclass="bent"><joint name="ball" type="ball"/></body>')
    write_resolved(root, Path("robot.xml"))
    assert root.find("worldbody").find(".//joint").attrib == {"name": "ball", "type": "ball"}
