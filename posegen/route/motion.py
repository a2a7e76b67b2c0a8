"""Geometric paths: the vertical approach and contact of one posture, and free motions.

* Approach, go-to-contact, release: the contact frame moves along the table normal above
  its contact point (from the approach standoff down to ``overshoot_m`` below the plane,
  where force control takes over). Each height is a placo projection *from the contact
  posture*, so the path passes through the selected posture itself at height zero.
* Free motion: a straight line in the stance space is tried first; if any state on it
  is invalid, OMPL's RRTConnect plans in the stance space (seeded), then the path is
  shortened and densified. Every returned waypoint has both soles exact and was checked.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.robot import FloatArray, Projector, StanceSpace, contact_in_table

LOG = logging.getLogger(__name__)

HEIGHT_STEP_M = 0.005  # between the projected heights of a vertical path
SEARCH_STEP_RAD = 0.05  # OMPL's validity-checking resolution while searching
CLEARANCE_M = 0.15  # height of the via posture above a contact
MAX_HALVINGS = 4  # of one interval of a straight line, to keep every joint's step small
SIMPLIFY_STEPS = 100  # vertex-reduction attempts when shortening OMPL's path


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
        if not space.is_valid(state, None):
            return None
    for state in contact:
        if not space.is_valid(state, chain, scene.contact_collision_margin_m):
            return None
    high = projector.project(joints, chain, point + CLEARANCE_M * normal)
    clearance = high.joints if high.converged and space.is_valid(high.joints, None) else None
    return Vertical(approach=approach, go_to_contact=contact, clearance=clearance)


def straight(space: StanceSpace, start: FloatArray, goal: FloatArray) -> list[FloatArray] | None:
    """Waypoints of the straight line in stance coordinates, each checked; None if blocked.

    No joint moves more than ``waypoint_step_rad`` between consecutive waypoints: the
    coordinates are split evenly, and an interval where the solved second leg moves
    further is halved until it does not (or until MAX_HALVINGS).
    """
    a, b = space.coordinates_of(start), space.coordinates_of(goal)
    step = space.scene.route.waypoint_step_rad
    count = max(1, int(np.ceil(np.max(np.abs(b - a)) / step)))
    path = [np.array(start, dtype=float)]
    fractions = [k / count for k in range(count, 0, -1)]  # a stack: the next fraction is last
    done, halvings = 0.0, 0
    while fractions:
        f = fractions[-1]
        state = space.joints_of(a + (b - a) * f, path[-1])
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


def plan_free(
    space: StanceSpace, start: FloatArray, goal: FloatArray, vias: Sequence[Sequence[FloatArray]] = ()
) -> list[FloatArray] | None:
    """A checked free motion from ``start`` to ``goal`` (both valid), or None.

    Tries, in order: the straight line; straight lines through each list of via
    postures (e.g. up above the table and down again, or through the start posture);
    OMPL's RRTConnect.
    """
    for via in [(), *vias]:
        corners = [start, *via, goal]
        path: list[FloatArray] = [np.array(start, dtype=float)]
        for a, b in itertools.pairwise(corners):
            leg = straight(space, a, b)
            if leg is None:
                break
            path.extend(leg[1:])
        else:
            return path
    return _plan_ompl(space, start, goal)


def seed_planner(seed: int) -> None:
    """Seed OMPL's process-wide random generator; effective only before its first use.

    Called once at the start of ``posegen route`` so that a run is repeatable.
    """
    from ompl import util as ou

    ou.setLogLevel(ou.LOG_ERROR)
    ou.RNG.setSeed(seed + 1)  # OMPL takes 0 as "no seed"


def _plan_ompl(space: StanceSpace, start: FloatArray, goal: FloatArray) -> list[FloatArray] | None:
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LOG_ERROR)
    n = len(space.coordinates)
    state_space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for i in range(n):
        bounds.setLow(i, float(space.lower[i]))
        bounds.setHigh(i, float(space.upper[i]))
    state_space.setBounds(bounds)
    setup = og.SimpleSetup(state_space)
    ends = [
        (space.coordinates_of(start), np.array(start, dtype=float)),
        (space.coordinates_of(goal), np.array(goal, dtype=float)),
    ]

    checks = [0]

    def valid(state: object) -> bool:
        checks[0] += 1
        x = np.array([state[i] for i in range(n)])  # type: ignore[index]
        warm = min(ends, key=lambda end: float(np.max(np.abs(end[0] - x))))[1]  # close the leg from the nearer end
        joints = space.joints_of(x, warm)
        return joints is not None and space.is_valid(joints, None)

    setup.setStateValidityChecker(valid)
    info = setup.getSpaceInformation()
    info.setStateValidityCheckingResolution(  # coarse while searching: the result is re-checked finely
        SEARCH_STEP_RAD / max(state_space.getMaximumExtent(), 1e-9)
    )
    s0, s1 = state_space.allocState(), state_space.allocState()
    for i, (u, v) in enumerate(zip(space.coordinates_of(start), space.coordinates_of(goal), strict=True)):
        s0[i], s1[i] = float(u), float(v)
    setup.setStartAndGoalStates(s0, s1)
    setup.setPlanner(og.RRTConnect(info))
    budget = int(space.scene.route.planning_checks)
    # a budget of state checks, not of seconds: the same seed gives the same path on any machine
    solved = setup.solve(ob.PlannerTerminationCondition(lambda: checks[0] >= budget))
    if not solved or not setup.haveExactSolutionPath():
        LOG.info("OMPL found no path in %d state checks", budget)
        return None
    solution = setup.getSolutionPath()
    simplifier = og.PathSimplifier(info)
    simplifier.reduceVertices(solution, SIMPLIFY_STEPS, SIMPLIFY_STEPS // 4)
    simplifier.ropeShortcutPath(solution)
    corners = [np.array([solution.getState(k)[i] for i in range(n)]) for k in range(solution.getStateCount())]
    path = [np.array(start, dtype=float)]
    for corner in corners[1:]:
        goal_joints = space.joints_of(corner, path[-1])
        leg = straight(space, path[-1], goal_joints) if goal_joints is not None else None
        if leg is None:
            LOG.info("OMPL's path failed the fine check")
            return None
        path.extend(leg[1:])
    return path
