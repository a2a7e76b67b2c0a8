"""The torques at speed as a toppra constraint: exact where linearised, and slower only where they bind."""

import itertools

import numpy as np
import pytest
import toppra

from posegen.errors import InfeasibleError
from posegen.robot import Balance, MotionTorques, stretch_for_margin, torque_stretch
from posegen.route.balancing import ZmpConstraint, slowed_locally, timed_in_balance, within_torques
from posegen.route.timing import parameterize, path_parameter
from posegen.route.torque_constraint import TimedLoads, TorqueConstraint

WAYPOINTS = 10


@pytest.fixture(scope="module")
def fast(scene, example_pool):
    """A straight path between two pool postures that, timed at the joints' full speed and 3x the route's
    acceleration, asks a joint for more torque than it may give: the first of the first eight postures' pairs
    that asks at least 1.2x the time, and that toppra can time with the torques linearised."""
    torques, balance = MotionTorques(scene), Balance(scene)
    velocity = scene.velocity_limit.copy()
    acceleration = np.full(len(scene.joint_names), 3 * scene.route.acceleration_limit_rad_s2)
    for i, j in itertools.combinations(range(8), 2):
        path = np.linspace(example_pool.postures[i].joints, example_pool.postures[j].joints, WAYPOINTS)
        timed = parameterize(path, velocity, acceleration)
        missed = TimedLoads.of(torques, timed)
        if torque_stretch(scene, torques, missed.loads, missed.spreads) < 1.2:
            continue
        try:
            local = slowed_locally(scene, balance, torques, path, velocity, acceleration, [], missed)
        except InfeasibleError:
            continue
        return torques, balance, velocity, acceleration, path, timed, local
    raise AssertionError("no pair of the first eight postures asks that much at that speed")


def test_the_affine_torques_are_the_exact_ones_at_the_reference_timing(scene, fast):
    torques, _, _, _, _, timed, _ = fast
    constraint = TorqueConstraint(scene, torques, TimedLoads.of(torques, timed))
    s = path_parameter(timed.positions)
    path = toppra.SplineInterpolator(s, timed.positions)
    a, b, c, nearest = constraint.affine(path, s)
    assert np.array_equal(nearest, np.arange(len(s)))
    first, second = path(s, 1), path(s, 2)  # (m, nj)
    speed = np.einsum("ij,ij->i", timed.velocities, first) / np.einsum("ij,ij->i", first, first)  # s'
    acceleration = np.einsum("ij,ij->i", timed.accelerations - second * speed[:, None] ** 2, first) / np.einsum(
        "ij,ij->i", first, first
    )  # s''
    finite = np.isfinite(scene.effort_limit)
    for k in range(len(s)):
        exact = torques.torques(torques.load(timed.positions[k], timed.velocities[k], timed.accelerations[k]))
        predicted = a[k] * acceleration[k] + b[k] * speed[k] ** 2 + c[k]
        assert predicted == pytest.approx(exact[finite], abs=1e-3)


def test_a_motion_is_slowed_only_where_its_torques_bind(scene, fast):
    torques, balance, velocity, acceleration, path, timed, local = fast
    loads = torques.loads(local.positions, local.velocities, local.accelerations)
    assert torque_stretch(scene, torques, loads, torques.spreads(local.positions)) == 1.0  # exact: within
    wrenches = balance.floor_wrenches(local.positions, local.velocities, local.accelerations, [None] * len(path))
    assert stretch_for_margin(scene.support_polygon, wrenches, scene.margins.zmp_m) == 1.0
    steps = np.diff(local.times) / np.diff(timed.times)  # (m - 1,) how much slower each step is than unconstrained
    assert steps.max() > 1.2 * steps.min()  # slower where they bind, not by one factor throughout
    uniform = within_torques(scene, torques, TimedLoads.of(torques, timed))
    zmp = ZmpConstraint(scene, balance, scene.margins.zmp_m + 0.002)
    chosen = timed_in_balance(scene, balance, zmp, path, velocity, acceleration, torques)
    assert chosen.times[-1] == min(local.times[-1], uniform.times[-1])  # the faster of the two
