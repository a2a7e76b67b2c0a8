"""The planned run, sampled at the control rate: joint commands, and what the plan says of the CoM and pelvis.

The commands follow the route's trajectory as a joint trajectory controller does (cubic
Hermite through its points' positions and velocities), held at the route's first posture
for ``rest_s`` before it starts and at its last for ``rest_s`` after it ends. The planned
CoM, pelvis and hands are the nominal model's at the commanded angles, its anchor sole at its place;
the planned ZMP is the floor's centre of pressure that the commanded motion needs, hands
free (the whole robot's inverse dynamics, :class:`posegen.robot.Balance`), computed every
``ZMP_EVERY`` samples and interpolated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.calibrate import hermite
from posegen.io import Route
from posegen.robot import Balance, FloatArray, Scene, centres_of_pressure

ZMP_EVERY = 10  # samples between two inverse-dynamics computations of the planned ZMP


@dataclass(frozen=True)
class Plan:
    """The commands and the planned figures at each control sample."""

    times_s: FloatArray  # (n,) s from the run's start
    route_start_s: float  # the route's time 0 on the run's clock
    positions: FloatArray  # (n, nj) rad, scene joint order
    velocities: FloatArray  # (n, nj) rad/s
    com: FloatArray  # (n, 2) m, the planned CoM's ground projection
    com_velocity: FloatArray  # (n, 2) m/s, its rate
    zmp: FloatArray  # (n, 2) m, the planned ZMP (the motion's floor wrench, hands free)
    pelvis_z: FloatArray  # (n,) m, the planned height of the free base
    base_rotation: FloatArray  # (n, 3, 3) the free base's planned orientation
    hands: dict[str, FloatArray]  # chain -> (n, 4, 4) its contact frame's planned world pose


def _hermite_rate(times: FloatArray, positions: FloatArray, velocities: FloatArray, at: FloatArray) -> FloatArray:
    """The time derivative (n, nj) of :func:`hermite`; zero before and after ``times``."""
    k = np.clip(np.searchsorted(times, at, side="right") - 1, 0, len(times) - 2)
    h = (times[k + 1] - times[k])[:, None]
    raw = (at - times[k])[:, None] / h
    s = np.clip(raw, 0.0, 1.0)
    s2 = s * s
    rate = (
        (6 * s2 - 6 * s) * positions[k] / h
        + (3 * s2 - 4 * s + 1) * velocities[k]
        + (6 * s - 6 * s2) * positions[k + 1] / h
        + (3 * s2 - 2 * s) * velocities[k + 1]
    )
    inside = (raw >= 0.0) & (raw <= 1.0)
    return np.asarray(np.where(inside, rate, 0.0))


def _hermite_acceleration(
    times: FloatArray, positions: FloatArray, velocities: FloatArray, at: FloatArray
) -> FloatArray:
    """The second time derivative (n, nj) of :func:`hermite`; zero before and after ``times``."""
    k = np.clip(np.searchsorted(times, at, side="right") - 1, 0, len(times) - 2)
    h = (times[k + 1] - times[k])[:, None]
    raw = (at - times[k])[:, None] / h
    s = np.clip(raw, 0.0, 1.0)
    rate = (
        (12 * s - 6) * positions[k] / h**2
        + (6 * s - 4) * velocities[k] / h
        + (6 - 12 * s) * positions[k + 1] / h**2
        + (6 * s - 2) * velocities[k + 1] / h
    )
    inside = (raw >= 0.0) & (raw <= 1.0)
    return np.asarray(np.where(inside, rate, 0.0))


def _planned_zmp(
    scene: Scene, route: Route, columns: list[int], at: FloatArray, commanded: FloatArray, rates: FloatArray
) -> FloatArray:
    """The planned ZMP (n, 2) m at the samples ``at`` (route time, s): every ``ZMP_EVERY``-th, interpolated."""
    picked = np.unique(np.append(np.arange(0, len(at), ZMP_EVERY), len(at) - 1))
    accelerations = _hermite_acceleration(
        route.times, route.positions[:, columns], route.velocities[:, columns], at[picked]
    )
    balance = Balance(scene)
    wrenches = np.array(
        [sum(balance.point(commanded[i], rates[i], a, None, 0.0)) for i, a in zip(picked, accelerations, strict=True)]
    )  # (m, 6)
    points = centres_of_pressure(wrenches)
    return np.column_stack([np.interp(at, at[picked], points[:, d]) for d in range(2)])


def sample_plan(scene: Scene, route: Route, period_s: float, rest_s: float) -> Plan:
    """The route sampled every ``period_s``, with ``rest_s`` at rest before and after.

    Args:
        scene: The nominal scene (the route's joints reordered to its order).
        route: The route (validated by :func:`posegen.io.read_route`).
        period_s: Control period, s.
        rest_s: Time at rest before the route starts and after it ends, s.

    Example:
        >>> plan = sample_plan(scene, read_route("plans/route.yaml"), 0.002, 1.0)

    """
    columns = route.joint_columns(scene.joint_names)
    positions, velocities = route.positions[:, columns], route.velocities[:, columns]
    count = int(np.floor((float(route.times[-1]) + 2 * rest_s) / period_s + 1e-9)) + 1
    times = np.arange(count) * period_s
    at = times - rest_s
    commanded = hermite(route.times, positions, velocities, at)
    rates = _hermite_rate(route.times, positions, velocities, at)
    model, data = scene.model, scene.model.createData()
    com = np.zeros((count, 2))
    pelvis = np.zeros(count)
    rotation = np.zeros((count, 3, 3))
    frames = {c.name: scene.frame_id(c.frame(c.contact_kind)) for c in scene.chains}
    hands: dict[str, FloatArray] = {c: np.zeros((count, 4, 4)) for c in frames}
    for i, joints in enumerate(commanded):
        q = scene.configuration(joints)
        com[i] = pin.centerOfMass(model, data, q, False)[:2]  # also the joints' placements
        pelvis[i] = q[2]
        rotation[i] = pin.Quaternion(q[3:7]).toRotationMatrix()
        for chain, frame in frames.items():
            hands[chain][i] = pin.updateFramePlacement(model, data, frame).homogeneous
    com_velocity = np.gradient(com, period_s, axis=0) if count > 1 else np.zeros_like(com)
    zmp = _planned_zmp(scene, route, columns, at, commanded, rates)
    return Plan(times, rest_s, commanded, rates, com, com_velocity, zmp, pelvis, rotation, hands)
