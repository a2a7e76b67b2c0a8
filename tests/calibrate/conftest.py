"""A lean calibration config for tests: few candidates, scales and fold seeds (fast, same code paths)."""

import dataclasses

import pytest

from posegen.robot import CandidateConfig, Scene

HIP_PITCH = {"hip_pitch": ("leg_left_3_joint", "leg_right_3_joint")}
LEAN_CANDIDATES = (
    CandidateConfig("offsets", ("*.joint_offset",)),
    CandidateConfig("offsets_hip_pitch", ("*.joint_offset",), compliance=("hip_pitch",)),
)


@pytest.fixture(scope="session")
def lean_scene(scene):
    calibration = dataclasses.replace(
        scene.calibration,
        compliance=HIP_PITCH,
        candidates=LEAN_CANDIDATES,
        prior_scales=(3.0, 30.0),
        folds=3,
        fold_seeds=2,
    )
    return Scene(dataclasses.replace(scene.config, calibration=calibration))
