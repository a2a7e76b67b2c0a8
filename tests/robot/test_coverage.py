"""Which moving links have collision geometry (their own, or their body's), and how check says what it used."""

from __future__ import annotations

import pinocchio as pin
import pytest

from posegen.robot import bare_links, left_out_m, link_masses
from posegen.robot.coverage import GeometryCoverage, visual_geometry


def _link(name: str, mass: float, visual: str = "", collision: str = "") -> str:
    inertial = f'<inertial><mass value="{mass}"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/>'
    inertial += "</inertial>"
    return f'<link name="{name}">{inertial if mass else ""}{visual}{collision}</link>'


def _box(kind: str, z: float, size: str) -> str:
    return f'<{kind}><origin xyz="0 0 {z}"/><geometry><box size="{size}"/></geometry></{kind}>'


def _joint(name: str, parent: str, child: str, z: float, kind: str = "revolute") -> str:
    limit = '<axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="10" velocity="3"/>' if kind == "revolute" else ""
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="0 0 {z}"/>{limit}</joint>'
    )


# An arm: a forearm without geometry (mass, 25 cm long), a wrist with a 4 cm box, and fixed to it a palm
# 10 cm below with a visual box only, a sensor's small visual box inside the wrist's box, a massive
# frame without geometry; a massive link between coincident joints; a torso whose collision disc
# leaves its tall visual box out.
ARM = (
    "<robot name='arm'>"
    + _link("base", 1.0, _box("visual", 0.2, "0.2 0.3 0.39"), _box("collision", 0.2, "0.06 0.06 0.01"))
    + _link("knuckle", 0.3)
    + _link("forearm", 1.0)
    + _link("wrist", 0.3, _box("visual", 0, "0.04 0.04 0.04"), _box("collision", 0, "0.04 0.04 0.04"))
    + _link("palm", 0.14, _box("visual", -0.1, "0.08 0.03 0.1"))
    + _link("sensor", 0.01, _box("visual", 0.005, "0.01 0.01 0.01"))
    + _link("frame", 0.05)
    + _joint("knuckle_joint", "base", "knuckle", 0.5)
    + _joint("forearm_joint", "knuckle", "forearm", 0.0)
    + _joint("wrist_joint", "forearm", "wrist", -0.25)
    + _joint("palm_fixed", "wrist", "palm", -0.02, "fixed")
    + _joint("sensor_fixed", "wrist", "sensor", 0.0, "fixed")
    + _joint("frame_fixed", "wrist", "frame", 0.0, "fixed")
    + "</robot>"
)


@pytest.fixture(scope="module")
def arm():
    model = pin.buildModelFromXML(ARM, pin.JointModelFreeFlyer())
    collision = pin.buildGeomFromUrdfString(model, ARM, pin.COLLISION)
    visual = pin.buildGeomFromUrdfString(model, ARM, pin.VISUAL)
    return model, collision, visual


def test_a_link_is_bare_unless_its_own_or_its_bodys_shapes_hold_it(arm):
    model, collision, visual = arm
    bare = {b.link: b.visual for b in bare_links(model, link_masses(ARM), collision, visual)}
    # the palm: its joint carries the wrist's box, which leaves the palm's mesh out; the forearm: nothing at all
    assert bare == {"palm": True, "forearm": False}
    assert "sensor" not in bare and "frame" not in bare  # inside the wrist's box; carried by the wrist's body
    assert "knuckle" not in bare  # between coincident joints: no extent
    assert "base" not in bare  # its own disc (too small for its mesh: see left_out_m)


def test_left_out_measures_how_far_a_links_visual_geometry_leaves_its_bodys_shapes(arm):
    model, collision, visual = arm
    assert left_out_m(model, collision, visual, "base") == pytest.approx(0.395 - 0.205, abs=1e-6)  # the disc's top
    assert left_out_m(model, collision, visual, "wrist") == pytest.approx(0.0, abs=1e-9)
    assert left_out_m(model, collision, visual, "sensor") == pytest.approx(-0.01)  # its top 1 cm inside the box
    assert left_out_m(model, collision, visual, "forearm") == -float("inf")  # nothing to leave out


def test_the_visual_geometry_of_only_the_links_asked_for_is_loaded(arm):
    model, _, _ = arm
    partial = visual_geometry(model, ARM, (), without={"base", "wrist"})
    names = {str(model.frames[o.parentFrame].name) for o in partial.geometryObjects}
    assert names == {"palm", "sensor"}
    assert len(visual_geometry(model, ARM, (), without={"base", "wrist", "palm", "sensor"}).geometryObjects) == 0
    assert link_masses(ARM)["palm"] == 0.14 and link_masses(ARM)["knuckle"] == 0.3


@pytest.mark.parametrize(
    ("coverage", "phrase"),
    [
        (GeometryCoverage(0, 0, 31, ()), "31 primitives"),  # never "0 meshes"
        (GeometryCoverage(35, 0, 0, ()), "35 meshes"),
        (GeometryCoverage(0, 23, 2, ()), "23 hulls of visual meshes, 2 primitives"),
        (GeometryCoverage(0, 0, 0, ("a",)), "no collision geometry"),
    ],
)
def test_check_names_only_the_kinds_of_geometry_it_used(coverage, phrase):
    assert coverage.describe() == phrase
