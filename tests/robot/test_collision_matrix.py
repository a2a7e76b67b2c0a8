"""Collision pairs found by sampling, config-disabled pairs and replaced shapes in the checker."""

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from posegen.robot import CollisionChecker, PairSurvey, Scene, load_config
from posegen.robot.additions import PairReason
from posegen.robot.collision_matrix import ALWAYS_FRACTION, survey_scene_pairs
from tests.conftest import ROOT

TALOS_FULL = ROOT / "configs" / "talos_full_table.yaml"
ICUB = ROOT / "configs" / "icub_table.yaml"


@pytest.fixture(scope="module")
def talos_full() -> Scene:
    return Scene(load_config(TALOS_FULL))


@pytest.fixture(scope="module")
def icub() -> Scene:
    return Scene(load_config(ICUB))


@pytest.fixture(scope="module")
def full_survey(talos_full) -> PairSurvey:
    return survey_scene_pairs(talos_full, samples=60, seed=3)


def test_locked_fingers_that_always_touch_are_found(full_survey, talos_full):
    found = {frozenset((p.link_a, p.link_b)) for p in full_survey.disabled}
    shipped = {frozenset((p.link_a, p.link_b)) for p in talos_full.config.collision.disabled_pairs}
    assert found == shipped  # the config's pairs are what the survey finds, and nothing else


def test_each_disabled_pair_meets_its_rule(full_survey, icub):
    survey = survey_scene_pairs(icub, samples=30, seed=1)
    for result in (full_survey, survey):
        for pair in result.disabled:
            if pair.reason == PairReason.ALWAYS:
                assert result.frequency[(pair.link_a, pair.link_b)] >= ALWAYS_FRACTION
        kept = {(p.link_a, p.link_b) for p in result.disabled}
        assert all(f < ALWAYS_FRACTION for pair, f in result.frequency.items() if pair not in kept)


def test_adjacent_links_are_found_through_links_without_geometry(icub):
    survey = survey_scene_pairs(icub, samples=5)
    adjacent = {frozenset((p.link_a, p.link_b)) for p in survey.disabled if p.reason == PairReason.ADJACENT}
    assert frozenset(("torso_1", "chest")) in adjacent  # joined through torso_2, which has no geometry
    assert frozenset(("l_hip_1", "l_upper_leg")) not in adjacent  # two joints apart, both with geometry


def test_disabled_pairs_leave_the_checker(talos_full):
    collision = dataclasses.replace(talos_full.config.collision, disabled_pairs=())
    bare = dataclasses.replace(talos_full.config, collision=collision)
    with_pairs = CollisionChecker(talos_full)
    without = CollisionChecker(Scene(bare))
    assert without.n_pairs - with_pairs.n_pairs == 2
    names = [o.name for o in with_pairs.geom.geometryObjects]
    checked = {frozenset((names[p.first], names[p.second])) for p in with_pairs.geom.collisionPairs}
    assert frozenset(("gripper_left_inner_double_link_0", "gripper_left_inner_single_link_0")) not in checked


def test_capsules_replace_a_links_meshes_along_its_joints(icub):
    checker = CollisionChecker(icub, convex=False)
    names = [str(o.name) for o in checker.geom.geometryObjects]
    assert "l_upper_leg_0" not in names  # the URDF's mesh is gone
    index = next(i for i, n in enumerate(names) if n.startswith("l_upper_leg_shape"))
    data = icub.model.createData()
    q = icub.configuration(icub.reference)
    pin.forwardKinematics(icub.model, data, q)
    geom_data = pin.GeometryData(checker.geom)
    pin.updateGeometryPlacements(icub.model, data, checker.geom, geom_data)
    placement = geom_data.oMg[index]
    half = checker.geom.geometryObjects[index].geometry.halfLength
    ends = [placement.act(np.array([0.0, 0.0, s * half])) for s in (-1, 1)]
    hip = data.oMi[icub.model.getJointId("l_hip_yaw")].translation
    knee = data.oMi[icub.model.getJointId("l_knee")].translation
    assert min(np.linalg.norm(e - hip) for e in ends) < 1e-9  # the capsule runs from the hip joint ...
    assert min(np.linalg.norm(e - knee) for e in ends) < 1e-9  # ... to the knee joint
