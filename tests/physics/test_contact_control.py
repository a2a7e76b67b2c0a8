"""The force-controlled contact: its phases from the route, how a hand gives way, when the route waits."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from posegen.io import SegmentType, read_route
from posegen.physics.contact_control import (
    FORCE_BAND,
    GUARD_FORCE_N,
    GUARD_SPEED_M_S,
    K_FORCE,
    MAX_SPEED_M_S,
    SEARCH_SPEED_M_S,
    SEARCH_TIMEOUT_S,
    SETTLE_S,
    UNLOAD_S,
    UNLOAD_SHARE,
    ContactTimes,
    HandControl,
    Phase,
    contact_times,
    unload_s,
)
from posegen.physics.fingertips import FLUSH_MARGIN_M, K_FLUSH, MAX_FLUSH_TILT_RAD
from posegen.physics.nominal import NominalRobot
from posegen.physics.tool import Tool
from posegen.robot import Scene


def _first_contact(route_file: Path, scene: Scene, tools: dict[str, Tool]) -> tuple[ContactTimes, HandControl]:
    """The route's first contact and hands controlling it alone, at a 30 N target."""
    contact = contact_times(read_route(route_file))[0]
    return contact, HandControl(NominalRobot(scene, tools), (contact,), force_n=30.0)


def test_contact_times_are_the_route_s_segments(route_file: Path) -> None:
    route = read_route(route_file)
    times = contact_times(route)
    holds = [s for s in route.segments if s.type == SegmentType.HOLD]
    assert len(times) == len(holds) == 2
    for contact, hold in zip(times, holds, strict=True):
        assert contact.approach_s < contact.press_s < contact.hold_s == hold.start_s < contact.lift_s < contact.free_s
        assert contact.lift_s == hold.end_s and contact.chain == hold.chain


def test_a_hand_searches_presses_and_turns_flush(route_file: Path, scene: Scene, tools: dict[str, Tool]) -> None:
    contact, hands = _first_contact(route_file, scene, tools)
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
    contact, hands = _first_contact(route_file, scene, tools)
    before, after, dt = contact.hold_s - 0.001, contact.hold_s + 0.001, 0.002
    assert hands.holds_back(before, after, dt)  # no force yet
    hands.wrenches[contact.chain] = np.array([0, 0, 29.0, 0, 0, 0])
    waits = sum(hands.holds_back(before, after, dt) for _ in range(1000))
    assert waits == round(SETTLE_S / dt) - 1  # settles, then goes on
    assert not hands.holds_back(before + 1.0, after + 1.0, dt)  # elsewhere: never
    other = HandControl(hands.robot, (contact,), force_n=30.0)
    assert abs(sum(other.holds_back(before, after, dt) for _ in range(5000)) - SEARCH_TIMEOUT_S / dt) <= 1


def test_a_release_takes_the_force_off_over_half_of_it(route_file: Path, scene: Scene, tools: dict[str, Tool]) -> None:
    robot = NominalRobot(scene, tools)
    contact = contact_times(read_route(route_file))[0]
    release = contact.free_s - contact.lift_s
    assert unload_s(contact) == max(UNLOAD_SHARE * release, UNLOAD_S)
    short = ContactTimes(contact.chain, "short", 0.0, 0.1, 0.2, 1.2, 1.25)
    assert unload_s(short) == UNLOAD_S  # never faster than UNLOAD_S
    hands = HandControl(robot, (contact,), force_n=30.0)
    half = contact.lift_s + 0.5 * unload_s(contact)
    assert hands.phase(contact.chain, half) == Phase.RELEASE
    assert np.isclose(hands.planned_push(contact.chain, contact.lift_s), 30.0)
    assert np.isclose(hands.planned_push(contact.chain, half), 15.0)  # linear, not a step
    assert hands.planned_push(contact.chain, contact.lift_s + unload_s(contact)) < 1e-9
    hand = hands.hands[contact.chain]
    hand.offset = np.array([0.0, 0.0, -0.01, 0.0, 0.0, 0.0])
    at_half = hands._twist(contact.chain, contact, half, np.array([0, 0, 15.0, 0, 0, 0]), hand)
    assert not np.any(at_half)  # the target's ramp: 15 N at half way is on target, the hand still
    pressing = hands._twist(contact.chain, contact, half, np.array([0, 0, 30.0, 0, 0, 0]), hand)
    assert pressing[2] > 0  # the full force at half way: it lifts
    after = contact.lift_s + unload_s(contact) + 1e-3
    back = hands._twist(contact.chain, contact, after, np.zeros(6), hand)
    assert back[2] > 0 and np.isclose(back[2] * (contact.free_s - after), 0.01)  # then back to the plan by the end


def test_a_free_hand_that_meets_the_table_gives_way_fast(
    route_file: Path, scene: Scene, tools: dict[str, Tool]
) -> None:
    contact, hands = _first_contact(route_file, scene, tools)
    hand = hands.hands[contact.chain]
    free = contact.approach_s - 0.05
    assert hands.phase(contact.chain, free) == Phase.FREE
    struck = np.array([0, 0, 100.0, 0, 0, 0])
    assert hands._twist(contact.chain, contact, free, struck, hand)[2] == GUARD_SPEED_M_S > MAX_SPEED_M_S
    light = np.array([0, 0, 0.5 * GUARD_FORCE_N, 0, 0, 0])
    assert not np.any(hands._twist(contact.chain, contact, free, light, hand))  # below the guard: held
    pressing = 0.5 * (contact.press_s + contact.hold_s)
    assert hands._twist(contact.chain, contact, pressing, struck, hand)[2] == GUARD_SPEED_M_S  # too hard: as fast


def test_a_pressing_hand_gives_way_faster_than_it_presses(
    route_file: Path, scene: Scene, tools: dict[str, Tool]
) -> None:
    _, hands = _first_contact(route_file, scene, tools)
    offset = np.zeros(6)
    light = hands._give_way(np.array([0, 0, 5.0, 0, 0, 0]), 30.0, offset)
    assert light[2] == -MAX_SPEED_M_S  # touching too lightly: down at the contact's speed
    for force in (50.0, 80.0, 150.0):  # too hard: up, in proportion, up to the guard's speed
        expected = min(K_FORCE * (force - 30.0), GUARD_SPEED_M_S)
        assert hands._give_way(np.array([0, 0, force, 0, 0, 0]), 30.0, offset)[2] == expected
    assert K_FORCE * (150.0 - 30.0) > GUARD_SPEED_M_S > MAX_SPEED_M_S  # the 150 N case saturates


def test_a_touching_hand_undoes_the_plan_s_descent(route_file: Path, scene: Scene, tools: dict[str, Tool]) -> None:
    contact, hands = _first_contact(route_file, scene, tools)
    chain, dt_s = contact.chain, 0.004
    pressing = 0.5 * (contact.press_s + contact.hold_s)
    hands.wrenches[chain] = np.array([0, 0, 20.0, 0, 0, 0])  # touching
    assert hands._undone_descent(chain, pressing, 0.8, dt_s) == 0.0  # the first step: no earlier height
    assert np.isclose(hands._undone_descent(chain, pressing, 0.7996, dt_s), 0.1)  # 0.4 mm in 4 ms: 0.1 m/s undone
    assert hands._undone_descent(chain, pressing, 0.7998, dt_s) == 0.0  # the plan rising: left as planned
    hands.wrenches[chain] = np.zeros(6)  # not touching: the plan's descent looks for the table
    assert hands._undone_descent(chain, pressing, 0.7994, dt_s) == 0.0
    hands.wrenches[chain] = np.array([0, 0, 20.0, 0, 0, 0])
    before = contact.approach_s - 0.05  # free: the plan (a force there is the guard's)
    assert hands.phase(chain, before) == Phase.FREE
    assert hands._undone_descent(chain, before, 0.7990, dt_s) == 0.0
    approach = 0.5 * (contact.approach_s + contact.press_s)
    assert hands.phase(chain, approach) == Phase.APPROACH
    assert np.isclose(hands._undone_descent(chain, approach, 0.7986, dt_s), 0.1)  # pushed past the guard: undone
    hands.wrenches[chain] = np.array([0, 0, 0.5 * GUARD_FORCE_N, 0, 0, 0])
    assert hands._undone_descent(chain, approach, 0.7982, dt_s) == 0.0  # below the guard: the approach goes on


def test_a_hand_is_flush_when_its_centre_of_pressure_loads_every_tip(
    route_file: Path, scene: Scene, tools: dict[str, Tool]
) -> None:
    contact, hands = _first_contact(route_file, scene, tools)
    chain = contact.chain
    hands.robot.update(scene.reference)
    axes = hands.robot.pose(hands.robot.contact_frames[chain])[:2, :2]
    polygon = hands.tips[chain]
    assert polygon is not None

    def torque_at(pressure: np.ndarray, force: float) -> np.ndarray:  # world axes, the force at ``pressure``
        local = np.array([pressure[1], -pressure[0]]) * force
        return axes @ local

    assert hands._flush(chain, 30.0, torque_at(np.zeros(2), 30.0))
    tip = polygon.vertices[0]
    edge = 0.5 * (polygon.vertices[0] + polygon.vertices[1])  # two tips carry it all
    assert not hands._flush(chain, 30.0, torque_at(edge, 30.0))
    assert not hands._flush(chain, 30.0, torque_at(tip, 30.0))
    inside = edge * (1.0 - 2.0 * FLUSH_MARGIN_M / polygon.margin(np.zeros(2)))  # toward the origin
    assert polygon.margin(inside) > FLUSH_MARGIN_M and hands._flush(chain, 30.0, torque_at(inside, 30.0))
    assert hands._flush(chain, 1.0, torque_at(edge, 30.0))  # not touching: nothing to settle


def test_a_pressing_hand_turns_flush_then_holds_still(route_file: Path, scene: Scene, tools: dict[str, Tool]) -> None:
    contact, hands = _first_contact(route_file, scene, tools)
    hand = hands.hands[contact.chain]
    pressing = 0.5 * (contact.press_s + contact.hold_s)
    hand.torque = np.array([0.4, -0.2])
    turn = hands._settle_flush(contact, pressing, hand, flush=False)
    assert np.allclose(turn, K_FLUSH * hand.torque)  # as the torque says (the sign _give_way turns by)
    assert not np.any(hands._settle_flush(contact, pressing, hand, flush=True))
    assert not np.any(hands._settle_flush(contact, contact.hold_s, hand, flush=False))  # the hold: still
    hand.offset = np.array([0, 0, 0, MAX_FLUSH_TILT_RAD, 0.0, 0])
    blocked = hands._settle_flush(contact, pressing, hand, flush=False)
    assert blocked[0] == 0.0 and blocked[1] == turn[1]  # no further than its bound


def _sensor_reading(hands: HandControl, chain: str, contact_wrench: np.ndarray) -> np.ndarray:
    """The wrist sensor's reading (6,) that gives ``contact_wrench`` (world axes at the contact origin), tool's weight
    included: what :meth:`NominalRobot.at_contact` undoes."""
    robot = hands.robot
    sensor = robot.data.oMf[robot.wrench_frames[chain]]
    lever = robot.data.oMf[robot.contact_frames[chain]].translation - sensor.translation
    force = contact_wrench[:3]
    torque = contact_wrench[3:] + np.cross(lever, force)
    return np.concatenate([sensor.rotation.T @ force, sensor.rotation.T @ torque]) + robot.tool_wrench(chain)


def test_a_hand_on_two_tips_turns_until_the_third_carries_load(
    route_file: Path, scene: Scene, tools: dict[str, Tool]
) -> None:
    """Through :meth:`HandControl.step`: a hand pressed on the edge between two fingertips turns toward the third
    (the roll and pitch that unload the edge), one whose every tip carries load does not turn, nor does any hand in
    its hold."""
    contact, hands = _first_contact(route_file, scene, tools)
    chain = contact.chain
    route = read_route(route_file)
    at_hold = route.positions[np.searchsorted(route.times, contact.hold_s)]
    joints = at_hold[route.joint_columns(scene.joint_names, str(route_file))]  # the hand flush on the table
    hands.robot.update(joints)
    polygon = hands.tips[chain]
    assert polygon is not None
    axes = hands.robot.pose(hands.robot.contact_frames[chain])[:3, :3]
    planned = {c: hands.robot.pose(hands.robot.contact_frames[c]) for c in hands.hands}
    force = 30.0

    def run(pressure: np.ndarray, t: float, steps: int = 60) -> np.ndarray:
        """The hand's roll and pitch offset (2,) rad after ``steps`` periods pressed at ``pressure`` (contact x, y)."""
        local = np.array([pressure[1] * force, -pressure[0] * force, 0.0])  # the torque at the contact origin
        wrench = np.concatenate([axes @ np.array([0, 0, force]), axes @ local])
        wrists = {c: _sensor_reading(hands, c, wrench if c == chain else np.zeros(6)) for c in hands.hands}
        hands.hands[chain].offset[:] = 0.0
        hands.hands[chain].torque[:] = 0.0
        for _ in range(steps):
            hands.step(t, wrists, planned, joints, 0.004)
        return hands.hands[chain].offset[3:5].copy()

    pressing = 0.5 * (contact.press_s + contact.hold_s)
    edge = 0.5 * (polygon.vertices[0] + polygon.vertices[1])  # two tips carry it all
    turned = run(edge, pressing)
    local = np.array([edge[1], -edge[0]])  # the torque's direction at the contact origin (contact axes)
    assert np.linalg.norm(turned) > 0.01  # about 0.2 rad/s for 0.24 s, less the filter's lag
    assert (axes[:2, :2].T @ turned) @ local > 0.99 * np.linalg.norm(turned) * np.linalg.norm(local)  # toward the third
    assert polygon.margin(0.5 * edge) > 2 * FLUSH_MARGIN_M
    assert not np.any(run(0.5 * edge, pressing))  # every tip loaded, off centre: still
    assert not np.any(run(edge, contact.hold_s + 0.01))  # the hold: still


def test_away_from_the_table_a_hand_holds_its_pose_unless_its_arm_lags(
    route_file: Path, scene: Scene, tools: dict[str, Tool]
) -> None:
    """Free, each hand is driven back to its planned pose in the world; a chain whose arm lags its command past
    its effort limit is not (its lag would wind the loop up into the torso and the other arm)."""
    from posegen.physics.contact_control import K_HOLD_PER_S, POSE_BAND

    contact, hands = _first_contact(route_file, scene, tools)
    hands.robot.update(scene.reference)
    free = contact.approach_s - 0.5
    assert not hands.in_contact(free)
    planned = {}
    for c in hands.hands:
        pose = hands.robot.pose(hands.robot.contact_frames[c]).copy()
        pose[2, 3] += 0.01  # planned 1 cm above where the commanded angles put it
        planned[c] = pose
    wrists = {c: _sensor_reading(hands, c, np.zeros(6)) for c in hands.hands}
    out = hands.step(free, wrists, planned, scene.reference, 0.004)
    for c in hands.hands:
        assert np.isclose(out[c][2], K_HOLD_PER_S * (0.01 - POSE_BAND[2])) and np.allclose(out[c][3:], 0.0, atol=1e-9)
    hands.saturated[contact.chain] = True
    out = hands.step(free, wrists, planned, scene.reference, 0.004)
    assert not np.any(out[contact.chain])  # the lagging arm: no pose loop
    other = next(c for c in hands.hands if c != contact.chain)
    assert np.isclose(out[other][2], K_HOLD_PER_S * (0.01 - POSE_BAND[2]))  # the other: as before (beyond its band)
