"""``posegen robot init`` on a URDF file: any up axis, relative meshes, no SRDF, missing geometry, bad input."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from posegen.cli.main import main
from posegen.draft import write_draft
from posegen.draft.drafting import draft_robot
from posegen.errors import ConfigError
from posegen.io import load_pool, write_pool
from posegen.robot import Scene, load_config
from posegen.robot.additions import Capsule, CollisionConfig, VisualHull
from posegen.robot.coverage import geometry_coverage
from posegen.robot.validation import check_for_planning
from tests.draft.humanoid_urdf import FOOT, humanoid_urdf


@pytest.fixture(scope="module")
def drafts(tmp_path_factory):
    """The same synthetic robot drafted z-up and y-up (written and loaded)."""
    out = {}
    for up in ("z", "y"):
        folder = tmp_path_factory.mktemp(f"robot_{up}")
        config = folder / "config.yaml"
        draft = write_draft(str(humanoid_urdf(folder / "description", up)), str(config), samples=20)
        out[up] = (draft, Scene(load_config(config)))
    return out


def test_the_draft_does_not_depend_on_the_model_up_axis(drafts):
    (z, z_scene), (y, y_scene) = drafts["z"], drafts["y"]
    assert (z.up_axis, z.root_rpy_deg) == ("+z", None)
    assert y.up_axis == "+y" and y.root_rpy_deg == (90.0, 0.0, 0.0)
    assert y.reference_joints == pytest.approx(z.reference_joints, abs=1e-4)
    assert (y.foot_x_m, y.foot_y_m, y.table_center_m) == (z.foot_x_m, z.foot_y_m, z.table_center_m)
    for scene in (z_scene, y_scene):  # each stands in its own scene the same way
        q = scene.configuration(scene.reference)
        data = scene.model.createData()
        pin.framesForwardKinematics(scene.model, data, q)
        for sole in scene.stance.sole_frames:
            assert data.oMf[scene.frame_id(sole)].rotation[:, 2] == pytest.approx([0, 0, 1], abs=1e-6)
            assert data.oMf[scene.frame_id(sole)].translation[2] == pytest.approx(0.0, abs=1e-6)
        assert scene.com_margin(q, data) >= scene.margins.com_m


def test_the_drafted_stance_is_found_from_the_geometry(drafts):
    draft, scene = drafts["z"]
    assert draft.notes[-1].startswith("the draft loads as a scene")
    check_for_planning(scene)
    half = FOOT[0] / 2  # the foot box is centred 0.03 m in front of the ankle
    assert draft.foot_x_m == pytest.approx((0.03 - half, 0.03 + half), abs=1e-3)
    assert draft.foot_y_m == pytest.approx((-FOOT[1] / 2, FOOT[1] / 2), abs=1e-3)
    assert draft.reference_joints["l_knee"] > 0.2 and draft.reference_joints["r_knee"] > 0.2  # bent
    assert [c.joints[-1] for c in draft.chains] == ["l_wrist", "r_wrist"] and set(draft.locked) == {"neck"}
    assert all(c.contact.flush for c in draft.chains)  # the palm boxes are flat
    assert {s.declared.parent for s in draft.soles if s.declared} == {"l_foot", "r_foot"}


def test_every_moving_link_gets_collision_geometry_and_the_check_says_so(drafts):
    draft, scene = drafts["z"]
    coverage = geometry_coverage(scene)
    assert coverage.bare_links == () and coverage.meshes == 4 and coverage.primitives > 0
    assert {s.link for s in draft.shapes if isinstance(s, Capsule)} == set(draft.covered)
    assert "l_thigh" in draft.covered and "l_hip_roll_link" not in draft.covered  # no extent: nothing to cover
    pairs = CollisionConfig(disabled_pairs=scene.config.collision.disabled_pairs)
    bare = Scene(dataclasses.replace(scene.config, collision=pairs))  # the URDF's geometry alone
    assert "l_thigh" in geometry_coverage(bare).bare_links and "l_foot" not in geometry_coverage(bare).bare_links


def test_a_visual_hull_replaces_missing_collision_geometry():
    draft = draft_robot("human", samples=5)
    hulls = {s.link for s in draft.shapes if isinstance(s, VisualHull)}
    assert {"left_upperleg", "left_lowerleg", "left_hand", "middle_thorax"} <= hulls
    assert draft.up_axis == "+y" and draft.root_rpy_deg == (90.0, 0.0, 0.0)
    assert not any(c.contact.flush for c in draft.chains)  # a rounded hand mesh: a point at its tip


def test_a_robot_without_any_geometry_gets_guessed_feet_and_capsules():
    draft = draft_robot("simple_humanoid", samples=5)
    assert all(not s.from_geometry for s in draft.soles)
    assert any("outside the URDF's limits" in c for c in draft.checks)  # its SRDF state breaks its own limits
    assert any(c.startswith("l_ankle has no geometry") for c in draft.checks)
    assert draft.chains[0].contact.frames[0].parent == "l_wrist"


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("not_xml", r"robot\.urdf: not valid XML"),
        ("mesh", r"robot\.urdf: link 'l_foot' (visual|collision) mesh '.*foot\.stl' not found"),
        ("one_leg", r"robot\.urdf: no two legs: .*'l_hip_yaw'.*waist"),
        ("mjcf", r"robot\.xml: no body in <worldbody>"),
        ("missing", r"nothing\.urdf: file not found"),
        ("not_urdf", r"robot\.urdf: not a URDF \(its root element is <sdf>"),
    ],
)
def test_bad_input_is_one_line_naming_the_file_and_element(case, message, tmp_path, capsys):
    path = humanoid_urdf(tmp_path, legs=1 if case == "one_leg" else 2)
    if case == "not_xml":
        path.write_text(path.read_text()[:-20])
    elif case == "mesh":
        (tmp_path / "meshes" / "foot.stl").unlink()
    elif case == "mjcf":
        path = tmp_path / "robot.xml"
        path.write_text("<mujoco><worldbody/></mujoco>")
    elif case == "missing":
        path = tmp_path / "nothing.urdf"
    elif case == "not_urdf":
        path.write_text("<sdf/>")
    output = tmp_path / "config.yaml"
    assert main(["robot", "init", str(path), "-o", str(output), "--samples", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("posegen: error: ")
    assert re.search(message, err), err
    assert not output.exists()  # never a half draft


def test_a_config_may_name_a_urdf_without_srdf_and_a_root_orientation(drafts):
    _, scene = drafts["y"]
    config = scene.config
    assert config.robot.srdf is None and scene.files.srdf is None
    assert config.to_dict()["stance"]["root_rpy_deg"] == [90.0, 0.0, 0.0]
    turned = Scene(dataclasses.replace(config, stance=dataclasses.replace(config.stance, root_rpy_deg=None)))
    with pytest.raises(ConfigError, match=r"soles are not on one floor|not under the robot|not balanced"):
        check_for_planning(turned)  # the y-up model lying on its back: the orientation is what makes it stand
    assert np.all(np.isfinite(turned.reference))


def test_relative_mesh_paths_are_read_from_the_urdf_folder(drafts, tmp_path):
    from posegen.robot.description import absolute_mesh_paths

    text = '<robot><link name="a"><visual><geometry><mesh filename="../m/x.stl"/></geometry></visual></link></robot>'
    fixed = absolute_mesh_paths(text, tmp_path / "urdf")
    assert f'filename="{(tmp_path / "m" / "x.stl").resolve()}"' in fixed
    kept = text.replace("../m/x.stl", "package://p/x.stl")
    assert absolute_mesh_paths(kept, tmp_path) == kept
    _, scene = drafts["z"]  # its URDF names its meshes relative to its folder
    assert scene.files.urdf_text().count(str(scene.files.urdf.parent / "meshes")) == 8  # 2 feet, 2 hands, x2


def test_a_visual_hull_contains_the_visual_mesh(drafts):
    from posegen.robot.collision_geometry import robot_geometry

    _, scene = drafts["z"]
    hull = CollisionConfig(shapes=(VisualHull("l_hand"),))
    geom = robot_geometry(scene.model, scene.urdf_xml, scene.files.package_dirs, hull, convex=False)
    visual = pin.buildGeomFromUrdfString(scene.model, scene.urdf_xml, pin.VISUAL)
    mesh = next(o for o in visual.geometryObjects if str(scene.model.frames[o.parentFrame].name) == "l_hand")
    made = [o for o in geom.geometryObjects if o.name.startswith("l_hand_shape")]
    assert len(made) == 1 and made[0].placement == mesh.placement
    points = np.asarray(made[0].geometry.points())
    vertices = np.asarray(mesh.geometry.vertices())
    assert points.min(axis=0) == pytest.approx(vertices.min(axis=0)) and points.max(axis=0) == pytest.approx(
        vertices.max(axis=0)
    )
    with pytest.raises(ConfigError, match=r"robot\.collision\.shapes\.l_thigh: visual_hull, but the link has no"):
        robot_geometry(scene.model, scene.urdf_xml, (), CollisionConfig(shapes=(VisualHull("l_thigh"),)), convex=False)


def test_check_says_what_it_checks_with_and_warns_of_bare_links(drafts, tmp_path, capsys):
    draft, scene = drafts["z"]
    primitives = sum(isinstance(s, Capsule) for s in draft.shapes)
    pool = tmp_path / "pool.yaml"
    config = scene.config.source_path
    assert main(["pool", "--n", "2", "--seed", "1", "--workers", "1", "--config", config, "-q", "-o", str(pool)]) == 0
    capsys.readouterr()
    assert main(["check", str(pool), "-q"]) == 0
    out = capsys.readouterr().out
    assert f"(4 meshes, {primitives} primitives; pinocchio" in out and "WARN" not in out
    text = Path(config).read_text()
    bare = tmp_path / "bare.yaml"  # the same robot without the drafted shapes: the thighs have nothing
    bare.write_text(text[: text.index("    shapes:")] + text[text.index("\nstance:") :])
    assert main(["check", str(pool), "--config", str(bare), "-q"]) in (0, 1)
    out = capsys.readouterr().out
    assert "(4 meshes; pinocchio" in out and f"WARN {len(draft.covered)} moving links have no collision geometry" in out
    assert " l_thigh " in out + " "


def test_a_foot_whose_geometry_hangs_from_a_fixed_link_touches_the_floor_by_it(tmp_path):
    """An empty ankle link with the foot's geometry on a link fixed to it (a converted MJCF body's layout)."""
    path = humanoid_urdf(tmp_path, "z")
    text = path.read_text()
    for side in "lr":
        text = text.replace(
            f'<child link="{side}_foot"/>',
            f'<child link="{side}_ankle_end"/>',
        ).replace(
            "</robot>",
            f'<link name="{side}_ankle_end"/><joint name="{side}_foot_fixed" type="fixed">'
            f'<parent link="{side}_ankle_end"/><child link="{side}_foot"/></joint>\n</robot>',
        )
    path.write_text(text)
    draft = write_draft(str(path), str(tmp_path / "config.yaml"), samples=20)
    assert [s.foot_link for s in draft.soles] == ["l_ankle_end", "r_ankle_end"]
    assert draft.floor_contact == ("l_foot", "r_foot")  # the links carrying the geometry
    assert draft.notes[-1].startswith("the draft loads as a scene")  # the feet stand on the floor, not in it


def test_a_torso_rooted_draft_runs_the_whole_chain(tmp_path, capsys):
    """Waist joints between the root (torso) and the legs: init, pool, check, route, check, simulate, calibrate."""

    def run(*argv: str) -> str:
        code = main(list(argv))
        out, err = capsys.readouterr()
        assert code == 0, (argv[0], out, err)
        return out

    config = str(tmp_path / "config.yaml")
    run("robot", "init", str(humanoid_urdf(tmp_path / "description", "z", waist=2)), "--samples", "40", "-o", config)
    pool = tmp_path / "pool.yaml"
    accepted = run("pool", "--n", "10", "--seed", "3", "--workers", "1", "--config", config, "-o", str(pool))
    assert re.search(r"pool: 10 postures accepted", accepted)
    assert "FAIL" not in run("check", str(pool), "-q")
    made, first, route = load_pool(pool), tmp_path / "first.yaml", tmp_path / "route.yaml"
    write_pool(first, dataclasses.replace(made, postures=made.postures[:3]))
    routed = re.search(r"route: (\d) of 3 postures", run("route", str(first), "-q", "--workers", "1", "-o", str(route)))
    assert routed and int(routed.group(1)) >= 1
    assert "FAIL" not in run("check", str(route), "-q")
    measurements = tmp_path / "sim.yaml"
    run("simulate", str(pool), "--seed", "1", "-o", str(measurements))
    run("calibrate", str(measurements), "--prior-scale", "5", "-q", "-o", str(tmp_path / "cal"))
    assert (tmp_path / "cal" / "calibrated.urdf").exists()


def test_names_yaml_would_read_otherwise_are_quoted_in_the_draft(tmp_path):
    """A link ``l_hand: #1`` broke the draft's YAML (a traceback); a joint ``no`` was read back as false."""
    path = humanoid_urdf(tmp_path, "z")
    path.write_text(path.read_text().replace('"l_hand"', '"l_hand: #1"').replace('"neck"', '"no"'))
    draft = write_draft(str(path), str(tmp_path / "config.yaml"), samples=20)
    config = load_config(tmp_path / "config.yaml")
    assert config.chain("left").gripper_frame == "left_gripper"
    assert {f.name: f.parent for f in config.frames}["left_gripper"] == "l_hand: #1"
    assert "no" in {**config.locked_joints, **config.stance.reference_joints}
    assert draft.notes[-1].startswith("the draft loads as a scene")


def test_a_prismatic_joint_has_an_axis_and_is_never_the_knee():
    """``JointModelPZ`` has no ``axis`` attribute: a leg with a sliding joint ended in a traceback."""
    from posegen.draft.stance import joint_axis

    slide = pin.JointModelPZ()
    assert list(joint_axis(slide)) == [0.0, 0.0, 1.0]
    assert list(joint_axis(pin.JointModelRY())) == [0.0, 1.0, 0.0]
