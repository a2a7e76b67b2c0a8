"""Free motions: every waypoint checked, and OMPL's answer independent of what ran before it."""

import numpy as np
import pytest

from posegen.robot import CollisionChecker, Projector, StanceSpace
from posegen.route import plan_free, start_posture, straight, vertical_paths, via_sequences
from posegen.route.free_motion import _plan_ompl


@pytest.fixture(scope="module")
def ends(scene, example_pool):
    space = StanceSpace(scene, CollisionChecker(scene, convex=True))
    projector = Projector(scene)
    postures = [example_pool.postures[i] for i in (9, 5)]  # the straight line and the vias are blocked
    verticals = [vertical_paths(space, projector, np.array(p.joints), p.chain) for p in postures]
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


def test_every_waypoint_is_valid_and_steps_are_small(scene, ends):
    space, (a, b) = ends
    assert straight(space, a.approach[0], b.approach[0]) is None
    vias = via_sequences(a.clearance, b.clearance, start_posture(scene))
    found = plan_free(space, a.approach[0], b.approach[0], vias, stream=0)
    assert not isinstance(found, str)
    path = np.array(found.waypoints)
    assert np.array_equal(path[0], a.approach[0]) and np.array_equal(path[-1], b.approach[0])
    assert all(space.is_valid(q, None) for q in path)
    assert np.abs(np.diff(path, axis=0)).max() <= scene.route.waypoint_step_rad * (1 + 1e-6)


def test_via_sequences_skip_missing_lifts_and_duplicates(scene):
    home = start_posture(scene)
    lift = home + 0.1
    assert via_sequences(None, None, home) == [[home]]
    sequences = via_sequences(lift, None, home)
    assert len(sequences) == 3 and sequences[0] == [lift]
