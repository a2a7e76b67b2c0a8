"""A hand settling flush on its fingertips: their polygon in the contact plane, the centre of pressure's test,
the turn that unloads an edge."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from posegen.physics.contact_control import MAX_TURN_RAD_S
from posegen.physics.fingertips import (
    FLUSH_MARGIN_M,
    K_FLUSH,
    MAX_FLUSH_TILT_RAD,
    flush_turn,
    loads_every_tip,
    tip_polygon,
)
from posegen.physics.geometry import tip_points
from posegen.robot import Scene, load_config
from tests.conftest import ROOT


def test_the_fingertips_polygon_lies_in_the_contact_plane_around_its_origin(scene: Scene) -> None:
    """TALOS's three fingertip ends, as the contact frame sees them: in its plane (a flush contact rests on
    them), around its origin; a point contact has none."""
    for chain in scene.chains:
        polygon = tip_polygon(scene, chain.name)
        assert polygon is not None and len(polygon.vertices) == len(chain.fingertip_frames) == 3
        data = scene.model.createData()
        pin.framesForwardKinematics(scene.model, data, scene.model_configuration(scene.locked_values))
        contact = data.oMf[scene.frame_id(chain.contact_frame)]
        for tip, point, _ in tip_points(scene, chain.name):
            end = contact.actInv(data.oMf[scene.frame_id(tip)].act(point))
            assert abs(end[2]) < 1e-9  # in the contact plane
            assert min(np.linalg.norm(polygon.vertices - end[:2], axis=1)) < 1e-12
        assert polygon.margin(np.zeros(2)) > 0.01  # the origin well inside
    point_robot = Scene(load_config(ROOT / "configs" / "jvrc_table.yaml"))
    assert all(tip_polygon(point_robot, c.name) is None for c in point_robot.chains)


def test_the_centre_of_pressure_tells_whether_every_tip_carries_load(scene: Scene) -> None:
    polygon = tip_polygon(scene, scene.chains[0].name)
    assert polygon is not None
    force = 30.0

    def torque(pressure: np.ndarray) -> np.ndarray:  # the push at ``pressure`` (contact x, y), about the origin
        return np.array([pressure[1], -pressure[0]]) * force

    edge = 0.5 * (polygon.vertices[0] + polygon.vertices[1])
    assert loads_every_tip(polygon, force, torque(np.zeros(2)))
    assert not loads_every_tip(polygon, force, torque(edge))  # on two tips
    assert not loads_every_tip(polygon, force, torque(polygon.vertices[2]))  # on one
    depth = polygon.margin(np.zeros(2))  # the origin's
    assert loads_every_tip(polygon, force, torque(edge * (1.0 - 2.0 * FLUSH_MARGIN_M / depth)))  # 2 x the margin in
    assert not loads_every_tip(polygon, force, torque(edge * (1.0 - 0.5 * FLUSH_MARGIN_M / depth)))  # half of it


def test_the_flush_turn_follows_the_torque_up_to_its_bounds() -> None:
    torque = np.array([0.4, -0.2])
    assert np.allclose(flush_turn(torque, np.zeros(2), MAX_TURN_RAD_S), K_FLUSH * torque)
    fast = flush_turn(np.array([10.0, 0.0]), np.zeros(2), MAX_TURN_RAD_S)
    assert np.isclose(np.linalg.norm(fast), MAX_TURN_RAD_S)
    bound = flush_turn(torque, np.array([MAX_FLUSH_TILT_RAD, -MAX_FLUSH_TILT_RAD]), MAX_TURN_RAD_S)
    assert bound[0] == 0.0 and bound[1] == 0.0  # both at their bound, turning further: stopped
    back = flush_turn(-torque, np.array([MAX_FLUSH_TILT_RAD, -MAX_FLUSH_TILT_RAD]), MAX_TURN_RAD_S)
    assert np.allclose(back, -K_FLUSH * torque)  # turning back: free
