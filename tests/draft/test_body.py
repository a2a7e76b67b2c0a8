"""The steps ``robot init`` finds a body in, each alone, on the synthetic humanoid (z up and y up)."""

import dataclasses
import itertools

import numpy as np
import pinocchio as pin
import pytest

from posegen.draft.body import (
    Tree,
    bend_reference,
    find_arms,
    find_legs,
    find_soles,
    fixed_base,
    orient,
    srdf_state,
    study_body,
)
from posegen.draft.geometry import load_geometry
from posegen.draft.limits import (
    JOINT_LIMIT_MARGIN_RAD,
    LIMIT_CLEARANCE_RAD,
    clear_of_limits,
    locked_joints,
    with_joints,
)
from posegen.draft.soles import sole_pose
from posegen.draft.source import load_draft_source
from posegen.draft.stance import reaching_branches, upper_branches
from posegen.errors import ConfigError
from tests.draft.humanoid_urdf import humanoid_urdf


@pytest.fixture(scope="module")
def sources(tmp_path_factory):
    """The synthetic humanoid, z up and y up, loaded as ``robot init`` loads it."""
    return {up: load_draft_source(str(humanoid_urdf(tmp_path_factory.mktemp(up), up)), None, ()) for up in "zy"}


@pytest.fixture(scope="module")
def standing(sources):
    """The z-up robot oriented, its kinematics at the neutral posture, its legs and soles."""
    src = sources["z"]
    model, tree = src.model, Tree.of(src.model)
    bearing = orient(model, pin.neutral(model), tree, src.label)
    q = pin.neutral(model)
    q[:7] = pin.SE3ToXYZQUAT(bearing.root)
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    roots = find_legs(model, data, tree, bearing.left, src.label)
    legs, checks = find_soles(model, data, load_geometry(model, src.text, ()), tree, roots, bearing.heading)
    return src, tree, bearing, q, data, legs, checks


def test_the_tree_holds_every_joint_once_and_the_whole_mass(sources):
    model = sources["z"].model
    tree = Tree.of(model)
    assert sorted(tree.subtree(1)) == list(range(1, model.njoints))
    for j, children in tree.children.items():
        assert all(model.parents[c] == j for c in children)
    assert tree.mass(tree.subtree(1)) == pytest.approx(sum(i.mass for i in model.inertias))


def test_srdf_state_takes_the_first_state_unless_it_breaks_the_limits(sources, tmp_path):
    src = sources["z"]
    assert srdf_state(src.model, src.files) == ("", pytest.approx(pin.neutral(src.model)), ())
    srdf = tmp_path / "robot.srdf"
    arms = '<joint name="l_shoulder_roll" value="0.5"/><joint name="r_shoulder_roll" value="-0.5"/>'  # 0: outside
    for knee, used in ((0.5, True), (3.0, False)):  # the knee's limits: [0, 2] rad
        srdf.write_text(
            '<robot name="synthetic"><group_state name="crouch" group="all">'
            f'<joint name="l_knee" value="{knee}"/>{arms}</group_state></robot>'
        )
        model = src.model.copy()
        state, q, checks = srdf_state(model, dataclasses.replace(src.files, srdf=srdf))
        knee_q = q[model.joints[model.getJointId("l_knee")].idx_q]
        if used:
            assert (state, knee_q, checks) == ("crouch", 0.5, ())
        else:
            assert (state, knee_q) == ("", 0.0) and len(checks) == 1 and "'crouch' puts l_knee outside" in checks[0]


def test_orient_turns_the_models_up_axis_up(sources):
    for up, src in sources.items():
        bearing = orient(src.model, pin.neutral(src.model), Tree.of(src.model), src.label)
        assert bearing.up == f"+{up}"
        model_up = np.eye(3)["xyz".index(up)]
        assert bearing.root.rotation @ model_up == pytest.approx([0, 0, 1], abs=1e-12)
        assert bearing.forward == pytest.approx(bearing.root.rotation[:, 0], abs=1e-12)  # the root's x, level
        assert bearing.left == pytest.approx(np.cross([0, 0, 1], bearing.forward))
        assert bearing.heading.rotation[:, 0] == pytest.approx(bearing.forward)


def test_legs_and_soles_are_found_left_first_down_to_the_feet(standing):
    src, _, bearing, _, data, legs, checks = standing
    model = src.model
    assert [str(model.names[j]) for j in legs.roots] == ["l_hip_yaw", "r_hip_yaw"]
    assert [str(model.names[j]) for j in legs.feet] == ["l_ankle_roll", "r_ankle_roll"]
    for path in legs.paths:
        assert len(path) == 6 and all(model.parents[b] == a for a, b in itertools.pairwise(path))
    assert legs.length_m == pytest.approx(0.8)  # hip to ankle: 0.4 + 0.4 m
    for sole in legs.soles:
        pose = sole_pose(model, data, sole)
        assert pose.rotation[:, 2] == pytest.approx([0, 0, 1], abs=1e-9)
        assert pose.translation[2] == pytest.approx(data.oMi[sole.foot_joint].translation[2] - 0.08, abs=1e-6)
    assert [s.declared.parent for s in legs.soles] == ["l_foot", "r_foot"]
    assert len(checks) == 2 and all("declared under the ankle" in c for c in checks)
    assert float(data.oMi[legs.roots[0]].translation @ bearing.left) > 0


def test_bend_reference_bends_the_knees_with_the_soles_flat_where_they_stood(standing):
    src, _, bearing, q, data, legs, _ = standing
    model = src.model
    bent, joints, margin, checks = bend_reference(model, q, legs, bearing.forward)
    assert margin == JOINT_LIMIT_MARGIN_RAD and len(checks) == 1 and checks[0].startswith("no SRDF posture")
    assert q[7:] == pytest.approx(0.0)  # the caller's posture untouched
    after = model.createData()
    pin.framesForwardKinematics(model, after, bent)
    heights = [sole_pose(model, after, s).translation[2] - sole_pose(model, data, s).translation[2] for s in legs.soles]
    assert heights[0] == pytest.approx(heights[1], abs=1e-6) and heights[0] > 0  # the pelvis lowered
    for sole in legs.soles:
        assert sole_pose(model, after, sole).rotation[:, 2] == pytest.approx([0, 0, 1], abs=1e-6)
    feet = np.mean([sole_pose(model, after, s).translation[:2] for s in legs.soles], axis=0)
    assert pin.centerOfMass(model, after, bent)[:2] == pytest.approx(feet, abs=2e-3)
    assert joints["l_knee"] > 0.2 and joints["r_knee"] > 0.2
    for name, value in joints.items():
        assert bent[model.joints[model.getJointId(name)].idx_q] == pytest.approx(value, abs=5e-5)


def test_find_arms_takes_the_two_longest_chains_left_first(standing):
    src, tree, bearing, _, data, legs, _ = standing
    model = src.model
    arms = find_arms(model, data, tree, legs.roots, bearing.left, src.label)
    assert [str(model.names[a[-1]]) for a in arms] == ["l_wrist", "r_wrist"]
    assert [str(model.names[a[0]]) for a in arms] == ["waist", "waist"]  # from the root's branch: the torso shared
    for arm in arms:
        assert all(model.parents[b] == a for a, b in itertools.pairwise(arm))
        assert "neck" not in {str(model.names[j]) for j in arm}


def test_locked_joints_and_clearance_from_the_limits(standing):
    src, tree, bearing, q, data, legs, _ = standing
    model = src.model
    arms = find_arms(model, data, tree, legs.roots, bearing.left, src.label)
    kept = legs.joints | {j for arm in arms for j in arm}
    assert locked_joints(model, q, kept) == {"neck": 0.0}
    elbow = model.getJointId("l_elbow")  # limits [-2, 0]: 0 is at the upper one
    assert clear_of_limits(model, q, [elbow]) == {"l_elbow": pytest.approx(-LIMIT_CLEARANCE_RAD)}
    moved = with_joints(model, q, {"l_elbow": -1.0})
    assert clear_of_limits(model, moved, [elbow]) == {} and moved is not q and q[model.joints[elbow].idx_q] == 0.0
    past = with_joints(model, q, {"neck": 3.0})  # outside [-1, 1]: locked at the limit
    assert locked_joints(model, past, kept) == {"neck": 1.0}


def test_study_body_gives_a_reference_with_its_locks_and_the_joints_it_set(sources):
    for src in sources.values():
        body = study_body(src)
        model = src.model
        assert body.state == "" and set(body.locked) == {"neck"}
        for name, value in {**body.locked, **body.reference_joints}.items():
            assert body.reference[model.joints[model.getJointId(name)].idx_q] == pytest.approx(value, abs=5e-5)
        assert body.kept == set(range(2, model.njoints)) - {model.getJointId("neck")}
        assert body.checks[-1].startswith("no SRDF posture")
        assert pin.XYZQUATToSE3(body.reference[:7]).rotation == pytest.approx(body.bearing.root.rotation)


def test_a_body_pinned_to_world_is_stood_free_and_said(tmp_path):
    """A simulator's description (a fixed joint from ``world``) drafts as a free robot, with a CHECK line."""
    urdf = humanoid_urdf(tmp_path, "z")
    text = urdf.read_text()
    assert fixed_base(text) == ()  # a free description says nothing
    first = text.index("<link name=")
    root = text[first:].split('"')[1]
    pin_joint = (
        f'<link name="world"/><joint name="pin" type="fixed"><parent link="world"/><child link="{root}"/></joint>'
    )
    pinned = urdf.with_name("pinned.urdf")
    pinned.write_text(text[:first] + pin_joint + "\n" + text[first:])
    [line] = fixed_base(pinned.read_text())
    assert f"'{root}'" in line and "'world'" in line
    body = study_body(load_draft_source(str(pinned), None, ()))
    assert line in body.checks  # the draft carries it, and the body was still found and stood
    assert body.legs.joints and len(body.arms) == 2


@pytest.fixture(scope="module")
def waisted(tmp_path_factory):
    """The synthetic humanoid rooted at the torso, one then two waist joints down to the pelvis."""
    return {
        n: load_draft_source(str(humanoid_urdf(tmp_path_factory.mktemp(f"waist{n}"), "z", waist=n)), None, ())
        for n in (1, 2)
    }


def test_legs_below_a_waist_branch_from_the_pelvis(waisted):
    """A torso-rooted model: the legs are the pelvis's branches, the waist joints neither legs nor arms, and free."""
    for n, src in waisted.items():
        model = src.model
        assert model.frames[model.getFrameId("torso")].parentJoint == 1  # the root is the torso
        body = study_body(src)
        names = [str(model.names[j]) for j in body.waist]
        assert body.bearing.up == "+z" and names == ["waist", "waist_pitch"][:n]
        assert all(model.parents[j] == body.waist[-1] for j in body.legs.roots)  # they branch at the pelvis
        assert [str(model.names[j]) for j in body.legs.roots] == ["l_hip_yaw", "r_hip_yaw"]
        assert [str(model.names[j]) for j in body.legs.feet] == ["l_ankle_roll", "r_ankle_roll"]
        assert [len(path) for path in body.legs.paths] == [6, 6] and not set(body.waist) & body.legs.joints
        assert [str(model.names[a[0]]) for a in body.arms] == ["l_shoulder_pitch", "r_shoulder_pitch"]
        assert not set(body.waist) & {j for arm in body.arms for j in arm}
        assert set(body.waist) <= body.kept and set(body.locked) == {"neck"}
        assert body.kept == set(range(2, model.njoints)) - {model.getJointId("neck")}


def test_the_descent_follows_the_only_reaching_branch_and_the_arms_start_above_it(waisted):
    src = waisted[2]
    model, tree = src.model, Tree.of(src.model)
    hips = [model.getJointId("l_hip_yaw"), model.getJointId("r_hip_yaw")]
    lowest = {j: 1.0 for j in range(2, model.njoints)}  # only the legs reach the floor (0 m)
    lowest.update({j: 0.0 for hip in hips for j in tree.subtree(hip)})
    for j in (model.getJointId("waist"), model.getJointId("waist_pitch")):
        lowest[j] = 0.0
    assert reaching_branches(tree.children, lowest, 0.0) == sorted(hips)
    lowest[model.getJointId("neck")] = 0.0  # two branches of the root reach: no descent (today's rule)
    assert reaching_branches(tree.children, lowest, 0.0) == sorted([model.getJointId(n) for n in ("waist", "neck")])
    upper = {str(model.names[j]) for j in upper_branches(model, tree.children, hips)}
    assert upper == {"neck", "l_shoulder_pitch", "r_shoulder_pitch"}  # the torso's, off the waist


def test_a_model_without_legs_is_not_stood_on_its_arms_below_its_waist(tmp_path):
    """Pelvis, waist, torso, arms: the descent finds the arms reaching the floor upside down, and refuses them."""
    src = load_draft_source(str(humanoid_urdf(tmp_path, "z", legs=0)), None, ())
    with pytest.raises(ConfigError, match=r"no two legs: .*'waist'"):
        study_body(src)


@pytest.mark.parametrize("root", ["base_footprint", "world"])
def test_a_root_link_at_the_floor_leaves_the_body_as_it_was(root, sources, tmp_path):
    """A ``base_footprint`` (REP 120) or ``world`` root fixed 1.5 m below the pelvis: joint 1 lies below the feet.

    The floor is that of the root's branches (the root's own placement left out), as :func:`orient` takes it.
    """
    urdf = humanoid_urdf(tmp_path, "z")
    text = urdf.read_text()
    root_xml = (
        f'<link name="{root}"/><joint name="to_pelvis" type="fixed"><parent link="{root}"/>'
        '<child link="pelvis"/><origin xyz="0 0 1.5"/></joint>'
    )
    urdf.write_text(text.replace('<robot name="synthetic">', f'<robot name="synthetic">{root_xml}'))
    rooted, plain = study_body(load_draft_source(str(urdf), None, ())), study_body(sources["z"])
    names = [[str(rooted.tree.model.names[j]) for j in path] for path in rooted.legs.paths]
    assert names == [[str(plain.tree.model.names[j]) for j in path] for path in plain.legs.paths]
    assert [s.frame for s in rooted.legs.soles] == [s.frame for s in plain.legs.soles]
    assert [len(arm) for arm in rooted.arms] == [len(arm) for arm in plain.arms]
    assert rooted.reference_joints == plain.reference_joints
    assert any("pins 'pelvis' to 'world'" in c for c in rooted.checks) == (root == "world")
