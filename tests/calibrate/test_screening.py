"""Screening never costs the calibration: monotone, bounded, and bad rows of the real recordings found."""

import dataclasses

import numpy as np
import pytest

from posegen.calibrate import Perturbation, Settings, calibrate, held_out_residuals, simulate
from posegen.model import Contacts, read_measurements
from posegen.robot import Scene
from tests.calibrate.test_calibration import COMPLIANCE, planned

SESSIONS = ["left_train", "right_train", "left_validation"]
LEAN = Settings(candidates=("offsets", "offsets_hip_pitch"), fold_seeds=2)
# (file, line, joint, rad): rows of the real recordings corrupted by a joint error their contact sees
CORRUPTIONS = {
    1: [("right_train.csv", 12, "arm_right_4_joint", 0.3)],
    2: [("right_train.csv", 12, "arm_right_4_joint", 0.3), ("left_train.csv", 9, "arm_left_2_joint", -0.05)],
    3: [
        ("right_train.csv", 12, "arm_right_4_joint", -0.1),
        ("left_train.csv", 9, "arm_left_2_joint", 0.05),
        ("right_train.csv", 20, "torso_2_joint", 0.08),
    ],
}


@pytest.fixture(scope="module")
def real(scene, real_data):
    train = read_measurements(real_data / "left_train.csv", scene).contacts.concat(
        read_measurements(real_data / "right_train.csv", scene).contacts
    )
    held_out = read_measurements(real_data / "left_validation.csv", scene).contacts
    clean = calibrate(scene, train, SESSIONS, LEAN)
    return train, held_out, clean


def held_out_z(calibration, held_out):
    return float(np.mean(np.abs(held_out_residuals(calibration, held_out)["training_plane"]["after"][:, 0])))


def row_of(contacts, file, line):
    return next(i for i, label in enumerate(contacts.labels) if label.startswith(f"{file}:{line}:"))


@pytest.mark.parametrize("count", sorted(CORRUPTIONS))
def test_corrupted_real_rows_are_flagged_and_the_held_out_error_stays(scene, real, count):
    train, held_out, clean = real
    joints = train.joints.copy()
    rows = []
    for file, line, joint, error in CORRUPTIONS[count]:
        rows.append(row_of(train, file, line))
        joints[rows[-1], scene.joint_index(joint)] += error
    calibration = calibrate(scene, train.at(joints), SESSIONS, LEAN)  # never an error
    flagged = {f.row for f in calibration.flags}
    assert set(rows) <= flagged and not flagged & set(calibration.kept)
    assert {f.row for f in clean.flags} <= flagged  # no masking: the rows a clean run leaves out stay out
    assert held_out_z(calibration, held_out) <= 1.1 * held_out_z(clean, held_out)


def test_valid_rows_never_make_screening_oscillate(scene, real):
    """left_train less its rows 2 and 7 ended in 'screening still changes the rows' before screening was monotone."""
    train, _, _ = real
    keep = [
        i for i, label in enumerate(train.labels) if not label.startswith(("left_train.csv:2:", "left_train.csv:7:"))
    ]
    calibration = calibrate(scene, train.subset(keep), SESSIONS, LEAN)
    assert len(calibration.kept) + len(calibration.flags) == len(keep)


def test_screening_stops_at_its_limit_and_says_so(lean_scene, example_pool):
    """A third of the rows corrupted: at most max_left_out of them are left out, the largest, with a warning.

    A third is past what a screening can promise: errors of one sign on one joint are in part
    taken up by its offset, and masking may hide most bad rows (the same errors all positive:
    1 to 8 of 14 found, depending on the 40 postures). Here they alternate in sign, and the
    limit is a tenth of the rows: more bad rows stand out than it allows, in every window of
    40 postures of the example pools tried (7-8 found with a fifth as the limit).
    """
    scene = Scene(
        dataclasses.replace(
            lean_scene.config, calibration=dataclasses.replace(lean_scene.calibration, max_left_out=0.1)
        )
    )
    recorded, _, _ = simulate(
        scene,
        planned(example_pool, list(range(80, 120))),
        Perturbation(encoder_noise_rad=np.deg2rad(0.005), compliance_rad_per_nm=COMPLIANCE),
        seed=6,
    )
    joints = recorded.joints.copy()
    bad = list(range(0, len(recorded), 3))  # every third row
    for k, row in enumerate(bad):
        joints[row, scene.joint_index(f"arm_{recorded.chains[row]}_4_joint")] += (-1) ** k * (0.1 + 0.02 * k)
    data = Contacts(joints, recorded.chains, recorded.sessions, recorded.labels)
    calibration = calibrate(scene, data, ["sim"], Settings(fold_seeds=1))
    left_out = [f for f in calibration.flags if f.reason == "residual"]
    limit = int(np.floor(0.1 * len(recorded)))
    assert len(left_out) == limit < len(bad) and {f.row for f in left_out} <= set(bad)
    assert any("limit" in w for w in calibration.warnings)
    assert len(calibration.kept) == len(recorded) - limit
