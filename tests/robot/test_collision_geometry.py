"""A visual hull stands for any visual geometry: a mesh's hull, a flat mesh's thin box, a primitive as it is."""

from __future__ import annotations

from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest
import trimesh

from posegen.errors import ConfigError
from posegen.robot import CollisionConfig, VisualHull, robot_geometry


def _urdf(folder: Path) -> str:
    corners = [[0, 0, 0], [0.1, 0, 0], [0, 0.05, 0], [0.1, 0.05, 0]]
    flat = trimesh.Trimesh(vertices=corners, faces=[[0, 1, 2], [1, 3, 2]])
    flat.export(folder / "flat.stl")  # a panel: qhull cannot hull it (and coal then crashes)
    visual = (
        '<visual><origin xyz="0 0 0.1"/><geometry><box size="0.1 0.2 0.3"/></geometry></visual>'
        f'<visual><origin xyz="0 0 0.3"/><geometry><mesh filename="{folder / "flat.stl"}"/></geometry></visual>'
    )
    return (
        '<robot name="r"><link name="base"><inertial><mass value="1"/>'
        '<inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial>'
        f"{visual}</link><link name='bare'/><joint name='j' type='fixed'><parent link='base'/>"
        "<child link='bare'/></joint></robot>"
    )


def test_a_visual_hull_keeps_primitives_and_boxes_a_flat_mesh(tmp_path):
    text = _urdf(tmp_path)
    model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    for convex in (False, True):
        geom = robot_geometry(model, text, (), CollisionConfig(shapes=(VisualHull("base"),)), convex=convex)
        box, panel = (o for o in geom.geometryObjects if o.name.startswith("base_shape"))
        assert isinstance(box.geometry, coal.Box) and box.placement.translation == pytest.approx([0, 0, 0.1])
        assert np.asarray(box.geometry.halfSide) == pytest.approx([0.05, 0.1, 0.15])
        assert isinstance(panel.geometry, coal.Box)  # the flat mesh: its box, 1 mm thick
        assert 2 * np.asarray(panel.geometry.halfSide) == pytest.approx([0.1, 0.05, 0.001])
        assert panel.placement.translation == pytest.approx([0.05, 0.025, 0.3])
    with pytest.raises(ConfigError, match=r"shapes\.bare: visual_hull, but the link has no visual geometry"):
        robot_geometry(model, text, (), CollisionConfig(shapes=(VisualHull("bare"),)), convex=False)


def test_a_flat_collision_mesh_becomes_its_thin_box(tmp_path):
    """A URDF whose collision mesh is a panel (a sole drawn as one face): qhull failed on it and coal crashed."""
    text = _urdf(tmp_path).replace("<visual>", "<collision>").replace("</visual>", "</collision>")
    model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    geom = robot_geometry(model, text, (), CollisionConfig(), convex=True)
    box, panel = geom.geometryObjects
    assert isinstance(box.geometry, coal.Box) and box.placement.translation == pytest.approx([0, 0, 0.1])
    assert isinstance(panel.geometry, coal.Box)
    assert 2 * np.asarray(panel.geometry.halfSide) == pytest.approx([0.1, 0.05, 0.001])
    assert panel.placement.translation == pytest.approx([0.05, 0.025, 0.3])
