"""``posegen robot init``: a starting config found from the description alone."""

import numpy as np
import pytest

from posegen.robot import Scene, load_config, write_draft
from posegen.robot.additions import Capsule
from posegen.robot.draft import draft_robot
from tests.conftest import CONFIG, ROOT


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
