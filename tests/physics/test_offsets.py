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


def test_a_lagging_free_arm_is_left_as_it_is(scene: Scene, tools: dict[str, Tool]) -> None:
    """Away from the table, an arm lagging at its effort limit is not moved by the other hand's twist.

    Without the lag the torso helps the left hand and the right arm follows it (its hand
    stays still relative to the base); with it, the right arm's offset stays where it was.
    """
    twist = {"left": np.array([0.0, 0.05, -0.05, 0.0, 0.0, 0.2]), "right": np.zeros(6)}
    soles = [np.zeros(6), np.zeros(6)]
    moved = {}
    for lagging in (frozenset(), frozenset({"right"})):
        robot, offsets = _offsets(scene, tools)
        offsets.dq[offsets.arms["right"]] = 0.05  # where the lag left it
        for _ in range(50):
            dq = offsets.step(soles, twist, scene.reference, 0.002, decay=True, lagging=lagging)
            robot.update(scene.reference + dq)
        moved[lagging] = dq.copy()
    right, torso, left = offsets.arms["right"], offsets.shared, offsets.arms["left"]
    assert np.abs(moved[frozenset()][right] - 0.05).max() > 1e-4  # it follows the torso
    np.testing.assert_allclose(moved[frozenset({"right"})][right], 0.05, atol=1e-12)  # but for rounding
    assert np.abs(moved[frozenset({"right"})][torso]).max() > 1e-5
    assert np.abs(moved[frozenset({"right"})][left]).max() > 1e-3


def test_at_the_table_a_lagging_arm_moves_as_before(scene: Scene, tools: dict[str, Tool]) -> None:
    """At the table (no decay) the contact's admittance decides (it presses no further): the solve is unchanged."""
    twist = {"left": np.array([0.0, 0.0, 0.01, 0.0, 0.0, 0.0]), "right": np.zeros(6)}
    soles = [np.zeros(6), np.zeros(6)]
    out = []
    for lagging in (frozenset(), frozenset({"left", "right"})):
        robot, offsets = _offsets(scene, tools)
        for _ in range(20):
            dq = offsets.step(soles, twist, scene.reference, 0.002, decay=False, lagging=lagging)
            robot.update(scene.reference + dq)
        out.append(dq.copy())
    np.testing.assert_array_equal(out[0], out[1])
