"""Shortcuts and blends: shorter and rounder, every new state valid, kept waypoints untouched."""

import dataclasses

import numpy as np
import pytest

from posegen.robot import CollisionChecker, Projector, Scene, StanceSpace
from posegen.route import blend_corners, corners, path_length, shortcut, through, vertical_paths
from tests.conftest import DETOUR_ROWS


@pytest.fixture(scope="module")
def detour(scene, example_pool):
    """Two approach poses joined through both lifts: a path with two corners."""
    space = StanceSpace(scene, CollisionChecker(scene, convex=True))
    projector = Projector(scene)
    postures = [example_pool.postures[i] for i in DETOUR_ROWS]
    a, b = (vertical_paths(space, projector, np.array(p.joints), p.chain) for p in postures)
    path = through(space, [a.approach[0], a.clearance, b.clearance, b.approach[0]])
    assert path is not None, f"DETOUR_ROWS {DETOUR_ROWS}: no path through both lifts"
    return space, path


def sharpest_turn(path, velocity_limit):
    """The largest angle (deg) between two consecutive steps, in joint space scaled by the velocity limits."""
    steps = np.diff(np.array(path) / velocity_limit, axis=0)
    steps = steps[np.linalg.norm(steps, axis=1) > 1e-6]
    unit = steps / np.linalg.norm(steps, axis=1)[:, None]
    return float(np.degrees(np.arccos(np.clip(np.sum(unit[:-1] * unit[1:], axis=1), -1, 1)).max()))


def test_shortcuts_never_lengthen_and_keep_the_ends(scene, detour):
    space, path = detour
    short = shortcut(space, path, np.random.default_rng(0), tries=12)
    assert path_length(short, scene.velocity_limit) <= path_length(path, scene.velocity_limit) + 1e-12
    assert np.array_equal(short[0], path[0]) and np.array_equal(short[-1], path[-1])
    assert all(space.is_valid(q, None) for q in short)


def test_blends_round_the_corners_outside_the_kept_waypoints(scene, detour):
    space, path = detour
    keep = [False] * len(path)
    keep[:3] = keep[-3:] = [True] * 3
    labels = ["a"] * len(path)
    before = corners(path, scene.velocity_limit)
    blended, new_keep, new_labels = blend_corners(space, path, keep, labels, "blend")
    assert len(before) >= 2
    assert sharpest_turn(blended, scene.velocity_limit) < sharpest_turn(path, scene.velocity_limit) / 2
    assert all(np.array_equal(x, y) for x, y in zip(blended[:3] + blended[-3:], path[:3] + path[-3:], strict=True))
    assert new_keep[:3] == [True] * 3 and len(new_keep) == len(new_labels) == len(blended)
    assert "blend" in new_labels
    assert all(space.is_valid(q, None) for q in blended)
    assert np.abs(np.diff(np.array(blended), axis=0)).max() <= scene.route.waypoint_step_rad * (1 + 1e-6)


def test_a_blend_that_takes_later_corners_in_leaves_them_alone(config, detour):
    _, path = detour
    coarse = Scene(dataclasses.replace(config, route=dataclasses.replace(config.route, waypoint_step_rad=100.0)))
    zigzag = [path[i] for i in (0, 30, 60, 40, 90, len(path) - 1)]  # a corner at every inner waypoint
    assert corners(zigzag, coarse.velocity_limit) == [1, 2, 3, 4]
    space = StanceSpace(coarse, CollisionChecker(coarse, convex=True))  # a blend is two waypoints: the path shrinks
    blended, keep, labels = blend_corners(space, zigzag, [False] * 6, ["a"] * 6, "blend")
    assert len(blended) == len(keep) == len(labels) < 6  # was an IndexError on the corners the first blend took in
    assert np.array_equal(blended[0], zigzag[0]) and np.array_equal(blended[-1], zigzag[-1])
    assert all(space.is_valid(q, None) for q in blended)
