"""One robot-ready trajectory through the selected contact postures.

Order (open TSP path from the start posture), then per posture: a free motion to its
approach posture (the contact lifted by the standoff along the table normal, balanced),
the approach down to just above the table, the go-to-contact through the contact to a
small overshoot below the plane (force control takes over), a hold, and the release
back up to the approach posture. Optionally a last free motion back to the start. A
posture that cannot be reached is reported and skipped; the others are still routed.
Every segment is timed rest to rest (:mod:`posegen.route.timing`), slower near the table.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from posegen.errors import InfeasibleError
from posegen.progress import Progress, ProgressCallback, ignore_progress
from posegen.robot import CollisionChecker, FloatArray, Posture, Projector, Scene, SegmentType, StanceSpace
from posegen.route.motion import plan_free, vertical_paths
from posegen.route.ordering import Order, order_postures
from posegen.route.timing import Timed, hold, parameterize

LOG = logging.getLogger(__name__)


@dataclass(frozen=True)
class Segment:
    """A run of trajectory points with one meaning."""

    type: SegmentType
    chain: str | None  # the arm at the table (None for free motions)
    posture: int | None  # index of the posture in the input list
    first: int  # index of its first point
    last: int  # index of its last point (inclusive)


@dataclass(frozen=True)
class Route:
    """The timed trajectory and how it was made."""

    joint_names: tuple[str, ...]
    times: FloatArray  # (m,) s, strictly increasing
    positions: FloatArray  # (m, nj) rad
    velocities: FloatArray  # (m, nj) rad/s
    accelerations: FloatArray  # (m, nj) rad/s^2
    segments: tuple[Segment, ...]
    order: Order
    skipped: tuple[tuple[int, str], ...]  # (posture index, reason)

    @property
    def visited(self) -> tuple[int, ...]:
        """Indices of the postures touched, in order."""
        return tuple(s.posture for s in self.segments if s.type == SegmentType.HOLD and s.posture is not None)


def start_posture(scene: Scene) -> FloatArray | None:
    """The reference posture, locked joints at their values, second leg closed on its sole.

    Returns:
        (nj,) joint angles, or None if the second sole cannot be reached from it.

    """
    return scene.close_stance(np.where(scene.locked, scene.locked_values, scene.reference))


def plan_route(
    scene: Scene,
    postures: Sequence[Posture],
    seed: int = 0,
    progress: ProgressCallback = ignore_progress,
) -> Route:
    """Plan and time the visit of every reachable posture.

    Args:
        scene: Scene.
        postures: Contact postures (a selection or a pool).
        seed: Seed of the TSP local search (OMPL's generator is seeded once per process,
            see :func:`posegen.route.motion.seed_planner`).
        progress: Told after each posture.

    Raises:
        InfeasibleError: The start posture is invalid, or no posture can be reached.

    """
    checker = CollisionChecker(scene, convex=True)
    space = StanceSpace(scene, checker)
    projector = Projector(scene)
    route_cfg = scene.route
    start = start_posture(scene)
    if start is None or not space.is_valid(start, None):
        raise InfeasibleError("the start posture (reference posture) is not balanced and collision-free")
    joints = np.array([p.joints for p in postures], dtype=float).reshape(len(postures), -1)
    order = order_postures(start, joints, scene.velocity_limit, seed)
    pieces: list[tuple[SegmentType, str | None, int | None, list[FloatArray]]] = []
    skipped: list[tuple[int, str]] = []
    current, current_high = start, None
    for done, index in enumerate(order.sequence, start=1):
        posture = postures[index]
        vertical = vertical_paths(space, projector, joints[index], posture.chain)
        if vertical is None:
            skipped.append((index, "no balanced, collision-free vertical approach above the contact"))
        else:
            highs = [h for h in (current_high, vertical.clearance) if h is not None]
            free = plan_free(space, current, vertical.approach[0], vias=[highs, [start]])
            if free is None:
                skipped.append((index, f"no free motion found in {int(route_cfg.planning_checks)} state checks"))
            else:
                down = list(vertical.approach) + list(vertical.go_to_contact[1:])
                pieces += [
                    (SegmentType.FREE, None, index, free),
                    (SegmentType.APPROACH, posture.chain, index, list(vertical.approach)),
                    (SegmentType.GO_TO_CONTACT, posture.chain, index, list(vertical.go_to_contact)),
                    (SegmentType.HOLD, posture.chain, index, [vertical.go_to_contact[-1]]),
                    (SegmentType.RELEASE, posture.chain, index, down[::-1]),
                ]
                current, current_high = vertical.approach[0], vertical.clearance
        if skipped and skipped[-1][0] == index:
            LOG.info("posture %d skipped: %s", index, skipped[-1][1])
        progress(Progress(done, len(postures), "posture"))
    if not pieces:
        raise InfeasibleError(f"no posture could be reached ({len(skipped)} skipped)")
    if route_cfg.return_to_start:
        back = plan_free(space, current, start, vias=[[current_high]] if current_high is not None else [])
        if back is None:
            LOG.warning("no free motion back to the start posture: the route ends at the last approach posture")
        else:
            pieces.append((SegmentType.FREE, None, None, back))
    return _assemble(scene, pieces, order, skipped)


def _assemble(
    scene: Scene,
    pieces: list[tuple[SegmentType, str | None, int | None, list[FloatArray]]],
    order: Order,
    skipped: list[tuple[int, str]],
) -> Route:
    cfg = scene.route
    scale = {
        SegmentType.FREE: cfg.velocity_scale_free,
        SegmentType.APPROACH: cfg.velocity_scale_near,
        SegmentType.RELEASE: cfg.velocity_scale_near,
        SegmentType.GO_TO_CONTACT: cfg.velocity_scale_contact,
        SegmentType.HOLD: cfg.velocity_scale_contact,
    }
    acceleration = np.full(len(scene.joint_names), cfg.acceleration_limit_rad_s2)
    times: list[float] = []
    rows: list[tuple[FloatArray, FloatArray, FloatArray]] = []
    segments: list[Segment] = []
    for kind, chain, posture, waypoints in pieces:
        if kind == SegmentType.HOLD:
            timed: Timed = hold(waypoints[0], cfg.hold_s)
        else:
            timed = parameterize(np.array(waypoints), scene.velocity_limit * scale[kind], acceleration)
        offset = times[-1] if times else 0.0
        skip = 1 if times else 0  # a segment starts where the previous one ended, at rest
        first = max(len(times) - 1, 0)
        for k in range(skip, len(timed.times)):
            times.append(offset + float(timed.times[k]))
            rows.append((timed.positions[k], timed.velocities[k], timed.accelerations[k]))
        segments.append(Segment(kind, chain, posture, first, len(times) - 1))
    positions, velocities, accelerations = (np.array([r[i] for r in rows]) for i in range(3))
    return Route(
        joint_names=scene.joint_names,
        times=np.array(times),
        positions=positions,
        velocities=velocities,
        accelerations=accelerations,
        segments=tuple(segments),
        order=order,
        skipped=tuple(skipped),
    )
