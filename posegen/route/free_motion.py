"""Free motions between two valid states: a ladder of ever costlier attempts, each checked.

In order, the first that gives a path wins:

1. the straight line in the stance space;
2. straight lines through via states: the midpoint of the two ends raised by half or
   all of the lifts above the two contacts (one corner instead of two), the lifts
   themselves (up, across, down), the start posture, and their combinations (a lift,
   then the start posture, then the other lift); a straight joint-space line between
   two high states can dip a hand into the table, and going through the start posture
   avoids that. Up to ``VIA_CANDIDATES`` via paths are returned, for the caller to keep
   the one that times fastest (a shorter detour is not always a faster one);
3. OMPL's RRTConnect with the configured budget of state checks;
4. RRTConnect again with four times that budget and another random stream.

Every waypoint returned was closed onto the second sole and checked at the fine
resolution (``waypoint_step_rad``); OMPL only searches at a coarse one.

OMPL seeds its generators from one process-wide seed sequence. Before each call it is
restarted (``RNG.setSeed`` resets the sequence to the process's first seed, posegen's
constant ``OMPL_SEED``), and ``stream`` throw-away generators are drawn to choose a
stream. A call's result therefore depends on its arguments only, not on what ran
before it in the process: segments may go to any worker in any order.
"""

from __future__ import annotations

import enum
import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from posegen.robot import FloatArray, StanceSpace
from posegen.route.motion import straight, through
from posegen.route.unplanned import Unplanned, UnplannedCause

LOG = logging.getLogger(__name__)

OMPL_SEED = 1  # OMPL's first seed in every process (0 means "from the clock" to OMPL)
SEARCH_STEP_RAD = 0.05  # OMPL's validity-checking resolution while searching
SIMPLIFY_STEPS = 100  # vertex-reduction attempts when shortening OMPL's path
LARGER_BUDGET = 4  # the last attempt's budget, in multiples of the configured one
POLLS_PER_CHECK = 10  # OMPL may poll its stop condition without checking a state (waiting for a goal): bounded too
STREAMS = 1 << 12  # random streams a call may choose from
VIA_CANDIDATES = 2  # via paths returned (the first that work, in ladder order)
RAISE_FRACTIONS = (0.5, 1.0)  # of the lifts, added to the midpoint of a free motion's ends


class Method(str, enum.Enum):
    """How a free motion was found."""

    STRAIGHT = "straight"
    VIA = "via"  # straight lines through via states
    OMPL = "ompl"  # RRTConnect with the configured budget
    OMPL_LARGER = "ompl_larger"  # RRTConnect with the larger budget and another stream


@dataclass(frozen=True)
class FreeMotion:
    """A checked free motion."""

    waypoints: tuple[FloatArray, ...]  # (nj,) each, rad; both ends included
    method: Method
    corners: int  # states where the path turns on purpose (vias, OMPL vertices), ends excluded


def via_sequences(
    start_high: FloatArray | None, goal_high: FloatArray | None, home: FloatArray
) -> list[list[FloatArray]]:
    """The via-state sequences tried after the straight line, in order of expected length."""
    highs = [h for h in (start_high, goal_high) if h is not None]
    candidates = [
        highs,
        [home],
        [*([start_high] if start_high is not None else []), home],
        [home, *([goal_high] if goal_high is not None else [])],
        [*([start_high] if start_high is not None else []), home, *([goal_high] if goal_high is not None else [])],
    ]
    unique: list[list[FloatArray]] = []
    for via in candidates:
        if via and not any(len(via) == len(u) and all(a is b for a, b in zip(via, u, strict=True)) for u in unique):
            unique.append(via)
    return unique


def raised_midpoints(
    space: StanceSpace,
    start: FloatArray,
    goal: FloatArray,
    start_high: FloatArray | None,
    goal_high: FloatArray | None,
) -> list[FloatArray]:
    """Valid via states halfway between two ends, raised by fractions of their lifts.

    The midpoint of ``start`` and ``goal`` plus ``f`` times the mean of the lifts
    (``start_high - start`` and ``goal_high - goal``) for each ``f`` in
    ``RAISE_FRACTIONS``, the second leg closed; states that cannot be closed or are
    invalid are left out. Empty unless both lifts exist.

    Args:
        space: The stance space.
        start: (nj,) rad.
        goal: (nj,) rad.
        start_high: (nj,) ``start``'s contact lifted well above the table, or None.
        goal_high: (nj,) the same for ``goal``, or None.

    """
    if start_high is None or goal_high is None:
        return []
    middle, lift = (start + goal) / 2, ((start_high - start) + (goal_high - goal)) / 2
    found = []
    for fraction in RAISE_FRACTIONS:
        state = middle + fraction * lift
        closed = space.joints_of(space.coordinates_of(state), state)
        if closed is not None and space.is_valid(closed, None):
            found.append(closed)
    return found


def plan_free(
    space: StanceSpace,
    start: FloatArray,
    goal: FloatArray,
    vias: Sequence[Sequence[FloatArray]],
    stream: int,
) -> FreeMotion | Unplanned:
    """A checked free motion from ``start`` to ``goal`` (both valid), or why there is none.

    The first of :func:`free_motions` (the ladder stops at the first that works).
    """
    found = free_motions(space, start, goal, vias, stream, via_candidates=1)
    return found if isinstance(found, Unplanned) else found[0]


def free_motions(
    space: StanceSpace,
    start: FloatArray,
    goal: FloatArray,
    vias: Sequence[Sequence[FloatArray]],
    stream: int,
    via_candidates: int = VIA_CANDIDATES,
) -> list[FreeMotion] | Unplanned:
    """Checked free motions from ``start`` to ``goal`` (both valid), or why there is none.

    Args:
        space: The stance space.
        start: (nj,) rad.
        goal: (nj,) rad.
        vias: Via-state sequences to try after the straight line, in order (see
            :func:`via_sequences` and :func:`raised_midpoints`).
        stream: Chooses OMPL's random streams (derive it from the seed and the segment).
        via_candidates: At most this many via paths are returned.

    Returns:
        The straight line alone if it is free; else the first ``via_candidates`` via
        paths that are free, in the order of ``vias``; else OMPL's path alone.

    """
    path = straight(space, start, goal)
    if path is not None:
        return [FreeMotion(tuple(path), Method.STRAIGHT, 0)]
    found: list[FreeMotion] = []
    tried: list[list[FloatArray]] = []
    for via in vias:
        corners = _distinct_corners([start, *via, goal])
        if len(corners) == 2 or any(_same(corners, t) for t in tried):
            continue  # a via state that is an end (the start posture, from the start posture): seen before
        tried.append(corners)
        path = through(space, corners)
        if path is not None:
            found.append(FreeMotion(tuple(path), Method.VIA, len(corners) - 2))
            if len(found) >= via_candidates:
                break
    if found:
        return found
    budget = int(space.scene.route.planning_checks)
    for method, checks, offset in ((Method.OMPL, budget, 0), (Method.OMPL_LARGER, LARGER_BUDGET * budget, 1)):
        planned = _plan_ompl(space, start, goal, checks, (stream + offset * (STREAMS // 2)) % STREAMS)
        if planned is not None:
            return [FreeMotion(tuple(planned[0]), method, planned[1])]
    return Unplanned(
        UnplannedCause.NO_FREE_MOTION,
        f"straight line and {len(vias)} via sequences blocked, "
        f"OMPL found no checked path in {budget} nor {LARGER_BUDGET * budget} state checks",
    )


def _distinct_corners(corners: Sequence[FloatArray]) -> list[FloatArray]:
    """The corners without those equal to the one before (a zero-length leg would repeat a waypoint)."""
    kept = [corners[0]]
    for corner in corners[1:]:
        if not np.array_equal(corner, kept[-1]):
            kept.append(corner)
    return kept


def _same(a: Sequence[FloatArray], b: Sequence[FloatArray]) -> bool:
    return len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))


def stream_of(seed: int, *keys: int) -> int:
    """A random-stream number for OMPL from a seed and the ids of what is planned."""
    return int(np.random.default_rng([seed, *(k + 1 for k in keys)]).integers(STREAMS))


def _restart_generator(stream: int) -> None:
    from ompl import util as ou

    ou.setLogLevel(ou.LOG_NONE)  # the restart logs "generation already started" from the second call on
    ou.RNG.setSeed(OMPL_SEED)
    ou.setLogLevel(ou.LOG_ERROR)
    if ou.RNG.getSeed() != OMPL_SEED:
        LOG.warning("OMPL was seeded elsewhere in this process (seed %d): routes are not repeatable", ou.RNG.getSeed())
    for _ in range(stream):
        ou.RNG()


def _plan_ompl(
    space: StanceSpace, start: FloatArray, goal: FloatArray, budget: int, stream: int
) -> tuple[list[FloatArray], int] | None:
    """RRTConnect in the stance coordinates, then a fine check; (waypoints, corners) or None."""
    from ompl import base as ob
    from ompl import geometric as og

    _restart_generator(stream)
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
    for i, (u, v) in enumerate(zip(ends[0][0], ends[1][0], strict=True)):
        s0[i], s1[i] = float(u), float(v)
    if not (valid(s0) and valid(s1)):  # OMPL would wait for a valid goal without checking anything: forever
        LOG.info("an end is not valid in the stance coordinates: no OMPL search")
        return None
    setup.setStartAndGoalStates(s0, s1)
    setup.setPlanner(og.RRTConnect(info))
    polls = [0]

    def spent() -> bool:  # a budget of state checks, not of seconds: the same seed, the same path on any machine
        polls[0] += 1
        return checks[0] >= budget or polls[0] >= POLLS_PER_CHECK * budget

    solved = setup.solve(ob.PlannerTerminationCondition(spent))
    if not solved or not setup.haveExactSolutionPath():
        LOG.info("OMPL found no path in %d state checks", budget)
        return None
    solution = setup.getSolutionPath()
    simplifier = og.PathSimplifier(info)
    simplifier.reduceVertices(solution, SIMPLIFY_STEPS, SIMPLIFY_STEPS // 4)
    simplifier.ropeShortcutPath(solution)
    vertices = [np.array([solution.getState(k)[i] for i in range(n)]) for k in range(solution.getStateCount())]
    path = _fine_path(space, start, goal, vertices)
    return None if path is None else (path, max(len(vertices) - 2, 0))


def _fine_path(
    space: StanceSpace, start: FloatArray, goal: FloatArray, vertices: Sequence[FloatArray]
) -> list[FloatArray] | None:
    """OMPL's vertices (stance coordinates) as joint waypoints, each leg checked finely; None if one fails."""
    path = [np.array(start, dtype=float)]
    for k, vertex in enumerate(vertices[1:], start=1):
        target = goal if k == len(vertices) - 1 else space.joints_of(vertex, path[-1])
        leg = straight(space, path[-1], target) if target is not None else None
        if leg is None:
            LOG.info("OMPL's path failed the fine check")
            return None
        path.extend(leg[1:])
    return path
