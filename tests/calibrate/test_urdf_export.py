"""The calibrated URDF: same names, loads in pinocchio, reproduces the calibrated residuals."""

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

from posegen.calibrate import Perturbation, Settings, calibrate, simulate, write_calibration
from posegen.model import CalibrationModel, Contacts, Kind
from posegen.robot import Scene, load_config


@pytest.fixture(scope="module")
def calibrated(lean_scene, example_pool, tmp_path_factory):
    rows = list(range(40))
    plan = Contacts(
        example_pool.joints()[rows],
        tuple(example_pool.postures[i].chain for i in rows),
        ("sim",) * 40,
        tuple(f"sim.yaml:{i}:c{i}" for i in rows),
    )
    perturbation = Perturbation(encoder_noise_rad=np.deg2rad(0.005), compliance_rad_per_nm=3e-4)
    recorded, _, _ = simulate(lean_scene, plan, perturbation, seed=9)
    calibration = calibrate(lean_scene, recorded, ["sim"], Settings(prior_scale=3.0, fold_seeds=1))
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
    """The URDF's own values, zero contact offsets, the fitted planes and compliance: the same residuals.

    The gravity torques are the calibration's (the nominal URDF's inertias): compliance is not a URDF quantity.
    """
    calibration, recorded, out = calibrated
    scene2 = Scene(load_config(out / "calibrated.yaml"))
    model = calibration.model
    model2 = CalibrationModel(scene2, sorted(model.contact.chains), ["sim"], scene2.calibration.compliance)
    x2 = model2.nominal()
    for kinds in ([Kind.PLANE], [Kind.COMPLIANCE]):
        x2[model2.columns(kinds)] = calibration.deliverables.urdf.estimate.x[model.columns(kinds)]
    observations = model.observations(recorded)
    expected = model.evaluate(calibration.deliverables.urdf.estimate.x, observations, floor=False).contact
    assert model2.evaluate(x2, observations, floor=False).contact == pytest.approx(expected, abs=1e-9)


def test_report_and_plots_are_written(calibrated):
    _, _, out = calibrated
    names = ("calibration.yaml", "calibrated.urdf", "calibrated.yaml", "parameters.png", "residuals.png")
    for name in (*names, "cross_validation.png"):
        assert (out / name).stat().st_size > 0
    assert (out / "parameters.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
