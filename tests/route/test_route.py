"""Route: order, segments, limits, the independent check, and a real ROS 2 message."""

import itertools

import numpy as np
import pytest

from posegen.robot import SegmentType, read_route
from posegen.route import (
    order_postures,
    plan_route,
    route_to_dict,
    start_posture,
    time_distances,
    verify_route,
    write_route,
)

ROWS = [0, 1, 2]


@pytest.fixture(scope="module")
def routed(scene, example_pool, tmp_path_factory):
    postures = [example_pool.postures[i] for i in ROWS]
    route = plan_route(scene, postures, seed=0)
    entries = [example_pool.to_dict()["postures"][i] for i in ROWS]
    data = route_to_dict(route, entries, dict(example_pool.provenance), {"routed": len(route.visited)})
    path = tmp_path_factory.mktemp("route") / "route.yaml"
    write_route(path, data)
    return route, path


def test_route_passes_the_independent_check(scene, routed):
    _, path = routed
    result = verify_route(scene, read_route(path))
    assert result.ok, [w for w in result.worst if w.violations]


def test_every_posture_is_visited_in_order_with_its_segments(example_pool, routed):
    route, _ = routed
    assert sorted(route.visited) == list(range(len(ROWS))) and not route.skipped
    kinds = [s.type for s in route.segments]
    assert kinds[: 5 * len(ROWS)] == [
        SegmentType.FREE,
        SegmentType.APPROACH,
        SegmentType.GO_TO_CONTACT,
        SegmentType.HOLD,
        SegmentType.RELEASE,
    ] * len(ROWS)
    for seg in route.segments:
        if seg.type == SegmentType.GO_TO_CONTACT:
            contact = np.array(example_pool.postures[ROWS[seg.posture]].joints)
            points = route.positions[seg.first : seg.last + 1]
            assert np.min(np.max(np.abs(points - contact), axis=1)) == 0.0  # passes through the posture itself
        if seg.type == SegmentType.HOLD:
            assert route.times[seg.last] - route.times[seg.first] == pytest.approx(1.0)
            assert np.all(route.positions[seg.first] == route.positions[seg.last])


def test_times_and_limits(scene, routed):
    route, _ = routed
    assert np.all(np.diff(route.times) > 0)
    cfg = scene.config.route
    assert np.all(np.abs(route.velocities) <= scene.velocity_limit * cfg.velocity_scale_free * (1 + 1e-9))
    assert np.all(np.abs(route.accelerations) <= cfg.acceleration_limit_rad_s2 * (1 + 1e-9))
    for seg in route.segments:  # slower near the table
        if seg.type in (SegmentType.GO_TO_CONTACT, SegmentType.HOLD):
            v = route.velocities[seg.first : seg.last + 1]
            assert np.all(np.abs(v) <= scene.velocity_limit * cfg.velocity_scale_contact * (1 + 1e-9))
    for seg in route.segments:  # rest to rest
        assert np.all(route.velocities[seg.first] == 0) and np.all(route.velocities[seg.last] == 0)


def test_route_starts_and_ends_at_the_start_posture(scene, routed):
    route, _ = routed
    start = start_posture(scene)
    assert np.allclose(route.positions[0], start) and np.allclose(route.positions[-1], start)


def test_tsp_order_is_a_permutation_no_longer_than_nearest_neighbour(scene, example_pool):
    joints = example_pool.joints()[:41]
    start = start_posture(scene)
    order = order_postures(start, joints, scene.velocity_limit, seed=1)
    assert sorted(order.sequence) == list(range(41))
    assert order.length_s <= order.nearest_neighbour_s + 1e-12
    d = time_distances(np.vstack([start[None], joints]), scene.velocity_limit)
    path = [0, *[i + 1 for i in order.sequence]]
    assert order.length_s == pytest.approx(sum(d[a, b] for a, b in itertools.pairwise(path)))
    assert order_postures(start, joints, scene.velocity_limit, seed=1) == order  # seeded


def test_unreachable_posture_is_reported_and_the_rest_routed(scene, example_pool):
    import dataclasses

    good = example_pool.postures[0]
    joints = list(example_pool.postures[1].joints)
    other = "right" if example_pool.postures[1].chain == "left" else "left"
    k = scene.joint_index(f"arm_{other}_1_joint")
    joints[k] = float(scene.upper[k])  # on its limit: no valid contact state
    bad = dataclasses.replace(example_pool.postures[1], joints=tuple(joints))
    route = plan_route(scene, [good, bad], seed=0)
    assert route.visited == (0,)
    assert [i for i, _ in route.skipped] == [1] and "vertical approach" in route.skipped[0][1]


def test_file_loads_as_a_ros2_joint_trajectory(routed):
    from rosbags.typesys import Stores, get_typestore

    _, path = routed
    data = read_route(path)
    store = get_typestore(Stores.ROS2_HUMBLE)
    types = store.types
    traj = data["trajectory"]
    header = types["std_msgs/msg/Header"](
        stamp=types["builtin_interfaces/msg/Time"](**traj["header"]["stamp"]), frame_id=traj["header"]["frame_id"]
    )
    points = [
        types["trajectory_msgs/msg/JointTrajectoryPoint"](
            positions=np.array(p["positions"]),
            velocities=np.array(p["velocities"]),
            accelerations=np.array(p["accelerations"]),
            effort=np.array(p["effort"], dtype=float),
            time_from_start=types["builtin_interfaces/msg/Duration"](**p["time_from_start"]),
        )
        for p in traj["points"]
    ]
    msg = types["trajectory_msgs/msg/JointTrajectory"](header=header, joint_names=traj["joint_names"], points=points)
    raw = store.serialize_cdr(msg, msg.__msgtype__)
    back = store.deserialize_cdr(raw, "trajectory_msgs/msg/JointTrajectory")
    assert back.joint_names == traj["joint_names"] and len(back.points) == len(traj["points"])
    stamps = [p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in back.points]
    assert np.all(np.diff(stamps) > 0)
    assert all(0 <= p.time_from_start.nanosec < 1_000_000_000 for p in back.points)
    assert np.allclose(back.points[5].positions, traj["points"][5]["positions"])


def test_csv_beside_the_route(routed):
    _, path = routed
    lines = path.with_suffix(".csv").read_text().splitlines()
    assert lines[0].startswith("time_s,segment,chain,posture,")
    assert len(lines) - 1 == len(read_route(path)["trajectory"]["points"])


def test_no_joint_jumps_between_free_motion_waypoints(scene, routed):
    """Every exported step of a free motion is within the waypoint step (legs included)."""
    route, _ = routed
    step = scene.config.route.waypoint_step_rad
    for seg in route.segments:
        if seg.type == SegmentType.FREE:
            moves = np.abs(np.diff(route.positions[seg.first : seg.last + 1], axis=0)).max()
            assert moves <= step * (1 + 1e-6), (seg, moves)
