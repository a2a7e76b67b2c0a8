"""Route: order, segments, rest points, limits, the independent check, repair, workers, a real ROS 2 message."""

import dataclasses
import itertools

import numpy as np
import pytest

from posegen.errors import InfeasibleError, InputError
from posegen.io import SegmentType, read_route, sidecars_of, write_route
from posegen.model import build_design
from posegen.route import (
    Substitutes,
    order_postures,
    plan_route,
    rest_to_rest_time,
    route_artefact,
    start_posture,
    transfer_times,
    verify_route,
)
from tests.conftest import routable_rows

ROWS = [0, 1, 2, 4, 5]  # five example-pool postures that route (the first test asserts none is skipped)


def write(route, pool, rows, path):
    entries = {i: pool.to_dict()["postures"][r] for i, r in enumerate(rows)}
    write_route(path, route_artefact(route, entries, dict(pool.provenance), {"routed": len(route.visited)}))
    return path


@pytest.fixture(scope="module")
def routed(scene, example_pool, tmp_path_factory):
    postures = [example_pool.postures[i] for i in ROWS]
    route = plan_route(scene, postures, seed=0)
    path = write(route, example_pool, ROWS, tmp_path_factory.mktemp("route") / "route.yaml")
    return route, path


def test_route_passes_the_independent_check(scene, routed):
    _, path = routed
    result = verify_route(scene, read_route(path))
    assert result.ok, [w for w in result.worst if w.violations]
    assert result.checked == len(routed[0].times)


def test_every_posture_is_visited_once_with_its_segments(example_pool, routed):
    route, _ = routed
    assert sorted(route.visited) == list(range(len(ROWS))) and not route.skipped and not route.substitutions
    kinds = [s.type for s in route.segments]
    per_contact = [SegmentType.FREE, SegmentType.APPROACH, SegmentType.GO_TO_CONTACT, SegmentType.HOLD]
    assert kinds[:4] == per_contact and kinds[-1] == SegmentType.FREE  # from the start, and back to it
    assert kinds.count(SegmentType.HOLD) == len(ROWS) == kinds.count(SegmentType.GO_TO_CONTACT)
    for a, b in itertools.pairwise(route.segments):
        assert a.last_point == b.first_point  # consecutive segments share their boundary point
    for seg in route.segments:
        if seg.type == SegmentType.GO_TO_CONTACT:
            contact = np.array(example_pool.postures[ROWS[seg.posture]].joints)
            points = route.positions[seg.first_point : seg.last_point + 1]
            assert np.min(np.max(np.abs(points - contact), axis=1)) == 0.0  # passes through the posture itself
        if seg.type == SegmentType.HOLD:
            assert route.times[seg.last_point] - route.times[seg.first_point] == pytest.approx(1.0)
            assert np.all(route.positions[seg.first_point] == route.positions[seg.last_point])


def test_the_robot_stops_only_in_contact_and_before_go_to_contact(routed):
    """Rest at the start, the end, every hold and every go-to-contact start; moving everywhere else."""
    route, _ = routed
    rest = {0, len(route.times) - 1}
    for seg in route.segments:
        if seg.type == SegmentType.HOLD:
            rest.update(range(seg.first_point, seg.last_point + 1))
        if seg.type == SegmentType.GO_TO_CONTACT:
            rest.add(seg.first_point)
            rest.add(seg.last_point)  # the hold starts there
    speed = np.abs(route.velocities).max(axis=1)
    assert np.all(speed[sorted(rest)] == 0)
    moving = np.ones(len(speed), dtype=bool)
    moving[sorted(rest)] = False
    for seg in route.segments:  # release -> free -> approach without a stop, and go-to-contact's interior
        if seg.type in (SegmentType.FREE, SegmentType.APPROACH, SegmentType.RELEASE):
            boundary = [k for k in (seg.first_point, seg.last_point) if moving[k]]
            assert np.all(speed[boundary] > 0), seg
    assert np.all(speed[moving] > 0)


def test_times_and_limits(scene, routed):
    route, _ = routed
    assert np.all(np.diff(route.times) > 1e-3)
    cfg = scene.route
    assert np.all(np.abs(route.velocities) <= scene.velocity_limit * cfg.velocity_scale_free * (1 + 1e-9))
    assert np.all(np.abs(route.accelerations) <= cfg.acceleration_limit_rad_s2 * (1 + 1e-9))
    for seg in route.segments:  # slower near the table
        v = np.abs(route.velocities[seg.first_point : seg.last_point + 1])
        if seg.type == SegmentType.GO_TO_CONTACT:
            assert np.all(v <= scene.velocity_limit * cfg.velocity_scale_contact * (1 + 1e-9))
        if seg.type in (SegmentType.APPROACH, SegmentType.RELEASE):
            assert np.all(v[1:-1] <= scene.velocity_limit * cfg.velocity_scale_near * (1 + 1e-9))


def test_route_starts_and_ends_at_the_start_posture(scene, routed):
    route, _ = routed
    start = start_posture(scene)
    assert np.allclose(route.positions[0], start) and np.allclose(route.positions[-1], start)


def test_no_joint_jumps_between_waypoints(scene, routed):
    """Every exported step away from the contact segments is within the waypoint step (legs included)."""
    route, _ = routed
    step = scene.route.waypoint_step_rad
    for seg in route.segments:
        if seg.type in (SegmentType.FREE, SegmentType.APPROACH, SegmentType.RELEASE):
            moves = np.abs(np.diff(route.positions[seg.first_point : seg.last_point + 1], axis=0)).max()
            assert moves <= step * (1 + 1e-6), (seg, moves)


def test_tsp_order_is_a_permutation_no_longer_than_nearest_neighbour(scene, example_pool):
    joints = example_pool.joints()[:41]
    start = start_posture(scene)
    v, a = scene.velocity_limit * 0.5, np.full(len(start), 1.5)
    order = order_postures(start, joints, v, a, seed=1)
    assert sorted(order.sequence) == list(range(41))
    assert order.length_s <= order.nearest_neighbour_s + 1e-12
    d = transfer_times(np.vstack([start[None], joints]), v, a)
    path = [0, *[i + 1 for i in order.sequence]]
    assert order.length_s == pytest.approx(sum(d[i, j] for i, j in itertools.pairwise(path)))
    assert order_postures(start, joints, v, a, seed=1) == order  # seeded


def test_rest_to_rest_time_of_a_bang_bang_and_a_trapezoid():
    v, a = np.array([1.0, 1.0]), np.array([2.0, 2.0])
    assert float(rest_to_rest_time(np.array([0.5, 0.1]), v, a)) == pytest.approx(2 * np.sqrt(0.5 / 2))  # never at v
    assert float(rest_to_rest_time(np.array([0.1, 3.0]), v, a)) == pytest.approx(3.0 / 1.0 + 1.0 / 2.0)


def test_same_route_whatever_the_number_of_workers(scene, example_pool, tmp_path):
    rows = [5, 6, 7]
    postures = [example_pool.postures[i] for i in rows]
    files = []
    for workers in (1, 2):
        folder = tmp_path / f"w{workers}"
        route = plan_route(scene, postures, seed=3, workers=workers)
        files.append(write(route, example_pool, rows, folder / "route.yaml"))
    assert files[0].read_bytes() == files[1].read_bytes()
    sidecars = [sidecars_of(f) for f in files]
    assert [s.name for s in sidecars[0]] == [s.name for s in sidecars[1]] and len(sidecars[0]) == 1
    assert sidecars[0][0].read_bytes() == sidecars[1][0].read_bytes()


def unreachable(scene, posture):
    """The posture with an idle-arm joint on its limit: no valid state above the contact."""
    joints = list(posture.joints)
    other = "right" if posture.chain == "left" else "left"
    k = scene.joint_index(f"arm_{other}_1_joint")
    joints[k] = float(scene.upper[k])
    return dataclasses.replace(posture, joints=tuple(joints))


def test_a_lost_posture_is_replaced_by_the_pool_posture_with_the_largest_gain(scene, example_pool):
    rows = routable_rows(scene, example_pool, 8, 3)  # three postures that route: the middle one is made unreachable
    postures = [example_pool.postures[i] for i in rows]
    postures[1] = unreachable(scene, postures[1])
    pool = example_pool
    design = build_design(scene, pool.joints(), [p.chain for p in pool.postures])[0]
    substitutes = Substitutes(pool.postures, tuple(rows), lambda: design)
    route = plan_route(scene, postures, seed=0, substitutes=substitutes)
    assert not route.skipped and len(route.visited) == 3
    (swap,) = route.substitutions
    assert swap.lost == 1 and "vertical approach" in swap.reason
    assert route.visited.count(len(postures) + swap.substitute) == 1 and 1 not in route.visited
    gains = design.gains([rows[0], rows[2]])
    gains[rows] = -np.inf
    assert swap.gain == pytest.approx(float(gains[swap.substitute]))
    assert swap.gain == pytest.approx(float(np.max(gains)))  # the best one could be routed here
    assert swap.rank_after >= swap.rank_before - 3  # a 3-row posture for a 3-row posture


def test_a_posture_held_in_an_earlier_batch_is_never_the_substitute(scene, example_pool):
    """A session's batch must not measure again what an earlier batch held: the best gain held, the next routes."""
    rows = routable_rows(scene, example_pool, 8, 3)
    postures = [example_pool.postures[i] for i in rows]
    postures[1] = unreachable(scene, postures[1])
    design = build_design(scene, example_pool.joints(), [p.chain for p in example_pool.postures])[0]
    gains = design.gains([rows[0], rows[2]])
    gains[rows] = -np.inf
    best = int(np.argmax(gains))
    held = Substitutes(example_pool.postures, tuple(rows), lambda: design, frozenset({best}))
    (swap,) = plan_route(scene, postures, seed=0, substitutes=held).substitutions
    assert swap.substitute != best
    gains[best] = -np.inf
    assert swap.gain == pytest.approx(float(np.max(gains)))  # the best of those not held


def test_without_a_pool_a_lost_posture_is_skipped_with_its_reason(scene, example_pool):
    good = example_pool.postures[0]
    bad = unreachable(scene, example_pool.postures[1])
    route = plan_route(scene, [good, bad], seed=0)
    assert route.visited == (0,)
    assert [i for i, _ in route.skipped] == [1] and "vertical approach" in route.skipped[0][1]


def test_file_loads_as_a_ros2_joint_trajectory(routed):
    import yaml
    from rosbags.typesys import Stores, get_typestore

    from posegen.io import stamp

    _, path = routed
    read = read_route(path)
    times, positions, velocities, accelerations = read.times, read.positions, read.velocities, read.accelerations
    store = get_typestore(Stores.ROS2_HUMBLE)
    types = store.types
    traj = yaml.safe_load(path.read_text())["trajectory"]
    header = types["std_msgs/msg/Header"](
        stamp=types["builtin_interfaces/msg/Time"](**traj["header"]["stamp"]), frame_id=traj["header"]["frame_id"]
    )
    points = [
        types["trajectory_msgs/msg/JointTrajectoryPoint"](
            positions=positions[k],
            velocities=velocities[k],
            accelerations=accelerations[k],
            effort=np.zeros(0),
            time_from_start=types["builtin_interfaces/msg/Duration"](**stamp(float(times[k]))),
        )
        for k in range(len(times))
    ]
    msg = types["trajectory_msgs/msg/JointTrajectory"](header=header, joint_names=traj["joint_names"], points=points)
    raw = store.serialize_cdr(msg, msg.__msgtype__)
    back = store.deserialize_cdr(raw, "trajectory_msgs/msg/JointTrajectory")
    assert back.joint_names == traj["joint_names"] == list(read.joint_names)
    assert len(back.points) == traj["points"] == len(times)
    stamps = [p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in back.points]
    assert np.all(np.diff(stamps) > 0)
    assert all(0 <= p.time_from_start.nanosec < 1_000_000_000 for p in back.points)
    assert np.allclose(back.points[5].positions, positions[5])


def test_stored_points_are_the_planned_ones_to_float32(routed):
    route, path = routed
    read = read_route(path)
    times, positions, velocities = read.times, read.positions, read.velocities
    assert np.array_equal(times, route.times)
    assert np.max(np.abs(positions - route.positions)) <= 2.5e-7
    assert np.max(np.abs(velocities - route.velocities)) <= 2e-6  # float32 and the 2^-20 rad/s grid


def test_a_route_starts_and_ends_where_the_robot_stands(scene, example_pool, routed, tmp_path):
    """The next batch of a session starts where the last one left the robot (here: above a contact)."""
    route, _ = routed
    approach = next(s for s in reversed(route.segments) if s.type == SegmentType.APPROACH)
    standing = route.positions[approach.first_point]  # the standoff above the last contact: no start posture
    assert np.abs(standing - start_posture(scene)).max() > 0.05
    postures = [example_pool.postures[i] for i in ROWS[:2]]
    later = plan_route(scene, postures, seed=0, from_posture=standing)
    assert np.array_equal(later.positions[0], standing) and later.returns
    assert np.array_equal(later.positions[-1], standing)  # and back there
    assert sorted(later.visited) == [0, 1]
    result = verify_route(scene, read_route(write(later, example_pool, ROWS[:2], tmp_path / "later.yaml")))
    assert result.ok, [w for w in result.worst if w.violations]
    with pytest.raises(InputError, match="joint angles"):
        plan_route(scene, postures, seed=0, from_posture=standing[:-1])
    fallen = standing.copy()
    fallen[scene.joint_index("leg_left_4_joint")] += 0.6  # a knee bent: the sole leaves the floor
    with pytest.raises(InfeasibleError, match="the posture given"):
        plan_route(scene, postures, seed=0, from_posture=fallen)
