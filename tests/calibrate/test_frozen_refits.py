"""Frozen refits: the frozen-Jacobian fold refit is a Gauss-Newton step on the same residual."""

import numpy as np
import pytest

from posegen.calibrate.estimation import Noise, _problem, frozen_jacobian
from posegen.calibrate.frozen_refits import refit_frozen, refit_frozen_folds
from posegen.model import DEFAULT_FLOOR_NOISE, DEFAULT_NOISE, CalibrationModel, Contacts, candidate_spec
from posegen.robot import CandidateConfig, PriorConfig


@pytest.mark.parametrize("floor", [False, True])
def test_one_frozen_step_is_one_gauss_newton_step(scene, floor):
    """With the Jacobian of the start point, one chord step equals one Gauss-Newton step.

    The residual lists every contact row, then every floor row: the frozen Jacobian,
    stored per posture, must be stacked in that order (with the floor it was not).
    """
    model = CalibrationModel(scene, ["left", "right"], ["a"], {})
    rng = np.random.default_rng(3)
    joints = np.tile(scene.reference, (6, 1)) + rng.normal(0.0, 0.05, (6, len(scene.joint_names)))
    chains = ("left", "right") * 3
    observations = model.observations(Contacts(joints, chains, ("a",) * 6, tuple("abcdef")))
    candidate = CandidateConfig("legs", ("*.joint_offset", "leg.*"), floor=floor)
    spec = candidate_spec(model, candidate, PriorConfig(), 10.0)
    noise = Noise(DEFAULT_NOISE, DEFAULT_FLOOR_NOISE)
    x = model.nominal() + model.basis @ rng.normal(0.0, 1e-3, model.size)

    delta = refit_frozen(model, observations, spec, noise, x, frozen_jacobian(model, observations, spec, noise, x), 1)

    start = model.delta_of(x)
    free = list(spec.free)
    fun, jac = _problem(model, observations, spec, noise, start, np.ones(len(observations)))
    matrix = jac(start[free])
    step = np.linalg.solve(matrix.T @ matrix, matrix.T @ fun(start[free]))
    np.testing.assert_allclose(delta[free], start[free] - step, rtol=1e-4, atol=1e-9)


@pytest.mark.parametrize("floor", [False, True])
def test_folds_refitted_together_are_each_folds_own_refit(scene, floor):
    """``refit_frozen_folds`` (every fold at once) gives each fold what ``refit_frozen`` on its rows alone gives."""
    model = CalibrationModel(scene, ["left", "right"], ["a"], {"hip_pitch": ("leg_left_3_joint", "leg_right_3_joint")})
    rng = np.random.default_rng(4)
    joints = np.tile(scene.reference, (8, 1)) + rng.normal(0.0, 0.05, (8, len(scene.joint_names)))
    observations = model.observations(Contacts(joints, ("left", "right") * 4, ("a",) * 8, tuple("abcdefgh")))
    candidate = CandidateConfig("legs", ("*.joint_offset", "leg.*"), floor=floor, compliance=("hip_pitch",))
    spec = candidate_spec(model, candidate, PriorConfig(), 10.0)
    noise = Noise(DEFAULT_NOISE, DEFAULT_FLOOR_NOISE)
    x = model.nominal() + model.basis @ rng.normal(0.0, 1e-3, model.size)
    jacobian = frozen_jacobian(model, observations, spec, noise, x)
    folds = [[0, 1, 2, 3, 4, 5], [2, 3, 4, 5, 6, 7], [0, 1, 6, 7]]
    together = refit_frozen_folds(model, observations, spec, noise, x, jacobian, folds, 2)
    for rows, delta in zip(folds, together, strict=True):
        own = (jacobian[0][rows], jacobian[1])
        alone = refit_frozen(model, observations.subset(rows), spec, noise, x, own, 2)
        np.testing.assert_allclose(delta, alone, rtol=1e-9, atol=1e-13)
    assert not np.allclose(together[0], together[1])
