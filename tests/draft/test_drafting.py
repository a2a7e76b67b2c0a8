"""``posegen robot init``: a starting config found from the description alone."""

import numpy as np
import pinocchio as pin
import pytest

from posegen.draft import write_draft
from posegen.draft.body import study_body
from posegen.draft.covering import collision_additions
from posegen.draft.drafting import draft_robot, find_hands, table_for
from posegen.draft.geometry import Geometry, vertices
from posegen.draft.soles import floor_height
from posegen.draft.source import load_draft_source
from posegen.robot import Scene, load_config, yaw_rotation
from posegen.robot.additions import Box, Capsule, CollisionConfig
from posegen.robot.collision_geometry import robot_geometry
from tests.conftest import CONFIG, ROOT
from tests.draft.humanoid_urdf import humanoid_urdf


@pytest.fixture(scope="module")
def talos_full_draft(tmp_path_factory):
    path = tmp_path_factory.mktemp("draft") / "talos_full_table.yaml"
    return write_draft("talos_full", str(path), samples=40), path


def test_draft_finds_legs_arms_and_what_to_lock(talos_full_draft):
    draft, _ = talos_full_draft
    shipped = load_config(ROOT / "configs" / "talos_full_table.yaml")
    assert tuple(s.frame for s in draft.soles) == shipped.stance.sole_frames
    assert draft.up_axis == "+z" and draft.root_rpy_deg is None
    assert [c.joints[-1] for c in draft.chains] == ["arm_left_7_joint", "arm_right_7_joint"]
    assert all(len(c.joints) == 7 for c in draft.chains)
    assert set(draft.locked) == set(shipped.locked_joints)  # fingers and head, nothing else
    assert draft.contact_force_n is None  # its wrists hold posegen's 30 N press, as the shipped config's
    found = {frozenset((p.link_a, p.link_b)) for p in draft.survey.disabled}
    assert found == {frozenset((p.link_a, p.link_b)) for p in shipped.collision.disabled_pairs}


def test_draft_table_is_near_the_hand_made_one(talos_full_draft):
    draft, _ = talos_full_draft
    table = load_config(CONFIG).table
    assert np.linalg.norm(np.subtract(draft.table_center_m, table.top_center_m)) < 0.1


def test_written_draft_loads_as_a_scene(talos_full_draft):
    draft, path = talos_full_draft
    assert draft.notes[-1].startswith("the draft loads as a scene")
    scene = Scene(load_config(path))
    assert len(scene.chains) == 2 and scene.locked.sum() == len(draft.locked)


def test_draft_flags_implausible_limits_and_misplaced_meshes():
    draft = draft_robot("icub", samples=5)
    assert len(draft.velocity_limits) == 29 and set(draft.urdf_velocity.values()) == {100.0}
    assert {"l_upper_leg", "r_upper_leg"} <= set(draft.misplaced)  # thighs' meshes miss their CoM by ~0.1 m
    capsules = {s.link for s in draft.shapes if isinstance(s, Capsule)}
    assert set(draft.misplaced) <= capsules and capsules - set(draft.misplaced) <= set(draft.covered)


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    """The synthetic humanoid with and without meshes: its source, body and kinematics at the reference."""
    out = {}
    for meshes in (True, False):
        urdf = humanoid_urdf(tmp_path_factory.mktemp(f"meshes_{meshes}"), meshes=meshes)
        src = load_draft_source(str(urdf), None, ())
        body = study_body(src)
        data = src.model.createData()
        pin.framesForwardKinematics(src.model, data, body.reference)
        out[meshes] = (src, body, data)
    return out


def test_collision_additions_cover_every_moving_link_and_box_bare_feet(synthetic):
    for meshes, (src, body, data) in synthetic.items():
        added, checks = collision_additions(src.model, data, body, src.text)
        assert checks[0].startswith(f"{len(added.covered)} moving links have no collision geometry")
        assert {"l_thigh", "r_shank", "torso"} <= set(added.covered)
        assert ("l_foot" in added.covered) != meshes and ("l_hand" in added.covered) != meshes
        boxes = {s.link for s in added.shapes if isinstance(s, Box)}
        assert boxes == (set() if meshes else {"l_foot", "r_foot"})
        assert {s.link for s in added.shapes} == set(added.covered) | set(added.misplaced)


def test_find_hands_gives_each_arm_its_hand_without_the_torso(synthetic):
    src, body, data = synthetic[True]
    chains, checks = find_hands(src.model, data, body.geometry, body)
    assert [(c.name, c.hand, c.joints[-1]) for c in chains] == [
        ("left", "l_hand", "l_wrist"),
        ("right", "r_hand", "r_wrist"),
    ]
    assert not set(chains[0].joints) & set(chains[1].joints) and "waist" not in chains[0].joints
    assert all(c.contact.flush and c.gripper.parent == c.hand for c in chains)
    assert [c.sole for c in chains] == [s.frame for s in body.legs.soles]
    assert len(checks) == 2 and checks[0].startswith("left hand (l_hand): a flat face")


def test_table_for_puts_the_table_within_reach_and_clear_of_the_body(synthetic):
    src, body, data = synthetic[True]
    added, _ = collision_additions(src.model, data, body, src.text)  # the torso's capsule stands above the table's top
    shapes = CollisionConfig(shapes=added.shapes)
    geometry = Geometry(robot_geometry(src.model, src.text, (), shapes, convex=False), body.geometry.visual)
    chains, _ = find_hands(src.model, data, geometry, body)
    (top, size, spots_x, spots_y, yaw), reach = table_for(src.model, data, geometry, body, chains[0])
    assert 0.5 < reach < 0.6  # shoulder to wrist 0.5 m, then to the palm's face
    heading = body.bearing.heading
    assert np.allclose(heading.rotation, yaw_rotation(np.deg2rad(yaw)), atol=1e-6)  # the table's frame is the robot's
    shoulder = heading.actInv(data.oMi[src.model.getJointId("l_shoulder_pitch")].translation)
    centre = heading.actInv(np.array(top))  # its height is from the floor
    floor = floor_height(src.model, data, body.legs.soles)
    assert centre[0] > shoulder[0] and shoulder[2] - floor - 0.5 * reach > top[2] > 0.0
    points = vertices(src.model, data, geometry.collision, set(range(1, src.model.njoints)), heading)
    points[:, 2] -= floor
    beside = points[(points[:, 2] > top[2] - size[2]) & (np.abs(points[:, 1]) < size[1] / 2)]
    assert len(beside) and np.all(beside[:, 0] < centre[0] - size[0] / 2)  # the near edge in front of the body
    assert max(spots_x) <= size[0] / 2 and max(np.abs(spots_y)) <= size[1] / 2
