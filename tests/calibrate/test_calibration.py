"""Calibration: recovery of a known robot (with and without the floor equations and compliance),
a corrupted row, unusable rows, and the real TALOS recordings."""

import dataclasses

import numpy as np
import pytest

from posegen.calibrate import (
    Noise,
    Perturbation,
    Settings,
    calibrate,
    estimate,
    held_out_residuals,
    simulate,
    true_parameters,
)
from posegen.calibrate.calibration import check_enough, unusable_rows
from posegen.calibrate.estimation import held_at_urdf
from posegen.calibrate.simulation import settle_true
from posegen.errors import InputError
from posegen.model import (
    DEFAULT_FLOOR_NOISE,
    DEFAULT_NOISE,
    CalibrationModel,
    Contacts,
    Kind,
    Part,
    candidate_spec,
    read_measurements,
    start_point,
)
from posegen.robot import CandidateConfig, PriorConfig
from tests.calibrate.conftest import HIP_PITCH

TO_DISPLAY = np.array([1e3, 180 / np.pi, 180 / np.pi])  # mm, deg, deg
COMPLIANCE = 3e-4  # rad/N m: ~1 deg of hip sag under 50 N m
OFFSETS_LEGS = CandidateConfig("offsets_legs", ("*.joint_offset", "leg.*"))
OFFSETS_LEGS_HIP = CandidateConfig("offsets_legs_hip", ("*.joint_offset", "leg.*"), compliance=("hip_pitch",))


def planned(pool, rows, session="sim"):
    chains = tuple(pool.postures[i].chain for i in rows)
    return Contacts(pool.joints()[rows], chains, (session,) * len(rows), tuple(f"sim.yaml:{i}:c{i}" for i in rows))


@pytest.fixture(scope="module")
def truth(scene, example_pool):
    """A compliant robot whose errors lie along joint offsets, leg placements and contact offsets."""
    model = CalibrationModel(scene, ["left", "right"], ["sim"], HIP_PITCH)
    rng = np.random.default_rng(21)
    delta = np.zeros(model.size)
    for i, d in enumerate(model.directions):
        if d.kind == Kind.JOINT_OFFSET:
            delta[i] = np.deg2rad(0.3) * rng.normal()
        elif d.part == Part.LEG:
            delta[i] = (1.5e-3 if d.kind == Kind.LINK_TRANSLATION else np.deg2rad(0.2)) * rng.normal()
        elif d.kind in (Kind.CONTACT_HEIGHT, Kind.CONTACT_TILT):
            delta[i] = (1e-3 if d.kind == Kind.CONTACT_HEIGHT else np.deg2rad(0.2)) * rng.normal()
    rigid = Perturbation(length_m=0.0, angle_rad=0.0, compliance_rad_per_nm=COMPLIANCE)
    x = true_parameters(model, rigid, seed=21) + model.basis @ delta
    recorded, converged, _ = settle_true(model, x, planned(example_pool, list(range(80))))
    recorded = recorded.subset(np.flatnonzero(converged))
    return model, x, recorded.subset(range(60)), recorded.subset(range(60, len(recorded)))


def fit(model, contacts, candidate, floor):
    spec = candidate_spec(model, dataclasses.replace(candidate, floor=floor), PriorConfig(), 10.0)
    observations = model.observations(contacts)
    start = held_at_urdf(model, spec, start_point(model, observations))
    return estimate(model, observations, spec, Noise(DEFAULT_NOISE, DEFAULT_FLOOR_NOISE), start)


@pytest.fixture(scope="module")
def fits(truth):
    model, _, train, _ = truth
    return {floor: fit(model, train, OFFSETS_LEGS_HIP, floor) for floor in (False, True)}


def test_a_known_robot_is_recovered_with_and_without_the_floor_equations(truth, fits):
    model, x, _, test = truth
    observations = model.observations(test)
    compliance = model.columns([Kind.COMPLIANCE])
    for floor, estimate_ in fits.items():
        held_out = model.evaluate(estimate_.x, observations, floor=False).contact * TO_DISPLAY
        assert np.abs(held_out[:, 0]).max() < 0.05, floor  # mm
        assert np.abs(held_out[:, 1:]).max() < 0.005, floor  # deg
        assert estimate_.x[compliance] == pytest.approx(x[compliance], rel=0.03), floor


def test_the_floor_equations_recover_the_legs_that_contacts_cannot_see(truth, fits):
    """Leg errors that only open the stance loop are invisible to contacts; the floor equations pin them."""
    model, _, _, test = truth
    closure = {floor: model.evaluate(fits[floor].x, model.observations(test)).floor for floor in fits}
    height = {floor: np.abs(c[:, 2]).max() for floor, c in closure.items()}  # the second sole's, zero in truth
    assert height[True] < 0.01 * height[False] and height[True] < 1e-6  # m


def test_without_compliance_a_compliant_robot_is_not_recovered(truth, fits):
    model, _, train, test = truth
    rigid = fit(model, train, OFFSETS_LEGS, floor=False)
    observations = model.observations(test)
    error_rigid = np.abs(model.evaluate(rigid.x, observations, floor=False).contact[:, 0]).mean()
    error_compliant = np.abs(model.evaluate(fits[False].x, observations, floor=False).contact[:, 0]).mean()
    assert error_rigid > 10 * error_compliant and error_rigid > 2e-4  # m


@pytest.fixture(scope="module")
def robust(lean_scene, example_pool):
    """Calibrations of one simulated compliant robot, clean and with one arm joint of one row off by 0.3 rad."""
    recorded, _, _ = simulate(
        lean_scene,
        planned(example_pool, list(range(70))),
        Perturbation(encoder_noise_rad=np.deg2rad(0.005), compliance_rad_per_nm=COMPLIANCE),
        seed=6,
    )
    train, test = recorded.subset(range(50)), recorded.subset(range(50, len(recorded)))
    joints = train.joints.copy()
    bad_row = 7
    joints[bad_row, lean_scene.joint_index(f"arm_{train.chains[bad_row]}_4_joint")] += 0.3
    corrupted = Contacts(joints, train.chains, train.sessions, train.labels)
    return (
        {name: calibrate(lean_scene, data, ["sim"]) for name, data in (("clean", train), ("bad", corrupted))},
        test,
        bad_row,
    )


def test_a_corrupted_row_is_left_out_and_the_held_out_error_stays(robust):
    calibrations, test, bad_row = robust
    flagged = [f for f in calibrations["bad"].flags if f.reason == "residual"]
    assert bad_row in [f.row for f in flagged] and bad_row not in calibrations["bad"].kept
    error = {
        name: np.sqrt(np.mean(held_out_residuals(c, test)["training_plane"]["after"][:, 0] ** 2))
        for name, c in calibrations.items()
    }
    # Both are micrometres (0.005 deg of encoder noise): one row fewer may move the cross-validated
    # choice and the error by ~20 %; a 0.3 rad row kept would put it at millimetres.
    assert error["bad"] <= 1.25 * error["clean"], error


def test_the_compliant_candidate_is_chosen_for_a_compliant_robot(robust):
    calibrations, _, _ = robust
    selection = calibrations["clean"].selection
    assert selection.chosen.candidate == "offsets_hip_pitch"
    assert 0.0 <= selection.stability <= 1.0 and len(selection.seed_picks) == 2


def test_unusable_rows_are_reported_and_too_few_rows_refused(lean_scene, example_pool):
    contacts = planned(example_pool, list(range(12)))
    sessions = ("sim",) * 11 + ("alone",)
    joints = contacts.joints.copy()
    joints[3, lean_scene.joint_index("leg_left_4_joint")] += 0.2  # the left knee bends: a sole leaves the floor
    data = Contacts(joints, contacts.chains, sessions, contacts.labels)
    model = CalibrationModel(lean_scene, ["left", "right"], ["sim", "alone"], HIP_PITCH)
    flags = {f.row: f.reason for f in unusable_rows(model, model.observations(data), lean_scene.calibration)}
    assert flags == {3: "feet off the floor (mm or deg)", 11: "alone in its session"}
    with pytest.raises(InputError, match="plane parameters"):
        check_enough(model, data.subset([0]), lean_scene.calibration)
    one_each = [next(i for i in range(11) if data.chains[i] == chain) for chain in ("left", "right")]
    with pytest.raises(InputError, match="spot"):  # one spot per chain: nothing to hold out
        check_enough(model, data.subset(one_each), lean_scene.calibration)


def test_real_data_beats_before_and_the_published_toolbox(scene, real_data):
    train = read_measurements(real_data / "left_train.csv", scene).contacts.concat(
        read_measurements(real_data / "right_train.csv", scene).contacts
    )
    held_out = read_measurements(real_data / "left_validation.csv", scene).contacts
    settings = Settings(candidates=("offsets_hip_pitch",), prior_scale=10.0, fold_seeds=1)  # the model chosen
    calibration = calibrate(scene, train, ["left_train", "right_train", "left_validation"], settings)
    residuals = held_out_residuals(calibration, held_out)
    for protocol in ("training_plane", "refitted_plane"):
        before = np.mean(np.abs(residuals[protocol]["before"]), axis=0) * TO_DISPLAY
        after = np.mean(np.abs(residuals[protocol]["after"]), axis=0) * TO_DISPLAY
        assert np.all(after < before), (protocol, before, after)
    after = np.mean(np.abs(residuals["training_plane"]["after"]), axis=0) * TO_DISPLAY
    assert np.all(after <= [4.86, 0.44, 0.50])  # the authors' public toolbox on the same data
