"""The robot figure: meshes within the budget, and only what moved is sent again."""

import numpy as np

from posegen.view import MeshSource, RobotFigure, robot_meshes
from posegen.view.robot_figure import TRIANGLE_BUDGET
from posegen.view.viewer import local_server
from tests.view.conftest import recording


def test_the_lighter_meshes_are_chosen_when_the_visual_ones_are_heavy(scene):
    light = robot_meshes(scene)
    assert light.triangles <= TRIANGLE_BUDGET and light.source == MeshSource.COLLISION  # TALOS: 158,856 visual
    heavy = robot_meshes(scene, budget=10**7)
    assert heavy.source == MeshSource.VISUAL and heavy.triangles > TRIANGLE_BUDGET
    parents = {m.parent_joint for m in light.meshes}
    assert parents <= set(range(scene.model.njoints)) and len(parents) > 20


def test_posing_again_at_the_same_configuration_sends_nothing(scene, example_pool):
    a, b = (scene.configuration(example_pool.joints()[i]) for i in (0, 1))
    with local_server() as server:
        figure = RobotFigure(server, scene.model, robot_meshes(scene), "robot", (70, 110, 200))
        serializer = server.get_scene_serializer()
        figure.pose(a)
        serializer.insert_sleep(1.0)
        figure.pose(a)
        serializer.insert_sleep(1.0)
        figure.pose(b)
        page = recording(serializer.as_html())
    moves = [t for t, m in page["messages"] if m["type"] in ("SetOrientationMessage", "SetPositionMessage")]
    assert 1.0 not in moves and moves.count(0.0) > 0
    changed = np.flatnonzero(np.abs(example_pool.joints()[0] - example_pool.joints()[1]) > 1e-3)
    assert moves.count(2.0) >= len(changed)  # every joint that moved, at least
    assert moves.count(2.0) <= scene.model.njoints  # and one message per joint, not per mesh


def test_a_robot_without_collision_geometry_is_drawn_within_the_budget():
    from posegen.robot import Scene, load_config
    from tests.conftest import ROOT

    human = Scene(load_config(ROOT / "configs" / "human_table.yaml"))  # visual meshes only, hulls declared
    drawn = robot_meshes(human, budget=10**7)
    assert drawn.source == MeshSource.VISUAL and drawn.meshes
    light = robot_meshes(human, budget=2000)
    assert light.meshes and light.triangles < drawn.triangles
    assert light.source in (MeshSource.COLLISION, MeshSource.COLLISION_HULLS, MeshSource.VISUAL_HULLS)
