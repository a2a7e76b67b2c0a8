"""Calibration from point contacts (height only), alone and mixed with flush contacts of the same chain."""

import dataclasses

import numpy as np
import pytest

from posegen.calibrate import Noise, Perturbation, calibrate, estimate, held_out_residuals, simulate
from posegen.calibrate.calibration import check_enough
from posegen.calibrate.deliverable_files import judged_figures
from posegen.calibrate.estimation import held_at_urdf
from posegen.calibrate.file_judge import judge
from posegen.calibrate.scoring import column_stats, fold_loss
from posegen.calibrate.screening import chi_thresholds, row_dof
from posegen.calibrate.simulation import settle_true, true_parameters
from posegen.errors import InputError
from posegen.model import (
    DEFAULT_FLOOR_NOISE,
    DEFAULT_NOISE,
    CalibrationModel,
    ContactModel,
    Contacts,
    Kind,
    candidate_spec,
    level_postures,
    read_measurements,
    start_point,
    write_measurements,
)
from posegen.robot import FLUSH, POINT, CandidateConfig, PriorConfig, Scene

OFFSETS = CandidateConfig("offsets", ("*.joint_offset",))
FULL = CandidateConfig("full", ("*.*",))


def planned(scene, pool, chain, kind, session, n, seed):
    """``n`` standing contacts of one kind, the hand turned at random about its contact (settled, nominal robot)."""
    rows = [i for i, p in enumerate(pool.postures) if p.chain == chain][:20]
    m = len(rows)
    seeds = Contacts(pool.joints()[rows], (chain,) * m, (session,) * m, ("",) * m, (kind,) * m)
    made = level_postures(ContactModel(scene, [chain], [session], {chain: [kind]}), seeds, 3 * n, seed)
    inside = np.all((made.joints >= scene.lower) & (made.joints <= scene.upper), axis=1)  # settling ignores limits
    made = made.subset(np.flatnonzero(inside)[:n])
    assert len(made) == n
    labels = tuple(f"sim.yaml:{i}:{session}_{chain}_{i % 12}" for i in range(len(made)))
    return dataclasses.replace(made, labels=labels)


@pytest.fixture(scope="module")
def point_truth(point_scene, example_pool):
    """A TALOS with joint offset and contact point errors, touching with fingertips: 80 training, 30 held out."""
    contacts = planned(point_scene, example_pool, "left", POINT, "sim", 110, seed=4)
    model = CalibrationModel(point_scene, ["left"], ["sim"], {}, {"left": [POINT]})
    rng = np.random.default_rng(8)
    delta = np.zeros(model.size)
    for i, d in enumerate(model.directions):
        if d.kind == Kind.JOINT_OFFSET:
            delta[i] = np.deg2rad(0.3) * rng.normal()
        elif d.kind == Kind.CONTACT_POINT:
            delta[i] = 1.5e-3 * rng.normal()
    rigid = Perturbation(length_m=0.0, angle_rad=0.0)
    x = true_parameters(model, rigid, seed=8) + model.basis @ delta
    recorded, converged, _ = settle_true(model, x, contacts)
    recorded = recorded.subset(np.flatnonzero(converged))
    assert len(recorded) >= 100
    return model, x, recorded.subset(range(80)), recorded.subset(range(80, len(recorded)))


def test_a_simulated_point_contact_calibration_recovers_the_truth(point_truth):
    model, x, train, test = point_truth
    spec = candidate_spec(model, OFFSETS, PriorConfig(), 10.0)
    observations = model.observations(train)
    start = held_at_urdf(model, spec, start_point(model, observations))
    fitted = estimate(model, observations, spec, Noise(DEFAULT_NOISE, DEFAULT_FLOOR_NOISE), start)
    held_out = model.observations(test)
    before = model.evaluate(start, held_out, floor=False).contact[:, 0]
    after = model.evaluate(fitted.x, held_out, floor=False).contact[:, 0]
    assert np.abs(before).mean() > 1e-3 and np.abs(after).max() < 5e-5  # m: 1 mm and more, to 0.05 mm
    truth = model.evaluate(x, held_out, floor=False).contact[:, 0]
    assert np.abs(truth).max() < 1e-9  # the held-out contacts touch the true table: the truth predicts zero
    # no roll or pitch is measured: their noise keeps its value instead of collapsing onto zero residuals
    assert fitted.noise.contact[1:] == pytest.approx(DEFAULT_NOISE[1:])
    assert fitted.noise.contact[0] <= 1e-5  # noise-free heights: the noise floor


def test_rows_dof_and_equations_count_the_measured_rows(point_scene, point_truth):
    model, _, train, _ = point_truth
    observations = model.observations(train.subset(range(3)))
    assert list(row_dof(observations, floor=False)) == [1, 1, 1]
    assert list(row_dof(observations, floor=True)) == [7, 7, 7]
    flush_bound, point_bound = chi_thresholds(np.array([3.0, 1.0]), 0.01)
    assert point_bound < flush_bound
    three = dataclasses.replace(train.subset(range(3)), labels=("a:1:s1", "a:2:s2", "a:3:s3"))
    with pytest.raises(InputError, match="3 equations for the 3 plane parameters"):
        check_enough(model, three, point_scene.calibration)


@pytest.fixture(scope="module")
def mixed(point_scene, example_pool, tmp_path_factory):
    """One chain touching flush in session 'a' and with a fingertip in session 'b', through ``calibrate``."""
    scene = Scene(
        dataclasses.replace(
            point_scene.config,
            calibration=dataclasses.replace(
                point_scene.calibration, candidates=(FULL,), prior_scales=(5.0,), folds=3, fold_seeds=1
            ),
        )
    )
    plan = planned(scene, example_pool, "left", FLUSH, "a", 40, seed=5).concat(
        planned(scene, example_pool, "left", POINT, "b", 50, seed=6)
    )
    recorded, _, _ = simulate(scene, plan, Perturbation(encoder_noise_rad=np.deg2rad(0.002)), seed=9)
    path = tmp_path_factory.mktemp("mixed") / "mixed.yaml"
    write_measurements(path, scene, recorded, scene.provenance(9))
    read = read_measurements(path, scene).contacts
    train = read.subset([i for i in range(len(read)) if i % 5])
    test = read.subset([i for i in range(len(read)) if not i % 5])
    return scene, recorded, read, calibrate(scene, train, ["a", "b"]), test


def test_a_mixed_chain_calibrates_and_reports_what_each_kind_measures(mixed):
    _, recorded, read, calibration, test = mixed
    assert read.kinds == recorded.kinds and set(read.kinds) == {FLUSH, POINT}  # the file keeps each contact's kind
    names = {p.name for p in calibration.model.contact.parameters}
    assert {"left_contact.z", "left_tip.z"} <= names
    residuals = held_out_residuals(calibration, test)["training_plane"]
    points = np.array([k == POINT for k in test.kinds])
    for name in ("before", "after"):
        assert np.all(residuals[name][points, 1:] == 0.0)
    assert np.abs(residuals["after"][:, 0]).mean() < 0.2 * np.abs(residuals["before"][:, 0]).mean()
    scene = calibration.model.scene
    judged = judge(scene, calibration.train, calibration.kept, test.subset(np.flatnonzero(points)))
    only_points = judged_figures(judged.held_out, test.subset(np.flatnonzero(points)))["all"]["mean_abs"]
    assert only_points["roll_deg"] is None and only_points["z_mm"] is not None  # no roll measured, none reported
    assert calibration.after.noise.contact[1] < DEFAULT_NOISE[1]  # roll noise estimated from the flush rows


def test_a_contact_kind_the_chain_does_not_make_is_refused(scene, point_scene, mixed, tmp_path):
    _, recorded, _, _, _ = mixed
    path = tmp_path / "point.yaml"
    write_measurements(path, point_scene, recorded, {})
    with pytest.raises(InputError, match="makes no point contact"):
        read_measurements(path, scene)  # the default config declares no point frame


def test_cross_validation_scores_count_the_measured_rows():
    """Per measured row, times three: a flush-only score is unchanged, a point contact counts one row, not three."""
    flush = np.array([[1e-3, np.deg2rad(0.1), 0.0]])
    point = np.array([[1e-3, np.nan, np.nan]])
    assert fold_loss(flush) == pytest.approx((2.0, 3)) and fold_loss(point) == pytest.approx((1.0, 1))
    mean_abs, _ = column_stats(np.vstack([flush, point]))
    assert mean_abs[0] == pytest.approx(1e-3) and mean_abs[1] == pytest.approx(np.deg2rad(0.1))  # roll: flush row only
    assert np.isnan(column_stats(point)[1][1])  # no roll measured: none reported
