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


def test_stl_headers_count_the_triangles_of_binary_files_only(tmp_path):
    import trimesh

    from posegen.view.robot_figure import _stl_triangles

    sphere = trimesh.creation.icosphere(subdivisions=2)  # 320 faces
    sphere.export(tmp_path / "binary.stl")
    (tmp_path / "ascii.stl").write_text(trimesh.exchange.stl.export_stl_ascii(sphere))
    truncated = (tmp_path / "binary.stl").read_bytes()[:-50]  # its count no longer matches its size
    (tmp_path / "truncated.stl").write_bytes(truncated)
    assert _stl_triangles(tmp_path / "binary.stl") == len(sphere.faces) == 320
    assert _stl_triangles(tmp_path / "ascii.stl") == 0
    assert _stl_triangles(tmp_path / "truncated.stl") == 0
    assert _stl_triangles(tmp_path / "missing.stl") == 0


def test_heavy_visual_meshes_are_not_loaded_and_the_choice_is_the_same(scene, monkeypatch):
    from posegen.view import robot_figure

    loaded: list[MeshSource] = []
    geometry = robot_figure._geometry

    def counting(scene_, source):  # type: ignore[no-untyped-def]
        loaded.append(source)
        return geometry(scene_, source)

    monkeypatch.setattr(robot_figure, "_geometry", counting)
    lower_bound = robot_figure.visual_triangles_at_least(scene)
    assert lower_bound > robot_figure.SKIP_FACTOR * TRIANGLE_BUDGET  # TALOS's binary STL files
    assert lower_bound <= robot_meshes(scene, budget=10**7).triangles  # a lower bound of what is drawn
    for budget in (TRIANGLE_BUDGET, 10):  # the collision meshes fit; nothing fits: the lightest
        loaded.clear()
        chosen = robot_meshes(scene, budget=budget)
        assert MeshSource.VISUAL not in loaded
        monkeypatch.setattr(robot_figure, "SKIP_FACTOR", float("inf"))  # every source loaded and counted
        every = robot_meshes(scene, budget=budget)
        monkeypatch.setattr(robot_figure, "SKIP_FACTOR", 2)
        assert (chosen.source, chosen.triangles) == (every.source, every.triangles)
