"""Remembered evaluations: the same numbers as evaluating again, shared read-only, never of other observations."""

from functools import partial

import numpy as np
import pytest

from posegen.calibrate import estimation
from posegen.calibrate.estimation import Noise, estimate, fit
from posegen.model import (
    DEFAULT_FLOOR_NOISE,
    DEFAULT_NOISE,
    CalibrationModel,
    Contacts,
    Evaluations,
    Kind,
    candidate_spec,
    start_point,
)
from posegen.robot import CandidateConfig, PriorConfig

COMPLIANCE = {"hip_pitch": ["leg_left_3_joint", "leg_right_3_joint"]}


@pytest.fixture(scope="module")
def model(scene):
    return CalibrationModel(scene, ["left", "right"], ["a"], COMPLIANCE)


@pytest.fixture(scope="module")
def observations(scene, model):
    rng = np.random.default_rng(7)
    joints = np.tile(scene.reference, (6, 1)) + rng.normal(0.0, 0.1, (6, len(scene.joint_names)))
    return model.observations(Contacts(joints, ("left", "right") * 3, ("a",) * 6, tuple("abcdef")))


def _x(model, seed):
    x = model.nominal() + model.basis @ np.random.default_rng(seed).normal(0.0, 2e-3, model.size)
    x[model.columns([Kind.COMPLIANCE])] = 2e-4  # rad/N m
    return x


def _arrays(evaluation):
    return (evaluation.contact, evaluation.floor, evaluation.contact_jacobian, evaluation.floor_jacobian)


def test_a_remembered_evaluation_is_the_models_own(model, observations):
    evaluations = Evaluations(model, observations, remembered=2)
    x = _x(model, 1)
    first = evaluations.evaluate(x, jacobian=True)
    assert evaluations.evaluate(x.copy(), jacobian=True) is first  # the same bytes: made once
    for mine, fresh in zip(_arrays(first), _arrays(model.evaluate(x, observations, jacobian=True)), strict=True):
        assert np.array_equal(mine, fresh) and not mine.flags.writeable
    assert evaluations.evaluate(x, jacobian=False) is not first  # another question at the same point
    assert evaluations.evaluate(x, jacobian=True, floor=False).floor.shape == (len(observations), 0)
    assert evaluations.evaluate(x, jacobian=True) is not first  # forgotten: two others asked since
    other = x.copy()
    other[0] += 1e-9
    assert not np.array_equal(evaluations.evaluate(other).contact, evaluations.evaluate(x).contact)


def test_a_fit_with_remembered_evaluations_is_the_same_fit(model, observations, monkeypatch):
    """Sharing evaluations between the fits of an estimate changes no bit of it (only what is computed twice)."""
    candidate = CandidateConfig("legs", ("*.joint_offset", "leg.*"), floor=True)
    spec = candidate_spec(model, candidate, PriorConfig(), 10.0)
    noise = Noise(DEFAULT_NOISE, DEFAULT_FLOOR_NOISE)
    start = start_point(model, observations)
    shared = Evaluations(model, observations)
    once, used = fit(model, observations, spec, noise, start, evaluations=shared)
    again, used_again = fit(model, observations, spec, noise, start)
    assert used == used_again and np.array_equal(once, again)
    second = fit(model, observations, spec, noise, model.x_of(once), evaluations=shared)[0]  # starts where it ended
    assert np.array_equal(second, fit(model, observations, spec, noise, model.x_of(once))[0])
    shared_estimate = estimate(model, observations, spec, noise, start)
    monkeypatch.setattr(estimation, "Evaluations", partial(Evaluations, remembered=0))  # nothing remembered
    alone = estimate(model, observations, spec, noise, start)
    assert shared_estimate.iterations == alone.iterations > 0
    for mine, fresh in ((shared_estimate.x, alone.x), (shared_estimate.std, alone.std)):
        assert np.array_equal(mine, fresh)
    assert shared_estimate.noise == alone.noise
    with pytest.raises(ValueError, match="other observations than the ones given"):
        fit(model, observations.subset(range(4)), spec, noise, start, evaluations=shared)
    other = CalibrationModel(model.scene, ["left", "right"], ["a"], COMPLIANCE)  # the same layout, another object
    with pytest.raises(ValueError, match="another model"):
        fit(other, observations, spec, noise, start, evaluations=shared)
