"""Calibration on simulated contacts (known truth) and on the real TALOS recordings."""

import numpy as np
import pytest

from posegen.calibrate import Perturbation, Settings, calibrate, held_out_residuals, read_measurements, simulate
from posegen.model import ContactModel, Contacts, Group, settle_contacts, structural_base
from tests.conftest import REAL_DATA

TO_DISPLAY = np.array([1e3, 180 / np.pi, 180 / np.pi])  # mm, deg, deg


@pytest.fixture(scope="module")
def noiseless(scene, example_pool):
    rows = list(range(150))
    joints = example_pool.joints()[rows]
    plan = Contacts(joints, tuple(example_pool.postures[i].chain for i in rows), ("sim",) * 150, ("",) * 150)
    recorded, model, theta = simulate(scene, plan, Perturbation(), seed=5)
    train, test = recorded.subset(range(100)), recorded.subset(range(100, 150))
    calibration = calibrate(scene, train, ["sim"], Settings(kappa=1e4))  # a prior too weak to bias
    return calibration, test, model, theta


def test_noiseless_held_out_residuals_vanish(noiseless):
    calibration, test, _, _ = noiseless
    residuals = held_out_residuals(calibration, test)
    after = np.abs(residuals["training_plane"]["after"]) * TO_DISPLAY
    assert after[:, 0].max() < 0.01  # mm
    assert after[:, 1:].max() < 0.001  # deg
    before = np.abs(residuals["training_plane"]["before"]) * TO_DISPLAY
    assert before[:, 0].max() > 1.0  # the errors were real


def test_known_errors_on_base_parameters_are_recovered(scene, example_pool):
    """Errors put on base parameters only (dependent ones nominal) come back exactly."""
    rows = list(range(100))
    chains = tuple(example_pool.postures[i].chain for i in rows)
    plan = Contacts(example_pool.joints()[rows], chains, ("sim",) * 100, ("",) * 100)
    model = ContactModel(scene, sorted(set(chains)), ["sim"])
    base = structural_base(model, plan)
    rng = np.random.default_rng(11)
    theta = model.nominal()
    robot = [c for c in base.columns if model.parameters[c].group != Group.PLANE]
    for c in robot:
        theta[c] += rng.normal(0, 2e-3) if model.parameters[c].unit.value == "m" else rng.normal(0, np.deg2rad(0.5))
    theta[model.index["plane@sim.z"]] = 0.68
    theta[model.index["plane@sim.roll"]] = np.deg2rad(0.3)
    recorded = settle_contacts(model, theta, plan)
    calibration = calibrate(scene, recorded, ["sim"], Settings(kappa=1e4), base=base)
    assert calibration.after.theta[robot] == pytest.approx(theta[robot], abs=1e-6)  # m and rad
    planes = model.columns(Group.PLANE)
    assert calibration.after.theta[planes] == pytest.approx(theta[planes], abs=1e-6)


def test_outlier_contact_is_detected_and_left_out(scene, example_pool):
    rows = list(range(90))
    plan = Contacts(
        example_pool.joints()[rows],
        tuple(example_pool.postures[i].chain for i in rows),
        ("sim",) * 90,
        tuple(f"c{i}" for i in rows),
    )
    recorded, _, _ = simulate(scene, plan, Perturbation(encoder_noise_rad=np.deg2rad(0.01)), seed=6)
    joints = recorded.joints.copy()
    joints[17, scene.joint_index("arm_left_4_joint" if recorded.chains[17] == "left" else "arm_right_4_joint")] += 0.05
    bad = Contacts(joints, recorded.chains, recorded.sessions, recorded.labels)
    calibration = calibrate(scene, bad, ["sim"], Settings(kappas=(2.0, 10.0)))
    assert 17 in calibration.outliers
    assert 17 not in calibration.kept and len(calibration.outliers) <= 3


def test_too_few_contacts(scene, example_pool):
    from posegen.errors import InfeasibleError

    plan = Contacts(example_pool.joints()[:4], ("left",) * 4, ("s",) * 4, ("",) * 4)
    with pytest.raises(InfeasibleError, match="at least"):
        calibrate(scene, plan, ["s"])


@pytest.fixture(scope="module")
def real(scene):
    train = read_measurements(REAL_DATA / "left_train.csv", scene).contacts.concat(
        read_measurements(REAL_DATA / "right_train.csv", scene).contacts
    )
    held_out = read_measurements(REAL_DATA / "left_validation.csv", scene).contacts
    sessions = ["left_train", "right_train", "left_validation"]
    return calibrate(scene, train, sessions), held_out


def test_real_data_beats_before_and_the_published_toolbox(real):
    calibration, held_out = real
    residuals = held_out_residuals(calibration, held_out)
    for protocol in ("training_plane", "refitted_plane"):
        before = np.mean(np.abs(residuals[protocol]["before"]), axis=0) * TO_DISPLAY
        after = np.mean(np.abs(residuals[protocol]["after"]), axis=0) * TO_DISPLAY
        assert np.all(after < before), (protocol, before, after)
    after = np.mean(np.abs(residuals["training_plane"]["after"]), axis=0) * TO_DISPLAY
    assert np.all(after <= [4.86, 0.44, 0.50])  # the authors' public toolbox on the same data
