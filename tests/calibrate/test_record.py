"""The calibration folder read back: every contact's residuals and the posterior."""

import numpy as np
import pytest

from posegen.calibrate import ContactSet, held_out_residuals, read_calibration
from posegen.errors import InputError


@pytest.fixture(scope="module")
def record(calibration_folder):
    return read_calibration(calibration_folder.path)


def test_every_contact_is_read_back_with_its_residuals(calibration_folder, record):
    calibration, held_out = calibration_folder.calibration, calibration_folder.held_out
    train = calibration.train
    sets = [c.set for c in record.contacts]
    assert sets.count(ContactSet.HELD_OUT) == len(held_out)
    assert sets.count(ContactSet.TRAINING) + sets.count(ContactSet.OUTLIER) == len(train)
    assert sets.count(ContactSet.OUTLIER) == len(train) - len(calibration.kept)
    fitted = record.contacts[: len(train)]
    model = calibration.model
    before = model.evaluate(calibration.before.x, model.observations(train), floor=False).contact
    after = model.evaluate(calibration.after.x, model.observations(train), floor=False).contact
    assert np.allclose([c.before for c in fitted], before, rtol=1e-12, atol=1e-15)
    assert np.allclose([c.after for c in fitted], after, rtol=1e-12, atol=1e-15)
    assert np.array_equal([c.joints for c in fitted], train.joints)
    judged = held_out_residuals(calibration, held_out)["training_plane"]
    assert np.allclose([c.after for c in record.contacts[len(train) :]], judged["after"], rtol=1e-12, atol=1e-15)
    assert record.joint_names == calibration.model.scene.joint_names


def test_posterior_matches_the_identification(calibration_folder, record):
    calibration = calibration_folder.calibration
    posterior = record.posterior
    std = np.sqrt(np.diag(posterior.covariance))
    free = list(calibration.spec.free)
    assert np.allclose(std, calibration.after.std[free], rtol=1e-6)  # computed independently by estimate()
    assert posterior.names == tuple(calibration.model.directions[i].name for i in free)
    assert {p["name"] for p in record.report["parameters"]} <= set(posterior.names)  # planes are not reported
    rho = posterior.correlation
    assert np.allclose(rho, rho.T) and np.allclose(np.diag(rho), 1.0) and np.all(np.abs(rho) <= 1 + 1e-9)


def test_conditioning_figures(record):
    s = record.posterior.singular_values
    assert np.all(np.diff(s) <= 0) and s[-1] > 0
    assert record.posterior.condition == pytest.approx(s[0] / s[-1])
    assert record.posterior.condition_with_prior > 1.0


def test_a_folder_without_the_residual_table_is_refused(calibration_folder, tmp_path):
    for name in ("calibration.yaml", "posterior.npz", "calibrated.yaml"):
        (tmp_path / name).write_bytes((calibration_folder.path / name).read_bytes())
    with pytest.raises(InputError, match=r"no residuals\.csv"):
        read_calibration(tmp_path)


def test_a_malformed_residual_row_names_its_line(calibration_folder, tmp_path):
    for name in ("calibration.yaml", "posterior.npz", "calibrated.yaml", "residuals.csv"):
        (tmp_path / name).write_bytes((calibration_folder.path / name).read_bytes())
    lines = (tmp_path / "residuals.csv").read_text().splitlines()
    lines[3] = lines[3].rsplit(",", 1)[0]  # a field short
    (tmp_path / "residuals.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match="line 4"):
        read_calibration(tmp_path)
