"""Point contacts in planning: one fingertip (or a round hand) on the table, height only."""

import copy

import numpy as np
import pinocchio as pin
import pytest

from posegen.errors import ConfigError
from posegen.pool import generate_pool, verify_postures
from posegen.robot import FLUSH, POINT, Invariant, Scene, assess, parse_config
from tests.conftest import RADIUS_M, point_config_data


@pytest.fixture(scope="module")
def point_pool(point_scene):
    return generate_pool(point_scene.config, n=4, seed=5, workers=1)


def test_point_chain_config_round_trips_and_keeps_flush_geometry(point_scene):
    chain = point_scene.chain("left")
    assert chain.contact_kind == POINT and chain.kinds == (FLUSH, POINT)
    again = parse_config(point_scene.config.to_dict())
    assert again.to_dict() == point_scene.config.to_dict()
    assert "left" in point_scene.point_placements and "left" in point_scene.contact_placements


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda c: c.update(contact_kind="edge"), "unknown kind 'edge'; valid kinds: flush, point"),
        (lambda c: c.pop("point_frame"), "point_frame: missing"),
        (lambda c: c.update(point_cone_deg=95), "below 90 deg"),
    ],
)
def test_bad_point_settings(edit, message):
    data = copy.deepcopy(point_config_data())
    edit(data["chains"]["left"])
    with pytest.raises(ConfigError, match=message):
        parse_config(data)


def test_point_postures_touch_with_the_tip_inside_the_cone(point_scene, point_pool):
    assert len(point_pool.postures) == 4
    result = verify_postures(point_scene, point_pool.postures)
    assert result.ok
    data = point_scene.model.createData()
    normal = point_scene.table_pose[:3, 2]
    for posture in point_pool.postures:
        found = assess(point_scene, None, np.array(posture.joints), posture.chain)
        assert Invariant.CONTACT not in found.violations(point_scene)
        pin.framesForwardKinematics(point_scene.model, data, point_scene.configuration(np.array(posture.joints)))
        tip = data.oMf[point_scene.frame_id(f"{posture.chain}_tip")]
        height = float(normal @ (tip.translation - point_scene.table_pose[:3, 3]))
        assert height == pytest.approx(RADIUS_M, abs=1e-4)  # the rounding's centre, its radius above
        assert np.degrees(np.arccos(tip.rotation[:, 2] @ normal)) <= 30.0


def test_a_narrower_cone_is_enforced(point_scene, point_pool):
    narrow = Scene(parse_config(point_config_data(cone_deg=1.0)))
    tilts = [assess(narrow, None, np.array(p.joints), p.chain).contact_tilt_rad for p in point_pool.postures]
    found = [assess(narrow, None, np.array(p.joints), p.chain) for p in point_pool.postures]
    flagged = [Invariant.CONTACT in f.violations(narrow) for f in found]
    assert flagged == [t > np.radians(1.0) for t in tilts] and any(flagged)


def test_a_point_only_chain_needs_no_fingertips():
    data = point_config_data()
    for key in ("fingertip_frames", "fingertip_length_m", "contact_frame"):
        del data["chains"]["left"][key]
    config = parse_config(data)
    assert config.chain("left").kinds == (POINT,)
    assert parse_config(config.to_dict()).to_dict() == config.to_dict()
    scene = Scene(config)
    assert "left" not in scene.contact_placements and not scene.model.existFrame("left_contact")
