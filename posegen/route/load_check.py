"""What a route asks of the robot's actuators and feet, at every point (``posegen check ROUTE``).

Recomputed from the stored angles, velocities and accelerations alone:

* **torque**: the static torques that hold each point (:mod:`posegen.robot.statics`),
  with the hand unloaded and, in a go-to-contact or hold, also pressing the table with
  ``route.contact_force_n``, within ``margins.effort_ratio`` times the URDF's effort
  limits, each with its spread over ``margins.com_uncertainty_m`` (the true CoM off the
  model's: :meth:`posegen.robot.Statics.com_spread`). Joints the URDF gives no effort
  limit are not checked (said when none has one).
* **torque at speed**: the torques at the stored timing, hand unloaded, the floor's wrench
  shared as flat feet share it (:mod:`posegen.robot.motion_torques`), each with its spread,
  within half the static margin (0.95 of the effort for ``effort_ratio`` 0.9) or a little
  more than the same point at rest, if that is more.
* **zmp**: the soles' centre of pressure from the robot's inverse dynamics at the stored
  timing (:mod:`posegen.robot.balance`), and at a hold's points also at rest with the
  hand pressing (the force builds and is released while the robot holds still), inside
  the support polygon by ``margins.zmp_m``.

The worst ratio of every joint is reported too (:class:`posegen.robot.JointEffort`).
"""

from __future__ import annotations

import enum
from collections.abc import Sequence

import numpy as np

from posegen.io import Segment, SegmentType
from posegen.robot import (
    Balance,
    FloatArray,
    FloorWrenches,
    JointEffort,
    MotionTorques,
    Scene,
    Statics,
    Worst,
    allowed_ratios,
    effort_ratios,
    effort_ratios_at,
    worst_case,
    zmp_margins,
)

EFFORT_TOL = 1e-4  # on the effort ratio: float32 storage of the angles moves a torque by ~1e-5 N m
ZMP_TOL_M = 1e-5  # on the ZMP margin: float32 storage of the velocities and accelerations


class LoadInvariant(str, enum.Enum):
    """What the robot's actuators and feet must bear at every route point."""

    TORQUE = "torque"
    TORQUE_AT_SPEED = "torque_at_speed"
    ZMP = "zmp"


def pressing_chains(segments: Sequence[Segment], count: int) -> list[str | None]:
    """Per point, the chain whose hand may press the table there, or None.

    The go-to-contact (from its start, above the table, where force control takes over)
    and the hold. The force builds and is released while the robot holds still: the
    torques are checked pressing at every such point, the ZMP pressing at the hold's
    points, at rest (and at every point unloaded, at the stored speed).
    """
    out: list[str | None] = [None] * count
    for seg in segments:
        if seg.type in (SegmentType.GO_TO_CONTACT, SegmentType.HOLD):
            out[seg.first_point : seg.last_point + 1] = [seg.chain] * (seg.last_point + 1 - seg.first_point)
    return out


def _holds(segments: Sequence[Segment]) -> dict[int, str | None]:
    """The points of every hold, with its chain."""
    holds = [seg for seg in segments if seg.type == SegmentType.HOLD]
    return {k: seg.chain for seg in holds for k in range(seg.first_point, seg.last_point + 1)}


def check_loads(
    scene: Scene, segments: Sequence[Segment], times: FloatArray, q: FloatArray, v: FloatArray, a: FloatArray
) -> tuple[list[Worst], tuple[JointEffort, ...]]:
    """The torque and ZMP invariants at every point, and every joint's worst effort ratio.

    Args:
        scene: The scene.
        segments: The route's segment table.
        times: (m,) s.
        q: (m, nj) rad, in the scene's joint order.
        v: (m, nj) rad/s.
        a: (m, nj) rad/s^2.

    """
    pressing = pressing_chains(segments, len(times))
    force = scene.route.contact_force_n
    statics = Statics(scene)
    ratios = np.zeros((len(times), len(scene.joint_names)))  # (m, nj), the worse of unloaded and pressing
    torques = np.zeros_like(ratios)  # (m, nj) N m, the model's
    spreads = np.zeros_like(ratios)  # (m, nj) N m, over the CoM's uncertainty
    for k in range(len(times)):
        spreads[k] = statics.com_spread(q[k])
        for chain in {None, pressing[k]}:
            tau = statics.torques(q[k], chain, force)
            ratio = np.nan_to_num(effort_ratios(scene, np.abs(tau) + spreads[k]), nan=0.0)
            worse = ratio > ratios[k]
            ratios[k, worse], torques[k, worse] = ratio[worse], tau[worse]
    balance = Balance(scene)
    zmp = zmp_margins(scene.support_polygon, _total(balance.floor_wrenches(q, v, a, [None] * len(times))))
    holds = _holds(segments)
    if holds:
        idx = np.array(sorted(holds))
        rest = np.zeros((len(idx), q.shape[1]))
        wrenches = balance.floor_wrenches(q[idx], rest, rest, [holds[k] for k in idx], force)
        zmp[idx] = np.minimum(zmp[idx], zmp_margins(scene.support_polygon, wrenches.static))
    torque = _torque(scene, times, ratios, (torques, spreads), pressing)
    at_speed = _torque_at_speed(scene, times, (q, v, a), spreads)
    return [torque, at_speed, _zmp(scene, times, zmp, holds)], _per_joint(scene, ratios, torques)


def _total(wrenches: FloorWrenches) -> FloatArray:
    return np.asarray(wrenches.static + wrenches.dynamic)


def _at(times: FloatArray, k: int) -> str:
    return f"point {k} (t {times[k]:.4f} s)"


def _torque(
    scene: Scene,
    times: FloatArray,
    ratios: FloatArray,
    loads: tuple[FloatArray, FloatArray],
    pressing: Sequence[str | None],
) -> Worst:
    """The torque invariant; ``loads``: the model's torques and their spreads (CoM's uncertainty), (m, nj) N m."""
    torques, spreads = loads
    allowed = scene.margins.effort_ratio
    names = scene.joint_names
    if not np.any(np.isfinite(scene.effort_limit)):
        return Worst(LoadInvariant.TORQUE, 0.0, -1, 0, "the URDF gives no effort limit: torques not checked", (), False)

    def describe(k: int) -> str:
        j = int(np.argmax(ratios[k]))
        load = f"pressing {scene.route.contact_force_n:g} N with {pressing[k]}" if pressing[k] else "hand unloaded"
        spread = f" + {spreads[k, j]:.2f} N m for the CoM's uncertainty" if spreads[k, j] else ""
        return (
            f"{_at(times, k)} {names[j]}: {torques[k, j]:.2f} N m{spread} = {ratios[k, j]:.3f} x its effort limit "
            f"{scene.effort_limit[j]:g} N m ({load}); allowed {allowed}"
        )

    excess = ratios.max(axis=1) - allowed - EFFORT_TOL
    return worst_case(LoadInvariant.TORQUE, excess, describe, f"holding torques within {allowed} x the effort limits")


def _torque_at_speed(
    scene: Scene, times: FloatArray, motion: tuple[FloatArray, FloatArray, FloatArray], spreads: FloatArray
) -> Worst:
    """The torque-at-speed invariant: ``motion`` (q, v, a) each (m, nj); ``spreads`` (m, nj) N m."""
    if not np.any(np.isfinite(scene.effort_limit)):
        return Worst(LoadInvariant.TORQUE_AT_SPEED, 0.0, -1, 0, "the URDF gives no effort limit", (), False)
    torques = MotionTorques(scene)
    loads = torques.loads(*motion)
    moving = effort_ratios_at(scene, torques, loads, spreads, 1.0)  # (m, nj)
    allowed = allowed_ratios(scene, effort_ratios_at(scene, torques, loads, spreads, np.inf))
    names = scene.joint_names

    def describe(k: int) -> str:
        j = int(np.argmax(moving[k] - allowed[k]))
        return (
            f"{_at(times, k)} {names[j]}: {moving[k, j]:.3f} x its effort limit at speed (flat feet), "
            f"{allowed[k, j]:.3f} allowed (half the static margin, or a little more than at rest)"
        )

    excess = (moving - allowed).max(axis=1) - EFFORT_TOL
    detail = "torques at the stored timing (flat feet) within the effort limits"
    return worst_case(LoadInvariant.TORQUE_AT_SPEED, excess, describe, detail)


def _zmp(scene: Scene, times: FloatArray, margins: FloatArray, holds: dict[int, str | None]) -> Worst:
    margin = scene.margins.zmp_m

    def describe(k: int) -> str:
        where = "outside" if margins[k] < 0 else "inside"
        load = f" (the worse of moving and pressing {scene.route.contact_force_n:g} N at rest)" if k in holds else ""
        return f"{_at(times, k)} ZMP {abs(margins[k]):.4f} m {where} the support polygon{load}; margin {margin} m"

    return worst_case(
        LoadInvariant.ZMP, margin - ZMP_TOL_M - margins, describe, f"ZMP inside the support polygon by {margin} m"
    )


def _per_joint(scene: Scene, ratios: FloatArray, torques: FloatArray) -> tuple[JointEffort, ...]:
    out = []
    for j, name in enumerate(scene.joint_names):
        if not np.isfinite(scene.effort_limit[j]):
            continue
        k = int(np.argmax(ratios[:, j]))
        out.append(JointEffort(name, float(ratios[k, j]), float(torques[k, j]), float(scene.effort_limit[j]), k))
    return tuple(out)
