"""Geometric paths: the vertical approach and contact of one posture, and free motions.

* Approach, go-to-contact, release: the contact frame moves along the table normal above
  its contact point (from the approach standoff down to ``overshoot_m`` below the plane,
  where force control takes over). Each height is a placo projection *from the contact
  posture*, so the path passes through the selected posture itself at height zero.
* Straight lines in the stance space, split so that no joint (the solved leg included)
  moves more than ``waypoint_step_rad`` between checked waypoints: the building block of
  every free motion (:mod:`posegen.route.free_motion`). Every returned waypoint has both
  soles exact and was checked.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.robot import FloatArray, Projector, StanceSpace, contact_in_table

LOG = logging.getLogger(__name__)

HEIGHT_STEP_M = 0.005  # between the projected heights of a vertical path
CLEARANCE_M = 0.15  # height of the via posture above a contact
MAX_HALVINGS = 4  # of one interval of a straight line, to keep every joint's step small


@dataclass(frozen=True)
class Vertical:
    """The vertical paths of one contact posture (waypoints from top to bottom)."""

    approach: tuple[FloatArray, ...]  # standoff -> pre-contact height
    go_to_contact: tuple[FloatArray, ...]  # pre-contact height -> overshoot below the plane
    clearance: FloatArray | None  # the contact lifted by CLEARANCE_M, a via point of free motions


def vertical_paths(space: StanceSpace, projector: Projector, joints: FloatArray, chain: str) -> Vertical | None:
    """Approach and go-to-contact waypoints above a contact posture, or None if infeasible."""
    scene = space.scene
    route = scene.route
    data = scene.model.createData()
    pin.framesForwardKinematics(scene.model, data, scene.configuration(joints))
    contact = pin.SE3(scene.table_pose) * contact_in_table(scene, data, chain)
    normal = scene.table_pose[:3, 2]
    point = contact.translation - normal * float(normal @ (contact.translation - scene.table_pose[:3, 3]))
    standoff = scene.table.approach_standoff_m
    heights = np.unique(
        np.concatenate(
            [
                np.arange(standoff, route.pre_contact_m, -HEIGHT_STEP_M),
                [route.pre_contact_m],
                np.arange(route.pre_contact_m, -route.overshoot_m, -HEIGHT_STEP_M),
                [0.0, -route.overshoot_m],
            ]
        )
    )[::-1]  # from the top
    path = {}
    for height in heights:
        if abs(height) < 1e-12:
            path[0.0] = np.array(joints, dtype=float)
            continue
        result = projector.project(joints, chain, point + height * normal)
        if not result.converged:
            LOG.info("vertical path: projection at %.3f m failed", height)
            return None
        path[float(height)] = result.joints
    approach = tuple(path[h] for h in heights if h >= route.pre_contact_m - 1e-12)
    contact = tuple(path[h] for h in heights if h <= route.pre_contact_m + 1e-12)
    for state in approach:
        if not space.is_valid(state, None, near_table=True):
            return None
    for state in contact:
        if not space.is_valid(state, chain, scene.contact_collision_margin_m):
            return None
    high = projector.project(joints, chain, point + CLEARANCE_M * normal)
    clearance = high.joints if high.converged and space.is_valid(high.joints, None) else None
    return Vertical(approach=approach, go_to_contact=contact, clearance=clearance)


def straight(space: StanceSpace, start: FloatArray, goal: FloatArray) -> list[FloatArray] | None:
    """Waypoints of the straight line in stance coordinates, each checked; None if blocked (see :func:`follow`)."""
    a, b = space.coordinates_of(start), space.coordinates_of(goal)
    return follow(space, lambda f: a + (b - a) * f, float(np.max(np.abs(b - a))), start, goal)


def follow(
    space: StanceSpace,
    curve: Callable[[float], FloatArray],
    length: float,
    start: FloatArray,
    goal: FloatArray,
) -> list[FloatArray] | None:
    """Waypoints along a curve in stance coordinates, each closed and checked; None if blocked.

    No joint moves more than ``waypoint_step_rad`` between consecutive waypoints: the
    curve's parameter is split evenly by its ``length`` (largest coordinate change), and
    an interval where the solved second leg moves further is halved until it does not
    (or until MAX_HALVINGS).

    Args:
        space: The stance space.
        curve: Coordinates at a parameter in [0, 1]; curve(0) and curve(1) are those of
            ``start`` and ``goal``.
        length: Largest coordinate change along the curve, rad.
        start: (nj,) the first state (its second leg warm-starts the first closure).
        goal: (nj,) the last state, which the curve reaches at 1.

    """
    step = space.scene.route.waypoint_step_rad
    count = max(1, int(np.ceil(length / step)))
    path = [np.array(start, dtype=float)]
    fractions = [k / count for k in range(count, 0, -1)]  # a stack: the next fraction is last
    done, halvings = 0.0, 0
    while fractions:
        f = fractions[-1]
        state = space.joints_of(curve(f), path[-1])
        if state is None:
            return None
        if np.max(np.abs(state - path[-1])) > step * (1 + 1e-9) and halvings < MAX_HALVINGS:
            fractions.append((done + f) / 2)  # the leg moved too far: check halfway first
            halvings += 1
            continue
        if not space.is_valid(state, None):
            return None
        path.append(state)
        fractions.pop()
        done, halvings = f, 0
    path[-1] = np.array(goal, dtype=float)  # the same state, to the closure's 1e-10: segments join exactly
    return path


def through(space: StanceSpace, corners: Sequence[FloatArray]) -> list[FloatArray] | None:
    """Straight lines from corner to corner (see :func:`straight`), each checked; None if one is blocked."""
    path: list[FloatArray] = [np.array(corners[0], dtype=float)]
    for a, b in itertools.pairwise(corners):
        leg = straight(space, a, b)
        if leg is None:
            return None
        path.extend(leg[1:])
    return path
