"""The HTML page: one step per posture or frame, the robot where pinocchio puts it, nothing fetched."""

import re

import numpy as np
import pinocchio as pin
import pytest

from posegen.errors import InputError
from posegen.view import framing, open_artefact, write_html
from posegen.view.robot_figure import robot_meshes
from posegen.view.route_view import FPS, interpolate, sample_times
from tests.view.conftest import labels, messages_of, node_poses, recording, world_pose


def mesh_error(page, at_s, scene, joints):
    """Largest distance (m) between where the page draws each mesh vertex box and where pinocchio puts it."""
    poses = node_poses(page, at_s)
    names = [m["name"] for _, m in messages_of(page, "MeshMessage") if m["name"].startswith("/robot/")]
    meshes = robot_meshes(scene)
    assert len(names) == len(meshes.meshes)
    data = scene.model.createData()
    pin.forwardKinematics(scene.model, data, scene.configuration(joints))
    worst = 0.0
    for k, mesh in enumerate(meshes.meshes):
        name = next(n for n in names if n.endswith(f"/mesh{k}"))
        drawn = world_pose(poses, name)
        expected = data.oMi[mesh.parent_joint] * mesh.placement
        corners = mesh.vertices[[np.argmin(mesh.vertices[:, 0]), np.argmax(mesh.vertices[:, 0])]]
        for v in corners:
            worst = max(worst, float(np.linalg.norm(drawn.act(v) - expected.act(v))))
    return worst


def test_each_second_of_a_selection_page_is_a_posture_drawn_where_pinocchio_puts_it(selection_file, selection_page):
    artefact = open_artefact(selection_file)
    page = recording(selection_page.html)
    n = len(artefact.postures.postures)
    assert selection_page.steps == n and page["durationSeconds"] == pytest.approx(n)
    texts = labels(page)
    for k in (0, n // 2, n - 1):
        label = [text for t, text in texts if t <= k + 0.5][-1]
        assert label.startswith(f"selection posture {k + 1}/{n} | id {artefact.entries[k]['pool_id']} |")
        assert mesh_error(page, k + 0.5, artefact.scene, np.array(artefact.postures.postures[k].joints)) < 2e-3


def test_a_route_page_plays_the_trajectory_in_real_time(route_file, route_page):
    artefact = open_artefact(route_file)
    page = recording(route_page.html)
    assert page["durationSeconds"] == pytest.approx(artefact.times[-1] - artefact.times[0])
    frames = sample_times(artefact.times, FPS)
    assert route_page.steps == len(frames) and np.all(np.diff(frames) <= 1 / FPS + 1e-12)
    for f in (0, len(frames) // 3, len(frames) // 2, len(frames) - 1):
        joints = interpolate(artefact.times, artefact.positions, frames[f : f + 1])[0]
        assert mesh_error(page, frames[f] - frames[0] + 1e-9, artefact.scene, joints) < 2e-3
    texts = labels(page)
    for seg in artefact.segments:
        middle = (seg.start_s + seg.end_s) / 2
        assert [text for t, text in texts if t <= middle][-1].startswith(seg.type.value.replace("_", " ") + " | ")
    assert [m["name"] for _, m in messages_of(page, "LineSegmentsMessage")] == ["/route/path"]  # the swept path


def test_interpolation_passes_through_the_route_points_and_is_linear_between():
    times = np.array([0.0, 1.0, 3.0])
    positions = np.array([[0.0, 1.0], [1.0, 1.0], [3.0, -1.0]])
    assert np.allclose(interpolate(times, positions, times), positions)
    assert np.allclose(interpolate(times, positions, np.array([0.5, 2.0])), [[0.5, 1.0], [2.0, 0.0]])


def test_the_camera_is_the_framing_and_the_page_fetches_nothing(selection_file, selection_page):
    page = recording(selection_page.html)
    camera = framing(open_artefact(selection_file).scene)
    ((_, position),) = messages_of(page, "SetCameraPositionMessage")
    assert np.allclose(position["position"], camera.position)
    html = selection_page.html
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", html)  # no script, style or image from a server
    assert not re.search(r"""(fetch|import)\(\s*["']https?://""", html)


def test_writing_a_page_of_a_bad_artefact_leaves_no_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("format: posegen-pool\nformat_version: 1\njoint_names: []\npostures: []\n")
    out = tmp_path / "view.html"
    with pytest.raises(InputError, match="no postures"):
        write_html(open_artefact(bad), out)
    assert not out.exists()
