"""The calibration folder read back: every contact's residuals and the posterior."""

import numpy as np
import pytest

from posegen.calibrate import ContactSet, judge, read_calibration
from posegen.errors import InputError
from posegen.robot import Scene, load_config


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
    # before: the nominal URDF, after: calibrated.urdf as written, each as a stack loading it sees it
    nominal = judge(calibration.model.scene, train, calibration.kept, held_out)
    urdf = judge(Scene(load_config(calibration_folder.path / "calibrated.yaml")), train, calibration.kept, held_out)
    for rows, judged in ((fitted, nominal.training), (record.contacts[len(train) :], nominal.held_out)):
        assert np.allclose([c.before for c in rows], judged, rtol=1e-9, atol=1e-12)
    for rows, judged in ((fitted, urdf.training), (record.contacts[len(train) :], urdf.held_out)):
        assert np.allclose([c.after for c in rows], judged, rtol=1e-9, atol=1e-12)
    assert np.array_equal([c.joints for c in fitted], train.joints)
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
