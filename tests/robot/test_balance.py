"""The floor's wrench and the ZMP of a moving robot, against finite differences of its CoM and momentum."""

import numpy as np
import pinocchio as pin
import pytest

from posegen.robot import Balance, centres_of_pressure, pressed_zmp_margin, stretch_for_margin, zmp_margins
from tests.robot.conftest import full_state


def test_floor_wrench_is_the_rate_of_momentum_plus_the_weight(scene, motion):
    """f = m (c'' - g) and the moment about the CoM = the centroidal angular momentum's rate (finite differences)."""
    q0, v0, a0 = motion
    model, data = scene.model, scene.model.createData()
    mass = pin.computeTotalMass(model)
    gravity = np.array(model.gravity.linear)
    h = 1e-4

    def state(t):
        joints, velocity = q0 + v0 * t + 0.5 * a0 * t * t, v0 + a0 * t
        q, v, _ = full_state(scene, joints, velocity, np.zeros_like(velocity))
        com = pin.centerOfMass(model, data, q).copy()
        momentum = pin.computeCentroidalMomentum(model, data, q, v).angular.copy()
        return com, momentum

    (c_minus, l_minus), (c_zero, _), (c_plus, l_plus) = state(-h), state(0.0), state(h)
    acceleration = (c_plus - 2 * c_zero + c_minus) / h**2
    rate = (l_plus - l_minus) / (2 * h)
    wrench = Balance(scene).floor_wrenches(q0[None], v0[None], a0[None], [None])
    total = (wrench.static + wrench.dynamic)[0]
    assert total[:3] == pytest.approx(mass * (acceleration - gravity), rel=1e-5, abs=1e-3)
    moment = total[3:] - np.cross(c_zero, total[:3])  # about the CoM
    assert moment == pytest.approx(rate, rel=1e-4, abs=1e-3)
    # the ZMP of that wrench, from the CoM's motion (a point mass plus the momentum's rate)
    zmp = centres_of_pressure(total[None])[0]
    expected = c_zero[:2] - (c_zero[2] * mass * acceleration[:2] + np.array([rate[1], -rate[0]])) / total[2]
    assert zmp == pytest.approx(expected, abs=1e-6)


def test_static_wrench_is_the_weight_under_the_com(scene):
    balance = Balance(scene)
    zero = np.zeros((1, len(scene.joint_names)))
    wrench = balance.floor_wrenches(scene.reference[None], zero, zero, [None])
    assert np.allclose(wrench.dynamic, 0.0, atol=1e-9)
    data = scene.model.createData()
    com = pin.centerOfMass(scene.model, data, scene.configuration(scene.reference))
    assert centres_of_pressure(wrench.static)[0] == pytest.approx(com[:2], abs=1e-9)
    assert zmp_margins(scene.support_polygon, wrench.static)[0] == pytest.approx(
        scene.com_margin(scene.configuration(scene.reference), data), abs=1e-9
    )


def test_a_pressing_hand_moves_the_centre_of_pressure_away_from_it(scene):
    """30 N on a hand far ahead: the floor carries m g - F and its centre of pressure moves back."""
    model, data = scene.model, scene.model.createData()
    q = scene.configuration(scene.reference)
    com = pin.centerOfMass(model, data, q).copy()
    mass = float(data.mass[0])
    hand = np.array([com[0] + 0.6, com[1], 0.7])
    margin_free = pressed_zmp_margin(scene, com, mass, hand, 0.0)
    pressed = pressed_zmp_margin(scene, com, mass, hand, 30.0)
    weight = mass * 9.81
    shift = 30.0 * 0.6 / (weight - 30.0)  # (m g c - F h) / (m g - F) - c, along x
    polygon = scene.support_polygon
    back = polygon_margin_at(polygon, com[:2] - np.array([shift, 0.0]))
    assert margin_free == pytest.approx(scene.com_margin(q, data), abs=1e-9)
    assert pressed == pytest.approx(back, abs=1e-9)


def polygon_margin_at(polygon, point):
    from posegen.robot import polygon_margin

    return polygon_margin(polygon, point)


def test_stretch_scales_the_dynamic_part_as_the_inverse_square(scene, motion):
    """Timing t -> l t: the wrench's motion part of (q, v / l, a / l^2) is the original over l^2; the stretch found
    keeps the margin and a slightly smaller one does not."""
    q0, v0, a0 = motion
    balance = Balance(scene)
    fast = balance.floor_wrenches(q0[None], 8 * v0[None], 64 * a0[None], [None])
    slow = balance.floor_wrenches(q0[None], v0[None], a0[None], [None])
    assert fast.dynamic / 64 == pytest.approx(slow.dynamic, rel=1e-9, abs=1e-9)
    margin = float(zmp_margins(scene.support_polygon, slow.static)[0]) - 0.002
    stretch = stretch_for_margin(scene.support_polygon, fast, margin)
    assert 1.0 < stretch < np.inf
    within = zmp_margins(scene.support_polygon, fast.static + fast.dynamic / stretch**2)[0]
    assert within >= margin
    short = zmp_margins(scene.support_polygon, fast.static + fast.dynamic / (0.99 * stretch) ** 2)[0]
    assert short < margin
