"""The calibrated URDF: same names, loads in pinocchio, reproduces the model for every chain layout.

Layouts: the shipped robots (TALOS's gripper three fixed joints below the wrist, iCub's and
Romeo's hands the links of their wrist joints with declared contact frames) and TALOS
changed to have each other kind (a gripper that is a moving joint's link, fixed joints
pinocchio merges into a joint's placement, a sole two fixed joints below the ankle, a
gripper in the middle of a fixed chain, a tool link beside the fingertips, config-declared
soles and grippers, on a moving joint's link or with the fingertips not below them, flush
and point contacts on one chain). Parameters are random (mm, sub-degree): no calibration runs.
"""

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from posegen.calibrate import (
    Perturbation,
    Settings,
    calibrate,
    calibrated_config,
    calibrated_urdf,
    check_exportable,
    simulate,
    write_calibration,
)
from posegen.errors import ConfigError
from posegen.io import dump_yaml, write_yaml
from posegen.model import CalibrationModel, ContactModel, Contacts, Kind, placement_matrix
from posegen.robot import FLUSH, POINT, Scene, contact_placement, load_config, parse_config, with_declared_frames
from tests.conftest import ROOT, point_config_data


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


def test_the_deliverable_is_what_calibrated_urdf_and_calibrated_config_build(scene, calibrated):
    # the folder's URDF and config come from one export: the same bytes as the two public functions give
    calibration, _, out = calibrated
    deliverable = calibration.deliverables.urdf
    assert not deliverable.nominal
    model = calibration.model
    theta = model.theta(deliverable.estimate.x)
    urdf = calibrated_urdf(scene.files.urdf.read_text(), model.contact, theta)
    assert (out / "calibrated.urdf").read_text() == urdf
    config = calibrated_config(model.contact, theta, out / "calibrated.urdf")
    assert (out / "calibrated.yaml").read_text() == dump_yaml(config)


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


# --- every chain layout: the reloaded file reproduces the model at random parameters -------------------------

CONFIGS = ROOT / "configs"
SHIPPED = ("talos_table", "talos_full_table", "romeo_table", "icub_table")
PLANE = "table"


def _talos_data() -> dict:
    return yaml.safe_load((CONFIGS / "talos_table.yaml").read_text())


def _edited_talos(data: dict, folder: Path, edit) -> dict:
    """The config ``data`` on a copy of TALOS's URDF changed by ``edit(root)``."""
    files = Scene(load_config(CONFIGS / "talos_table.yaml")).files
    root = ET.parse(files.urdf).getroot()
    edit(root)
    urdf = folder / "talos_edited.urdf"
    ET.ElementTree(root).write(urdf)
    data["robot"]["source"] = {"urdf": str(urdf), "srdf": str(files.srdf), "package_dirs": list(files.package_dirs)}
    return data


def _add_fixed(root: ET.Element, name: str, parent: str, child: str, xyz: str, rpy: str) -> None:
    joint = ET.SubElement(root, "joint", name=name, type="fixed")
    ET.SubElement(joint, "parent", link=parent)
    ET.SubElement(joint, "child", link=child)
    ET.SubElement(joint, "origin", xyz=xyz, rpy=rpy)


def _joint(root: ET.Element, name: str) -> ET.Element:
    return next(j for j in root.findall("joint") if j.get("name") == name)


def _fixed_chains(root: ET.Element) -> None:
    """arm_left_4_joint hangs from two fixed links below arm_left_3_link (pinocchio merges them into
    its placement); a pad two fixed joints below the left ankle; a tool link beside the left fingers."""
    for name in ("arm_left_3_extra_a", "arm_left_3_extra_b", "left_sole_pad", "gripper_left_tool"):
        ET.SubElement(root, "link", name=name)
    _add_fixed(
        root, "arm_left_3_extra_a_joint", "arm_left_3_link", "arm_left_3_extra_a", "0.01 -0.02 -0.1", "0.1 -0.2 0.3"
    )
    _add_fixed(
        root, "arm_left_3_extra_b_joint", "arm_left_3_extra_a", "arm_left_3_extra_b", "0 0.01 -0.05", "-0.1 0 0.2"
    )
    _joint(root, "arm_left_4_joint").find("parent").set("link", "arm_left_3_extra_b")
    _add_fixed(root, "left_sole_pad_joint", "left_sole_link", "left_sole_pad", "0.005 0 -0.002", "0 0.01 0")
    _add_fixed(root, "gripper_left_tool_joint", "gripper_left_base_link", "gripper_left_tool", "0 0 -0.12", "0.1 0 0")


def layout_config(name: str, folder: Path) -> dict:
    """A config per layout: shipped, or TALOS changed to have it."""
    if name in SHIPPED:
        return yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())
    data = _talos_data()
    chains = data["chains"]
    if name == "gripper_under_revolute":  # the arm's last link, fingers below it through fixed joints
        chains["left"]["gripper_frame"] = "arm_left_7_link"
        chains["right"]["gripper_frame"] = "arm_right_7_link"
    elif name == "fixed_chains_and_merged":
        data = _edited_talos(data, folder, _fixed_chains)
        data["chains"]["left"].update(sole_frame="left_sole_pad", gripper_frame="gripper_left_tool")
        data["stance"]["sole_frames"] = ["left_sole_pad", "right_sole_link"]
        data["chains"]["right"]["gripper_frame"] = "wrist_right_ft_tool_link"  # mid fixed chain, fingers below
    elif name == "declared_frames":
        data["robot"]["frames"] = {
            "left_foot_sole": {"parent": "leg_left_6_link", "xyz_m": [0.0, 0.0, -0.107]},  # the foot link moves
            "right_foot_sole": {"parent": "right_sole_link", "xyz_m": [0.002, -0.001, 0.0], "rpy_deg": [0, 0, 5]},
            # the fingertips are not below it: the gripper's fixed joint above both carries it
            "left_palm": {"parent": "gripper_left_base_link", "xyz_m": [0.0, 0.0, -0.1], "rpy_deg": [10, 0, 0]},
            # only the arm's last link (a moving joint's child) is above it and the fingertips: a mount
            "right_palm": {"parent": "arm_right_7_link", "xyz_m": [0.0, 0.0, -0.2], "rpy_deg": [0, -5, 0]},
        }
        data["stance"]["sole_frames"] = ["left_foot_sole", "right_foot_sole"]
        for side in ("left", "right"):
            chains[side]["sole_frame"] = f"{side}_foot_sole"
            chains[side]["gripper_frame"] = f"{side}_palm"
    elif name == "point_and_flush":  # both contact kinds: the flush fold and the point's own offsets
        data = point_config_data()
    else:
        raise AssertionError(name)
    return data


LAYOUTS = (*SHIPPED, "gripper_under_revolute", "fixed_chains_and_merged", "declared_frames", "point_and_flush")


def random_theta(model: ContactModel, rng: np.random.Generator) -> np.ndarray:
    """Every parameter off: mm for lengths, sub-degree for angles."""
    angle = {"phix", "phiy", "phiz", "roll", "pitch"}
    sigma = np.array([np.deg2rad(0.5) if p.field in angle else 0.003 for p in model.parameters])
    return model.nominal() + rng.normal(0.0, sigma)


@dataclass(frozen=True)
class Exported:
    scene: Scene
    model: ContactModel
    theta: np.ndarray
    folder: Path


@pytest.fixture(scope="module", params=LAYOUTS)
def exported(request, tmp_path_factory) -> Exported:
    folder = tmp_path_factory.mktemp(request.param)
    scene = Scene(parse_config(layout_config(request.param, folder)))
    chains = [c.name for c in scene.chains]
    kinds = {c.name: (FLUSH, POINT) if c.point_frame else (c.contact_kind,) for c in scene.chains}
    model = ContactModel(scene, chains, [PLANE], kinds)
    theta = random_theta(model, np.random.default_rng(len(request.param)))
    (folder / "calibrated.urdf").write_text(calibrated_urdf(scene.files.urdf.read_text(), model, theta))
    write_yaml(folder / "calibrated.yaml", calibrated_config(model, theta, folder / "calibrated.urdf"))
    return Exported(scene, model, theta, folder)


def random_contacts(exported: Exported, n: int = 24) -> Contacts:
    scene = exported.scene
    rng = np.random.default_rng(5)
    joints = rng.uniform(scene.lower, scene.upper, size=(n, len(scene.joint_names)))
    joints[:, scene.locked] = scene.locked_values[scene.locked]
    pairs = [(c, k) for c, kinds in exported.model.kinds.items() for k in kinds]
    chains, kinds = zip(*(pairs[i % len(pairs)] for i in range(n)), strict=True)
    return Contacts(joints, chains, (PLANE,) * n, tuple(str(i) for i in range(n)), kinds)


def test_the_reloaded_calibration_predicts_the_models_contacts(exported):
    """The calibrated scene config (on calibrated.urdf) at its nominal values: the model's residuals at theta."""
    contacts = random_contacts(exported)
    model = exported.model
    scene2 = Scene(load_config(exported.folder / "calibrated.yaml"))
    model2 = ContactModel(scene2, list(model.chains), [PLANE], model.kinds)
    theta2 = model2.nominal()
    theta2[model2.plane_columns(PLANE)] = exported.theta[model.plane_columns(PLANE)]
    expected = model.residuals(exported.theta, contacts)
    assert np.abs(expected - model.residuals(model.nominal(), contacts)).max() > 1e-4  # the deviations show
    assert model2.residuals(theta2, contacts) == pytest.approx(expected, abs=1e-9)


def test_pinocchio_alone_finds_the_calibrated_frames(exported):
    """The file, and the config's frames where the stack defines its own: sole -> contact or point, random joints."""
    scene, model, theta = exported.scene, exported.model, exported.theta
    text = (exported.folder / "calibrated.urdf").read_text()
    frames = load_config(exported.folder / "calibrated.yaml").frames
    if frames:
        text = with_declared_frames(text, pin.buildModelFromXML(text, pin.JointModelFreeFlyer()), frames)
    urdf = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    data = urdf.createData()
    contacts = random_contacts(exported, n=4)
    for name, chain in model.chains.items():
        cfg = scene.chain(name)
        placements = {e.name: theta[model.placement_columns(e.name)] for e in chain.elements}
        for kind in model.kinds[name]:
            expected = chain.sole_to_contact(contacts.joints, placements, theta[model.tip_columns(name, kind)], kind)
            for i, joints in enumerate(contacts.joints):
                q = pin.neutral(urdf)
                for joint, value in zip(scene.joint_names, joints, strict=True):
                    q[urdf.joints[urdf.getJointId(joint)].idx_q] = value
                pin.framesForwardKinematics(urdf, data, q)
                sole = data.oMf[urdf.getFrameId(cfg.sole_frame)]
                if kind == POINT:
                    tip = data.oMf[urdf.getFrameId(cfg.point_frame)]
                else:
                    tip = data.oMf[urdf.getFrameId(cfg.gripper_frame)] * contact_placement(urdf, cfg, q)
                assert sole.actInv(tip).homogeneous == pytest.approx(expected[i], abs=1e-9)


def test_the_file_keeps_every_link_and_joint_and_the_config_its_frames(exported):
    """Only mounts are added; the config's frames stay in the config, unchanged but the point frames."""
    scene = exported.scene
    original = ET.parse(scene.files.urdf).getroot()
    new = ET.parse(exported.folder / "calibrated.urdf").getroot()
    joints = {j.get("name"): j for j in new.findall("joint")}
    mounts = {
        n
        for n in (e.get("name") for e in new.findall("link"))
        if n not in {e.get("name") for e in original.findall("link")}
    }
    assert all(m.endswith("_mount") for m in mounts)
    for joint in original.findall("joint"):
        twin = joints.pop(joint.get("name"))
        assert twin.get("type") == joint.get("type")
        assert twin.find("parent").get("link") == joint.find("parent").get("link")
        child = joint.find("child").get("link")
        assert twin.find("child").get("link") in (child, f"{child}_mount")
    assert set(joints) == {f"{m.removesuffix('_mount')}_calibration_joint" for m in mounts}
    ends = {f for c in scene.chains for f in (c.sole_frame, c.gripper_frame)}
    parents = {f.name: f.parent for f in scene.config.frames}
    for mount in mounts:  # under a moving joint, moving the link of a sole or gripper (or the one it hangs from)
        link = mount.removesuffix("_mount")
        assert joints[f"{link}_calibration_joint"].find("child").get("link") == link
        assert link in ends | {parents[f] for f in ends if f in parents}
    points = {c.point_frame for c in scene.chains if POINT in exported.model.kinds[c.name]}
    frames = {f.name: f for f in load_config(exported.folder / "calibrated.yaml").frames}
    assert set(frames) == {f.name for f in scene.config.frames}
    for frame in scene.config.frames:
        assert (frames[frame.name] == frame) == (frame.name not in points)


def test_icub_hands_keep_their_revolute_joints_and_get_a_mount(tmp_path):
    """The wrist's origin is the wrist's placement; the hand's placement goes to a fixed joint below it."""
    scene = Scene(load_config(CONFIGS / "icub_table.yaml"))
    model = ContactModel(scene, [c.name for c in scene.chains], [PLANE])
    theta = random_theta(model, np.random.default_rng(1))
    root = ET.fromstring(calibrated_urdf(scene.files.urdf.read_text(), model, theta))
    for chain in model.chains.values():
        hand = chain.elements[-1].name
        wrist = chain.elements[-2].name
        joints = {j.get("name"): j for j in root.findall("joint")}
        assert joints[wrist].get("type") == "revolute" and joints[wrist].find("child").get("link") == f"{hand}_mount"
        mount = joints[f"{hand}_calibration_joint"]
        assert mount.get("type") == "fixed" and mount.find("child").get("link") == hand
        origin = placement_matrix(theta[model.placement_columns(wrist)])
        xyz = [float(v) for v in joints[wrist].find("origin").get("xyz").split()]
        assert xyz == pytest.approx(origin[:3, 3], abs=1e-12)  # the wrist's parent link is its joint frame


@pytest.mark.parametrize("config", SHIPPED)
def test_every_shipped_config_is_exportable(config):
    scene = Scene(load_config(CONFIGS / f"{config}.yaml"))
    check_exportable(ContactModel(scene, [c.name for c in scene.chains], [PLANE]))


def test_a_frame_no_urdf_origin_places_is_refused_before_any_work():
    data = point_config_data()
    data["chains"]["left"].update(gripper_frame="arm_left_7_joint", fingertip_frames=[])  # a moving joint's frame
    scene = Scene(parse_config(data))
    with pytest.raises(ConfigError, match=r"chains\.left\.gripper_frame: 'arm_left_7_joint' is neither a link"):
        check_exportable(ContactModel(scene, ["left"], [PLANE]))


def test_a_point_frame_that_is_also_a_fingertip_is_refused_not_written_wrong():
    """Moving the point would move the flush contact frame: the reloaded file shows it, the export says so."""
    data = point_config_data()
    data["chains"]["left"]["point_frame"] = "gripper_left_fingertip_3_link"
    scene = Scene(parse_config(data))
    model = ContactModel(scene, ["left"], [PLANE], {"left": (FLUSH, POINT)})
    with pytest.raises(ConfigError, match="contact frame of chain 'left'"):
        check_exportable(model)
