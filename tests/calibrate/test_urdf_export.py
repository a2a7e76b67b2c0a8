"""The calibrated URDF: same names, loads in pinocchio, reproduces the calibrated residuals."""

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

from posegen.calibrate import Perturbation, Settings, calibrate, simulate, write_calibration
from posegen.model import ContactModel, Contacts, Group
from posegen.robot import Scene, load_config


@pytest.fixture(scope="module")
def calibrated(scene, example_pool, tmp_path_factory):
    rows = list(range(90))
    plan = Contacts(
        example_pool.joints()[rows], tuple(example_pool.postures[i].chain for i in rows), ("sim",) * 90, ("",) * 90
    )
    recorded, _, _ = simulate(scene, plan, Perturbation(encoder_noise_rad=np.deg2rad(0.005)), seed=9)
    calibration = calibrate(scene, recorded, ["sim"], Settings(kappa=5.0))
    out = tmp_path_factory.mktemp("cal")
    write_calibration(calibration, None, out, seed=9)
    return calibration, recorded, out


def test_same_links_and_joints(scene, calibrated):
    _, _, out = calibrated
    original = ET.parse(scene.files.urdf).getroot()
    new = ET.parse(out / "calibrated.urdf").getroot()
    assert [e.get("name") for e in original.iter("link")] == [e.get("name") for e in new.iter("link")]
    assert [e.get("name") for e in original.iter("joint")] == [e.get("name") for e in new.iter("joint")]
    model = pin.buildModelFromUrdf(str(out / "calibrated.urdf"), pin.JointModelFreeFlyer())
    assert model.nq == scene.model.nq


def test_calibrated_urdf_reproduces_the_calibrated_residuals(calibrated):
    calibration, recorded, out = calibrated
    scene2 = Scene(load_config(out / "calibrated.yaml"))
    model2 = ContactModel(scene2, sorted(calibration.model.chains), ["sim"])
    theta = model2.nominal()  # the calibrated URDF's own values, zero contact offsets
    for i in model2.columns(Group.PLANE):
        theta[i] = calibration.after.theta[calibration.model.index[model2.parameters[i].name]]
    expected = calibration.model.residuals(calibration.after.theta, recorded)
    assert model2.residuals(theta, recorded) == pytest.approx(expected, abs=1e-9)


def test_report_and_plots_are_written(calibrated):
    _, _, out = calibrated
    for name in ("calibration.yaml", "calibrated.urdf", "calibrated.yaml", "parameters.png", "residuals.png"):
        assert (out / name).stat().st_size > 0
    assert (out / "parameters.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
