"""The force-controlled contact: its phases from the route, how a hand gives way, when the route waits."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from posegen.io import SegmentType, read_route
from posegen.physics.contact_control import (
    FORCE_BAND,
    SEARCH_SPEED_M_S,
    SEARCH_TIMEOUT_S,
    SETTLE_S,
    HandControl,
    Phase,
    contact_times,
)
from posegen.physics.nominal import NominalRobot
from posegen.physics.tool import Tool
from posegen.robot import Scene


def test_contact_times_are_the_route_s_segments(route_file: Path) -> None:
    route = read_route(route_file)
    times = contact_times(route)
    holds = [s for s in route.segments if s.type == SegmentType.HOLD]
    assert len(times) == len(holds) == 2
    for contact, hold in zip(times, holds, strict=True):
        assert contact.approach_s < contact.press_s < contact.hold_s == hold.start_s < contact.lift_s < contact.free_s
        assert contact.lift_s == hold.end_s and contact.chain == hold.chain


def test_a_hand_searches_presses_and_turns_flush(route_file: Path, scene: Scene, tools: dict[str, Tool]) -> None:
    robot = NominalRobot(scene, tools)
    contact = contact_times(read_route(route_file))[0]
    hands = HandControl(robot, (contact,), force_n=30.0)
    t = 0.5 * (contact.press_s + contact.hold_s)
    assert hands.phase(contact.chain, t) == Phase.PRESS
    offset = np.zeros(6)
    free = hands._give_way(np.zeros(6), 30.0, offset)
    assert free[2] == -SEARCH_SPEED_M_S and not np.any(free[3:])  # not touching: down
    pressed = hands._give_way(np.array([0, 0, 60.0, 2.0, -2.0, 5.0]), 30.0, offset)
    assert pressed[2] > 0  # too hard: up
    assert pressed[3] > 0 and pressed[4] < 0  # turns to unload the tips the torque says are loaded
    assert pressed[5] == 0 and not np.any(pressed[:2])  # tangent and yaw held
    still = hands._give_way(np.array([0, 0, 30.0 * (1 + FORCE_BAND / 2), 0.1, 0.1, 0]), 30.0, offset)
    assert not np.any(still)  # in its band: still


def test_the_route_waits_for_the_force_then_goes_on(route_file: Path, scene: Scene, tools: dict[str, Tool]) -> None:
    robot = NominalRobot(scene, tools)
    contact = contact_times(read_route(route_file))[0]
    hands = HandControl(robot, (contact,), force_n=30.0)
    before, after, dt = contact.hold_s - 0.001, contact.hold_s + 0.001, 0.002
    assert hands.holds_back(before, after, dt)  # no force yet
    hands.wrenches[contact.chain] = np.array([0, 0, 29.0, 0, 0, 0])
    waits = sum(hands.holds_back(before, after, dt) for _ in range(1000))
    assert waits == round(SETTLE_S / dt) - 1  # settles, then goes on
    assert not hands.holds_back(before + 1.0, after + 1.0, dt)  # elsewhere: never
    other = HandControl(robot, (contact,), force_n=30.0)
    assert abs(sum(other.holds_back(before, after, dt) for _ in range(5000)) - SEARCH_TIMEOUT_S / dt) <= 1
