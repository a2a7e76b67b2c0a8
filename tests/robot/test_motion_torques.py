"""Joint torques at speed with flat feet, against pinocchio's inverse dynamics with the soles' wrenches applied."""

import numpy as np
import pinocchio as pin
import pytest

from posegen.robot import MotionTorques, Statics, torque_stretch
from posegen.robot.motion_torques import REST_SLACK, allowed_ratios, effort_ratios_at
from posegen.robot.sole_split import split_wrench
from posegen.route.timing import parameterize
from tests.robot.conftest import full_state


def test_the_torques_are_inverse_dynamics_with_the_soles_carrying_the_floors_wrench(scene, motion):
    """RNEA with the soles' flat-feet wrenches as external forces: no residual on the base, the torques returned."""
    torques = MotionTorques(scene)
    load = torques.load(*motion)
    model, data = scene.model, scene.model.createData()
    q, v, a = full_state(scene, *motion)
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    floor = data.oMi[1].act(pin.Force(pin.rnea(model, data, q, v, a)[:6])).vector  # world, about the origin
    poses = [data.oMf[f].homogeneous for f in torques.soles]
    (x0, x1), (y0, y1) = scene.stance.foot_x_m, scene.stance.foot_y_m
    centre, half = np.array([(x0 + x1) / 2, (y0 + y1) / 2, 0.0]), np.array([(x1 - x0) / 2, (y1 - y0) / 2])
    soles = split_wrench(floor, poses, centre, half)
    external = [pin.Force.Zero() for _ in range(model.njoints)]
    for frame, wrench in zip(torques.soles, soles, strict=True):
        parent = model.frames[frame].parentJoint
        external[parent] = external[parent] + model.frames[frame].placement.act(pin.Force(wrench))
    generalized = pin.rnea(model, data, q, v, a, external)
    assert np.abs(generalized[:6]).max() < 1e-6  # the soles carry the whole floor wrench
    assert torques.torques(load) == pytest.approx(generalized[scene.velocity_indices()], abs=1e-6)
    for wrench in soles:  # each sole's centre of pressure on its rectangle
        cop = np.array([-wrench[4], wrench[3]]) / wrench[2]
        assert np.all(np.abs(cop - centre[:2]) <= half + 1e-9)


def test_standing_at_rest_the_flat_feet_hold_what_the_least_size_split_holds(scene):
    """Half-sitting, the ZMP between the feet: the same normal shares (the moments are shared alike, not least)."""
    torques = MotionTorques(scene)
    rest = np.zeros(len(scene.joint_names))
    load = torques.load(scene.reference, rest, rest)
    at_rest = torques.torques(load, np.inf)
    assert at_rest == pytest.approx(torques.torques(load, 1.0), abs=1e-12)  # no motion, no dynamic part
    assert at_rest == pytest.approx(Statics(scene).torques(scene.reference, None, 0.0), abs=0.05)


def test_a_stretched_motion_asks_what_the_slower_motion_asks(scene, motion):
    """Time stretched by l: velocities / l, accelerations / l^2, the same torques."""
    q, v, a = motion
    torques = MotionTorques(scene)
    load = torques.load(q, v, a)
    for stretch in (1.7, 4.0):
        slower = torques.load(q, v / stretch, a / stretch**2)
        assert torques.torques(load, stretch) == pytest.approx(torques.torques(slower), abs=1e-6)


def test_the_stretch_is_the_least_that_keeps_the_allowed_ratios(scene, example_pool):
    """A weight transfer timed far too fast: slowed to the least stretch (bisection) that keeps every joint."""
    torques = MotionTorques(scene)
    path = np.linspace(scene.reference, np.array(example_pool.postures[4].joints), 12)  # (12, nj)
    timed = parameterize(path, scene.velocity_limit * 4.0, np.full(len(scene.joint_names), 40.0))
    loads = torques.loads(timed.positions, timed.velocities, timed.accelerations)
    spreads = torques.spreads(timed.positions)
    stretch = torque_stretch(scene, torques, loads, spreads)
    assert stretch > 1.0
    allowed = allowed_ratios(scene, effort_ratios_at(scene, torques, loads, spreads, np.inf))
    assert np.all(effort_ratios_at(scene, torques, loads, spreads, stretch) <= allowed + 1e-6)
    assert np.any(effort_ratios_at(scene, torques, loads, spreads, stretch / 1.01) > allowed)
    assert np.all(allowed >= 0.5 * (1 + scene.margins.effort_ratio))
    at_rest = effort_ratios_at(scene, torques, loads, spreads, np.inf)
    assert allowed == pytest.approx(np.maximum(0.95, at_rest + REST_SLACK))
