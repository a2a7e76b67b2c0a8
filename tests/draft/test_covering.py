"""Geometry a draft can trust on a robot never seen: a palm fixed below a wrist with a visual mesh only,
two thin collision rods under a wide sole mesh, a collision disc under a tall torso mesh."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pinocchio as pin
import pytest

from posegen.cli.main import main
from posegen.draft import write_draft
from posegen.robot import COVER_TOL_M, Scene, VisualHull, left_out_m, load_config, robot_geometry
from posegen.robot.additions import CollisionConfig
from posegen.robot.coverage import geometry_coverage
from tests.draft.humanoid_urdf import FOOT, humanoid_urdf

SOLE_TOLERANCE = 0.2  # a foot polygon within 20 % of the sole mesh's extent


@pytest.fixture(scope="module")
def unseen(tmp_path_factory):
    """The synthetic humanoid with all three flaws, drafted (written and loaded)."""
    folder = tmp_path_factory.mktemp("unseen")
    urdf = humanoid_urdf(folder / "description", palms=True, rod_feet=True, disc_torso=True)
    config = folder / "config.yaml"
    draft = write_draft(str(urdf), str(config), samples=20)
    return draft, Scene(load_config(config))


def _geometry(scene: Scene, collision: CollisionConfig) -> tuple[pin.GeometryModel, pin.GeometryModel]:
    checked = robot_geometry(scene.model, scene.urdf_xml, scene.files.package_dirs, collision, convex=False)
    return checked, pin.buildGeomFromUrdfString(scene.model, scene.urdf_xml, pin.VISUAL)


def _without_shapes(scene: Scene) -> Scene:
    """The same robot with the URDF's geometry alone (the draft's shapes taken out)."""
    pairs = CollisionConfig(disabled_pairs=scene.config.collision.disabled_pairs)
    return Scene(dataclasses.replace(scene.config, collision=pairs))


def test_a_palm_fixed_below_the_wrist_gets_the_hull_of_its_visual_mesh(unseen):
    draft, scene = unseen
    assert draft.covered["l_palm"] == draft.covered["r_palm"] == "the convex hull of its visual meshes"
    assert {VisualHull("l_palm"), VisualHull("r_palm")} <= set(draft.shapes)
    checked, visual = _geometry(scene, scene.config.collision)
    assert left_out_m(scene.model, checked, visual, "l_palm") <= 1e-9  # its mesh inside the checked geometry
    urdf_only, _ = _geometry(scene, CollisionConfig())
    assert left_out_m(scene.model, urdf_only, visual, "l_palm") > 0.1  # the wrist's shapes alone leave it out
    (left, right) = (chain.contact for chain in draft.chains)
    assert left.flush and left.touching == ("l_palm",) and right.touching == ("r_palm",)  # its face: the palm's
    assert scene.chain("left").touching_links == ("l_palm",)


def test_the_links_the_draft_covers_are_those_check_finds_bare_without_its_shapes(unseen):
    draft, scene = unseen
    assert draft.bare == () and geometry_coverage(scene).bare_links == ()  # no CHECK line, no WARN
    bare = geometry_coverage(_without_shapes(scene)).bare_links
    assert {"l_palm", "r_palm", "l_thigh"} <= set(bare)  # the palm too, though the wrist's joint carries shapes
    assert set(bare) == set(draft.covered)  # one rule: what check would warn of is what the draft covered


def test_the_draft_runs_and_check_warns_of_the_palm_without_its_shapes(unseen, tmp_path, capsys):
    draft, scene = unseen
    pool, route = tmp_path / "pool.yaml", tmp_path / "route.yaml"
    config = scene.config.source_path
    assert main(["pool", "--n", "3", "--seed", "1", "--workers", "1", "--config", config, "-q", "-o", str(pool)]) == 0
    assert main(["route", str(pool), "-q", "--workers", "1", "-o", str(route)]) == 0
    capsys.readouterr()
    for plan in (pool, route):
        assert main(["check", str(plan), "-q"]) == 0  # the plans pass on the drafted geometry
        out = capsys.readouterr().out
        assert "WARN" not in out and "hulls of visual meshes" in out
    text = Path(config).read_text()
    stripped = tmp_path / "stripped.yaml"
    stripped.write_text(text[: text.index("    shapes:")] + text[text.index("\nstance:") :])
    main(["check", str(pool), "--config", str(stripped), "-q"])
    (warning,) = [line for line in capsys.readouterr().out.splitlines() if "WARN" in line]
    assert f"WARN {len(draft.covered)} moving links have no collision geometry" in warning
    assert " l_palm " in warning + " " and " r_palm" in warning


def test_thin_rods_under_a_wide_sole_mesh_give_the_soles_footprint(unseen):
    draft, _ = unseen
    length, width = FOOT[0], FOOT[1]  # the sole mesh, centred 3 cm in front of the ankle
    assert draft.foot_x_m == pytest.approx((0.03 - length / 2, 0.03 + length / 2), abs=1e-3)
    assert draft.foot_y_m == pytest.approx((-width / 2, width / 2), abs=1e-3)
    assert abs(draft.foot_y_m[1] - draft.foot_y_m[0] - width) <= SOLE_TOLERANCE * width  # not the rods' 4 cm
    assert set(draft.left_out) >= {"l_foot", "r_foot"}  # the rods give way to the sole mesh's hull


def test_a_disc_under_a_tall_torso_mesh_gives_way_to_a_hull_containing_the_mesh(unseen):
    draft, scene = unseen
    assert draft.left_out["torso"] == "its visual geometry reaches 190 mm outside them"
    assert any("torso: its visual geometry reaches 190 mm" in check for check in draft.checks)
    checked, visual = _geometry(scene, scene.config.collision)
    assert left_out_m(scene.model, checked, visual, "torso") <= 1e-9
    urdf_only, _ = _geometry(scene, CollisionConfig())
    assert left_out_m(scene.model, urdf_only, visual, "torso") > 0.15  # the disc alone
    assert left_out_m(scene.model, urdf_only, visual, "l_hand") <= COVER_TOL_M  # a link whose shapes hold it: kept
    assert "l_hand" not in draft.left_out


def test_a_pelvis_under_a_root_link_at_the_floor_gets_the_capsules_it_gets_as_the_root(tmp_path):
    """The capsules along the joints started at the root joint: under a ``base_footprint`` 0.63 m below
    (iCub's case), the pelvis's reached the floor and the zero posture collided with it."""
    from posegen.draft.covering import skeleton

    urdf = humanoid_urdf(tmp_path, "z")
    plain = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    root = (
        '<link name="base_footprint"/><joint name="to_pelvis" type="fixed"><parent link="base_footprint"/>'
        '<child link="pelvis"/><origin xyz="0 0 0.63"/></joint>'
    )
    text = urdf.read_text().replace('<robot name="synthetic">', f'<robot name="synthetic">{root}')
    rooted = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    assert rooted.frames[rooted.getFrameId("pelvis")].placement.translation[2] == pytest.approx(0.63)  # off joint 1
    for link in ("pelvis", "torso", "l_thigh"):
        assert skeleton(rooted, link) == skeleton(plain, link), link
    assert skeleton(plain, "pelvis")  # the pelvis has capsules to check: to its hips and waist
