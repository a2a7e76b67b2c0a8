"""The camera frames robot and table; every colour is told apart from the robot's."""

import numpy as np

from posegen.view import ROBOT_RGB, framing
from posegen.view.scenery import CHAIN_RGB, GHOST_RGB, TABLE_RGB, robot_height
from tests.view.chromium import robot_pixels


def test_the_camera_sees_the_whole_robot_and_table(scene):
    camera = framing(scene)
    axis = (camera.look_at - camera.position) / np.linalg.norm(camera.look_at - camera.position)
    half = np.array(scene.table.size_m[:2]) / 2
    table = [scene.table_pose @ np.array([sx * half[0], sy * half[1], 0.0, 1.0]) for sx in (-1, 1) for sy in (-1, 1)]
    feet = [pose[:3, 3] for pose in scene.sole_poses.values()]
    head = [f + np.array([0.0, 0.0, robot_height(scene)]) for f in feet]
    for point in [t[:3] for t in table] + feet + head:
        ray = (point - camera.position) / np.linalg.norm(point - camera.position)
        assert np.degrees(np.arccos(ray @ axis)) < camera.fov_deg / 2  # inside the (vertical) field of view


def test_the_robot_is_the_only_blue_thing():
    assert robot_pixels(np.array([[ROBOT_RGB]], dtype=np.uint8)) == 1
    assert robot_pixels((np.array([[ROBOT_RGB]]) * 0.5).astype(np.uint8)) == 1  # shaded, still the robot
    others = np.array([[c] for c in (*CHAIN_RGB, GHOST_RGB, TABLE_RGB, (255, 255, 255), (128, 128, 128))], np.uint8)
    assert robot_pixels(others) == 0
