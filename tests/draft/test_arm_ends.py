"""The joints ``robot init`` drops from an arm's end: too narrow to plan, or a part the hand's tip does not follow."""

import numpy as np
import pinocchio as pin
import pytest

from posegen.draft import write_draft
from posegen.draft.arm_ends import without_idle_ends, without_narrow_ends
from posegen.draft.body import LIGHT_FRACTION, Tree, study_body
from posegen.draft.source import load_draft_source
from posegen.pool import generate_pool
from posegen.robot import Scene, leaves_no_room, load_config
from tests.conftest import CONFIG
from tests.draft.humanoid_urdf import humanoid_urdf


def test_an_arm_end_is_locked_exactly_when_the_scene_would_refuse_it_free():
    """The draft's rule is the scene's (``leaves_no_room``): a range of exactly twice the margin is dropped too."""
    margin = 0.02
    ranges = (1.0, 1.0, 1.0, 1.0, 0.0401, 0.04)  # the last: exactly twice the margin; the one before: just over
    joints = "".join(
        f'<link name="l{i + 1}"/><joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<axis xyz="0 1 0"/><limit lower="0" upper="{r}" effort="1" velocity="1"/></joint>'
        for i, r in enumerate(ranges)
    )
    model = pin.buildModelFromXML(f'<robot name="r"><link name="l0"/>{joints}</robot>', pin.JointModelFreeFlyer())
    arm = list(range(2, model.njoints))
    kept, check = without_narrow_ends(model, arm, margin)
    assert [str(model.names[j]) for j in kept] == ["j0", "j1", "j2", "j3", "j4"]
    assert check.startswith("'j5' ended an arm") and "the hand is the link of 'j4'" in check
    assert bool(leaves_no_room(0.0, ranges[-1], margin)) and not leaves_no_room(0.0, ranges[-2], margin)


@pytest.fixture(scope="module")
def talos_draft(tmp_path_factory):
    """The default robot drafted from its reduced URDF, whose grippers' fingers are fixed to the last arm link."""
    path = tmp_path_factory.mktemp("draft") / "talos.yaml"
    return write_draft("talos", str(path), samples=40), path


def test_a_gripper_motor_under_fixed_fingers_is_locked_and_the_fingertips_make_the_face(talos_draft):
    """The reduced model's ``gripper_*_joint`` moves one 0.17 kg link; the fingertips hang from ``arm_*_7_link``.

    Kept, it was taken for the hand: a point contact at its tip, which the fingertips
    reach 4 cm beyond, so that every projected sample pressed them into the table.
    """
    draft, _ = talos_draft
    shipped = load_config(CONFIG)
    assert [c.hand for c in draft.chains] == ["arm_left_7_link", "arm_right_7_link"]
    assert [c.joints[-1] for c in draft.chains] == ["arm_left_7_joint", "arm_right_7_joint"]
    assert {"gripper_left_joint", "gripper_right_joint"} <= set(draft.locked)
    assert set(shipped.locked_joints) <= set(draft.locked)
    assert all(c.contact.flush and len(c.contact.frames) == 3 for c in draft.chains)
    assert sum("a gripper's motor between fixed fingers" in c for c in draft.checks) == 2


def test_a_pool_of_the_draft_touches_the_table_with_the_three_fingertips(talos_draft):
    """At each pooled posture the three fingertips' meshes (read with pinocchio from the URDF) touch the table.

    Before, the drafted point contact on the motor link left every converged sample with a
    fingertip in the table: no posture was found in 256 samples.
    """
    _, path = talos_draft
    config = load_config(path)
    scene = Scene(config)
    pool = generate_pool(config, 6, seed=0)
    model = scene.model
    geom = pin.buildGeomFromUrdf(
        model, str(scene.files.urdf), pin.COLLISION, package_dirs=list(scene.files.package_dirs)
    )
    normal, top = scene.table_pose[:3, 2], scene.table_pose[:3, 3]
    data, gdata = model.createData(), geom.createData()
    for posture in pool.postures:
        pin.updateGeometryPlacements(model, data, geom, gdata, scene.configuration(np.array(posture.joints)))
        lowest = {}
        for k, obj in enumerate(geom.geometryObjects):
            name = str(model.frames[obj.parentFrame].name)
            if name.startswith(f"gripper_{posture.chain}_fingertip"):
                points = np.asarray(obj.geometry.vertices()) @ gdata.oMg[k].rotation.T + gdata.oMg[k].translation
                lowest[name] = float(((points - top) @ normal).min())  # m above the table top
        assert len(lowest) == 3 and all(abs(h) < 2e-3 for h in lowest.values()), lowest


def test_a_light_hand_reaching_beyond_its_wrist_stays_in_the_arm(tmp_path):
    """The synthetic humanoid's hand (a box beyond the last joint, light) is what the tip follows: no joint dropped."""
    src = load_draft_source(str(humanoid_urdf(tmp_path, "z")), None, ())
    model, tree = src.model, Tree.of(src.model)
    body = study_body(src)
    data = model.createData()
    pin.framesForwardKinematics(model, data, body.reference)
    light_kg = LIGHT_FRACTION * tree.mass(list(range(1, model.njoints)))
    hand = body.arms[0][-1]
    assert tree.mass(tree.subtree(hand)) < light_kg  # light: the geometry alone decides
    for arm in body.arms:
        assert without_idle_ends(model, data, body.geometry, arm, tree.subtree, light_kg) == (arm, "")
    heavy = without_idle_ends(model, data, body.geometry, body.arms[0], tree.subtree, 0.0)
    assert heavy == (body.arms[0], "")  # nothing is lighter than 0 kg
