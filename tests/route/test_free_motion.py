"""Free motions: every waypoint checked, OMPL's answer independent of what ran before it, the fastest via path kept."""

import threading

import numpy as np
import pinocchio as pin
import pytest
import yaml

from posegen.errors import InfeasibleError
from posegen.robot import TABLE, CollisionChecker, Projector, Scene, StanceSpace, parse_config
from posegen.route import (
    Method,
    Planner,
    Unplanned,
    UnplannedCause,
    free_motions,
    plan_free,
    plan_stop,
    plan_transfer,
    raised_midpoints,
    start_posture,
    straight,
    through,
    vertical_paths,
    via_sequences,
)
from posegen.route.free_motion import RAISE_FRACTIONS, VIA_CANDIDATES, _plan_ompl, stream_of
from posegen.route.planner import _timed_transfer
from tests.conftest import CONFIG, DETOUR_ROWS


@pytest.fixture(scope="module")
def ends(scene, example_pool):
    space = StanceSpace(scene, CollisionChecker(scene, convex=True))
    projector = Projector(scene)
    postures = [example_pool.postures[i] for i in DETOUR_ROWS]
    verticals = [vertical_paths(space, projector, np.array(p.joints), p.chain) for p in postures]
    a, b = verticals
    assert straight(space, a.approach[0], b.approach[0]) is None, f"DETOUR_ROWS {DETOUR_ROWS}: a straight line joins"
    return space, verticals


def test_ompl_gives_the_same_path_whatever_ran_before_it_in_the_process(ends):
    space, (a, b) = ends
    budget = int(space.scene.route.planning_checks)
    first = _plan_ompl(space, a.approach[0], b.approach[0], budget, stream=7)
    _plan_ompl(space, b.approach[0], a.approach[0], 300, stream=2)  # another plan in between
    again = _plan_ompl(space, a.approach[0], b.approach[0], budget, stream=7)
    other = _plan_ompl(space, a.approach[0], b.approach[0], budget, stream=8)
    assert first is not None and again is not None and other is not None
    assert len(first[0]) == len(again[0]) and all(np.array_equal(x, y) for x, y in zip(first[0], again[0], strict=True))
    assert len(first[0]) != len(other[0]) or any(
        not np.array_equal(x, y) for x, y in zip(first[0], other[0], strict=False)
    )


def test_ompl_stops_when_its_goal_is_invalid(example_pool, ends):
    """RRTConnect waits for a valid goal without checking a state: the search must still end (it did not)."""
    space, (a, _) = ends
    touching = np.array(example_pool.postures[DETOUR_ROWS[0]].joints)  # the hand on the table: not a free state
    assert not space.is_valid(touching, None)
    result: list[object] = []
    search = threading.Thread(
        target=lambda: result.append(_plan_ompl(space, a.approach[0], touching, 200, stream=0)), daemon=True
    )
    search.start()
    search.join(timeout=60)
    assert result == [None]


def test_every_waypoint_is_valid_and_steps_are_small(scene, ends):
    space, (a, b) = ends
    assert straight(space, a.approach[0], b.approach[0]) is None
    vias = via_sequences(a.clearance, b.clearance, start_posture(scene))
    found = plan_free(space, a.approach[0], b.approach[0], vias, stream=0)
    assert not isinstance(found, Unplanned)
    path = np.array(found.waypoints)
    assert np.array_equal(path[0], a.approach[0]) and np.array_equal(path[-1], b.approach[0])
    assert all(space.is_valid(q, None) for q in path)
    assert np.abs(np.diff(path, axis=0)).max() <= scene.route.waypoint_step_rad * (1 + 1e-6)


def table_distance(checker, scene, joints):
    """The smallest distance (m) of the robot to the table, every pair computed (no screening, no margins)."""
    data = pin.GeometryData(checker.geom)
    pin.computeDistances(scene.model, scene.model.createData(), checker.geom, data, scene.configuration(joints))
    pairs = [k for k in range(checker.n_pairs) if TABLE in checker._pair_names(k)]
    return min(data.distanceResults[k].min_distance for k in pairs)


def test_free_states_keep_the_table_clearance_and_approach_states_need_not(scene, ends):
    space, (a, b) = ends
    clearance = scene.margins.table_clearance_m
    assert clearance > scene.route.pre_contact_m  # TALOS's config: the last approach state is below the clearance
    low = a.approach[-1]
    assert table_distance(space.checker, scene, low) < clearance
    assert space.is_valid(low, None, near_table=True) and not space.is_valid(low, None)
    data = yaml.safe_load(CONFIG.read_text())
    data["margins"].pop("table_clearance_m")
    plain = StanceSpace(Scene(parse_config(data, str(CONFIG))), space.checker)
    assert plain.is_valid(low, None)  # without the key: the collision margin only, as before
    vias = via_sequences(a.clearance, b.clearance, start_posture(scene))
    found = plan_free(space, a.approach[0], b.approach[0], vias, stream=0)
    assert not isinstance(found, Unplanned)
    assert min(table_distance(space.checker, scene, q) for q in found.waypoints) >= clearance


def test_via_sequences_skip_missing_lifts_and_duplicates(scene):
    home = start_posture(scene)
    lift = home + 0.1
    assert via_sequences(None, None, home) == [[home]]
    sequences = via_sequences(lift, None, home)
    assert len(sequences) == 3 and sequences[0] == [lift]


@pytest.fixture(scope="module")
def detour(scene, example_pool):
    """Two stops of the example pool whose straight line is blocked, with raised midpoints and via paths."""
    planner = Planner(scene, seed=0)
    postures = [example_pool.postures[i] for i in DETOUR_ROWS]
    stops = [plan_stop(planner, (i, tuple(p.joints), p.chain)) for i, p in zip(DETOUR_ROWS, postures, strict=True)]
    assert not any(isinstance(s, Unplanned) for s in stops), f"DETOUR_ROWS {DETOUR_ROWS}: a stop does not plan"
    a, b = stops
    assert raised_midpoints(planner.space, a.approach[0], b.approach[0], a.lift, b.lift), f"DETOUR_ROWS {DETOUR_ROWS}"
    return planner, stops


def test_raised_midpoints_are_valid_states_halfway_between_the_ends_and_up(detour):
    planner, (a, b) = detour
    space, start, goal = planner.space, a.approach[0], b.approach[0]
    found = raised_midpoints(space, start, goal, a.lift, b.lift)
    assert found  # this pair has them (the fixture checks)
    lift = ((a.lift - start) + (b.lift - goal)) / 2
    expected = [space.coordinates_of((start + goal) / 2 + f * lift) for f in RAISE_FRACTIONS]
    for state in found:
        assert space.is_valid(state, None)
        assert any(np.allclose(space.coordinates_of(state), x, atol=1e-12) for x in expected)
        closed = space.joints_of(space.coordinates_of(state), state)
        assert closed is not None and np.allclose(closed, state, atol=1e-9)  # the second leg is already closed
    assert raised_midpoints(space, start, goal, None, b.lift) == []


def test_free_motions_returns_the_first_via_paths_each_checked(detour):
    planner, (a, b) = detour
    space, start, goal = planner.space, a.approach[0], b.approach[0]
    vias = [[m] for m in raised_midpoints(space, start, goal, a.lift, b.lift)]
    vias += via_sequences(a.lift, b.lift, planner.start)
    found = free_motions(space, start, goal, vias, stream=0, via_candidates=2)
    assert not isinstance(found, Unplanned) and len(found) == 2
    for motion in found:
        assert motion.method == Method.VIA
        path = np.array(motion.waypoints)
        assert np.array_equal(path[0], start) and np.array_equal(path[-1], goal)
        assert all(space.is_valid(q, None) for q in path)
    first = plan_free(space, start, goal, vias, stream=0)
    assert not isinstance(first, Unplanned)
    assert all(np.array_equal(x, y) for x, y in zip(first.waypoints, found[0].waypoints, strict=True))


def test_a_transfer_keeps_its_fastest_via_path(detour):
    planner, (a, b) = detour
    space, start, goal = planner.space, a.approach[0], b.approach[0]
    vias = [[m] for m in raised_midpoints(space, start, goal, a.lift, b.lift)]
    vias += via_sequences(a.lift, b.lift, planner.start)
    found = free_motions(space, start, goal, vias, stream=stream_of(planner.seed, a.node, b.node))
    assert not isinstance(found, Unplanned) and len(found) == VIA_CANDIDATES
    durations = [_timed_transfer(planner, m, a, b, (a.node, b.node)).timed.times[-1] for m in found]
    assert durations[0] > min(durations)  # here the first via path found is not the fastest
    transfer = plan_transfer(planner, (a, b))
    assert not isinstance(transfer, Unplanned)
    assert transfer.timed.times[-1] == min(durations)


def test_a_via_state_equal_to_an_end_is_dropped_not_repeated(detour):
    planner, (a, b) = detour
    space, start, goal = planner.space, a.approach[0], b.approach[0]
    ladder = [[m] for m in raised_midpoints(space, start, goal, a.lift, b.lift)]
    ladder += via_sequences(a.lift, b.lift, planner.start)
    via = next(v for v in ladder if through(space, [start, *v, goal]) is not None)
    # each of these is the path start -> via -> goal once a via state equal to an end is dropped
    vias = [via, [start, *via], [*via, goal], [start, start, *via, goal]]
    found = free_motions(space, start, goal, vias, stream=0, via_candidates=len(vias))
    assert not isinstance(found, Unplanned) and len(found) == 1 and found[0].method == Method.VIA
    steps = np.abs(np.diff(np.array(found[0].waypoints), axis=0)).max(axis=1)
    assert steps.min() > 0.0  # no waypoint repeated
    assert free_motions(space, start, goal, [[start], [goal]], stream=0, via_candidates=2)[0].method != Method.VIA


def test_a_path_toppra_cannot_time_is_a_planning_failure_not_a_crash(detour, example_pool, monkeypatch):
    import posegen.route.balancing as timing_module  # the planner times every path through it

    planner, (a, b) = detour
    timed = timing_module.parameterize
    calls = []

    def first_fails(*args, **kwargs):
        calls.append(1)
        if len(calls) == 1:
            raise InfeasibleError("toppra found no parameterisation of a path of 9 waypoints")
        return timed(*args, **kwargs)

    monkeypatch.setattr(timing_module, "parameterize", first_fails)
    transfer = plan_transfer(planner, (a, b))  # two via paths: the second is timed
    assert not isinstance(transfer, Unplanned) and 2 <= len(calls) <= 4  # the 2nd; again with ZMP, torques if needed

    def never(*args, **kwargs):
        raise InfeasibleError("toppra found no parameterisation of a path of 9 waypoints")

    monkeypatch.setattr(timing_module, "parameterize", never)
    untimed = plan_transfer(planner, (a, b))
    assert isinstance(untimed, Unplanned) and untimed.cause is UnplannedCause.NO_TIMING
    assert str(untimed) == (
        "no time parameterisation of the planned path: 2 free motions found, none timed: "
        "toppra found no parameterisation of a path of 9 waypoints"
    )
    posture = example_pool.postures[4]  # one with a vertical approach (posture 3 has none)
    stop = plan_stop(planner, (4, tuple(posture.joints), posture.chain))
    assert isinstance(stop, Unplanned) and stop.cause is UnplannedCause.NO_TIMING
