"""Joint offsets: the hands' twists move the hands by the arms first, and never past a joint's limit."""

from __future__ import annotations

import numpy as np

from posegen.physics.nominal import NominalRobot
from posegen.physics.offsets import LIMIT_MARGIN_RAD, JointOffsets
from posegen.physics.tool import Tool
from posegen.robot import Scene


def _offsets(scene: Scene, tools: dict[str, Tool]) -> tuple[NominalRobot, JointOffsets]:
    robot = NominalRobot(scene, tools)
    robot.update(scene.reference)
    return robot, JointOffsets(scene, robot)


def test_a_hand_twist_moves_its_hand_by_it(scene: Scene, tools: dict[str, Tool]) -> None:
    robot, offsets = _offsets(scene, tools)
    frame = robot.contact_frames["left"]
    before = robot.pose(frame)[:3, 3].copy()
    twist = {"left": np.array([0.0, 0.0, -0.01, 0.0, 0.0, 0.0]), "right": np.zeros(6)}
    soles = [np.zeros(6), np.zeros(6)]
    for _ in range(50):  # 0.1 s at 1 cm/s
        dq = offsets.step(soles, twist, scene.reference, 0.002, decay=False)
        robot.update(scene.reference + dq)
    moved = robot.pose(frame)[:3, 3] - before
    assert abs(moved[2] + 1e-3) < 1e-4 and np.linalg.norm(moved[:2]) < 1e-4
    torso = offsets.shared
    assert np.abs(dq[torso]).max() < np.abs(dq[offsets.arms["left"]]).max()  # the arm moves the hand first


def test_the_offsets_keep_the_commanded_angles_inside_the_limits(scene: Scene, tools: dict[str, Tool]) -> None:
    robot, offsets = _offsets(scene, tools)
    twist = {"left": np.array([0.0, 0.0, -0.5, 0.0, 0.0, 0.0]), "right": np.zeros(6)}  # far beyond reach
    soles = [np.zeros(6), np.zeros(6)]
    for _ in range(400):
        dq = offsets.step(soles, twist, scene.reference, 0.01, decay=False)
        robot.update(scene.reference + dq)
    commanded = scene.reference + dq
    moved = scene.reference != commanded
    assert np.all(commanded[moved] >= scene.lower[moved] + LIMIT_MARGIN_RAD - 1e-12)
    assert np.all(commanded[moved] <= scene.upper[moved] - LIMIT_MARGIN_RAD + 1e-12)
    assert not np.any(dq[scene.locked])
