"""The independent jobs of a route, run by worker processes: stops and transfers.

Once the visiting order is fixed, the route falls apart into jobs that need nothing but
their inputs and a loaded robot:

* a **stop** per posture: its vertical paths (approach from the standoff down to the
  pre-contact height; go-to-contact through the posture to the overshoot) and the
  go-to-contact's timing (rest to rest, where force control takes over);
* a **transfer** per pair of consecutive stops: from rest in the first contact to rest
  at the next pre-contact pose, i.e. the release straight up, the free motion (see
  :mod:`posegen.route.free_motion`), shortcut, its corners blended (also where it meets
  the verticals, within their upper half), and the approach straight down, all timed
  at once (:mod:`posegen.route.timing`) with the near-table velocity scale on the
  vertical parts and the free one elsewhere. When the free motion needs via states,
  each via path found is timed so, and the fastest is kept. The robot stops only in
  contact and at the pre-contact pose, where go-to-contact starts.

Every timed piece is then slowed down where its speed would carry the ZMP out of the
support polygon (:mod:`posegen.route.balancing`). Every state passes the robot's holding
torques (hand unloaded; pressing on the way to contact) as well as balance and collisions.

Each job's result depends only on its inputs (the seed is one of them), so jobs can run
on any worker in any order (a :class:`posegen.parallel.Job`).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from posegen.errors import InfeasibleError
from posegen.io import SegmentType
from posegen.robot import (
    Balance,
    CollisionChecker,
    Config,
    FloatArray,
    MotionTorques,
    Projector,
    Scene,
    StanceSpace,
)
from posegen.route.balancing import GRID_SLACK_M, ZmpConstraint, timed_in_balance
from posegen.route.free_motion import FreeMotion, Method, free_motions, raised_midpoints, stream_of, via_sequences
from posegen.route.motion import vertical_paths
from posegen.route.smoothing import blend_corners, shortcut
from posegen.route.timing import Timed
from posegen.route.unplanned import Unplanned, UnplannedCause

START = -1  # the node id of the start posture
KEEP_VERTICAL = 0.5  # fraction of each approach and release (from the table up) that stays exactly vertical


@dataclass(frozen=True)
class Stop:
    """A posture's vertical paths and timed go-to-contact."""

    node: int  # the posture's id in the route (see :mod:`posegen.route.route`)
    chain: str
    approach: FloatArray  # (a, nj) rad, standoff -> pre-contact height
    go_to_contact: Timed  # pre-contact -> overshoot below the plane, rest to rest
    lift: FloatArray | None  # (nj,) the contact lifted well above the table, a via state


@dataclass(frozen=True)
class Transfer:
    """A timed move from one contact (or the start) to the next pre-contact pose (or the start)."""

    timed: Timed  # rest to rest
    kinds: tuple[SegmentType, ...]  # per point: release, free or approach
    method: Method


class Planner:
    """A worker's state: the robot loaded once, and the start posture.

    ``start`` (nj,) rad: where the robot stands when the route begins (and where it
    returns); None: the reference posture (:func:`start_posture`).
    """

    def __init__(self, scene: Scene, seed: int, start: Sequence[float] | None = None) -> None:
        self.scene = scene
        self.seed = seed
        self.space = StanceSpace(scene, CollisionChecker(scene, convex=True))
        self.balance = Balance(scene)
        self.zmp = ZmpConstraint(scene, self.balance, scene.margins.zmp_m + GRID_SLACK_M)
        self.torques = MotionTorques(scene, self.balance)
        self.start = start_posture(scene) if start is None else np.array(start, dtype=float)

    @functools.cached_property
    def projector(self) -> Projector:
        """The placo projection of the vertical paths (built on first use: only stops need it)."""
        return Projector(self.scene)

    @classmethod
    def from_config(cls, config: Config, seed: int, start: Sequence[float] | None = None) -> Planner:
        """Build the planner in a worker (the job's setup)."""
        return cls(Scene(config), seed, start)


def start_posture(scene: Scene) -> FloatArray | None:
    """The reference posture, locked joints at their values, second leg closed on its sole.

    Returns:
        (nj,) joint angles, or None if the second sole cannot be reached from it.

    """
    return scene.close_stance(np.where(scene.locked, scene.locked_values, scene.reference))


def plan_stop(planner: Planner, request: tuple[int, tuple[float, ...], str]) -> Stop | Unplanned:
    """The stop of a posture ``(node, joints, chain)``, or why there is none."""
    node, joints, chain = request
    scene = planner.scene
    vertical = vertical_paths(planner.space, planner.projector, np.array(joints, dtype=float), chain)
    if vertical is None:
        return Unplanned(UnplannedCause.NO_VERTICAL)
    for point in vertical.go_to_contact:
        if not planner.space.holds(np.asarray(point), chain):
            return Unplanned(UnplannedCause.TORQUE)
    limit = scene.velocity_limit * scene.route.velocity_scale_contact
    try:
        path = np.array(vertical.go_to_contact)  # the hand presses at rest (the pool keeps that balanced)
        timed = timed_in_balance(
            scene, planner.balance, planner.zmp, path, limit, _acceleration(scene), planner.torques
        )
    except InfeasibleError as exc:
        return Unplanned(UnplannedCause.NO_TIMING, f"go-to-contact: {exc}")
    return Stop(node, chain, np.array(vertical.approach), timed, vertical.clearance)


def plan_transfer(planner: Planner, request: tuple[Stop | None, Stop | None]) -> Transfer | Unplanned:
    """The transfer between two stops (None: the start posture), or why there is none."""
    source, target = request
    space = planner.space
    assert planner.start is not None
    a = source.approach[0] if source else planner.start
    b = target.approach[0] if target else planner.start
    lifts = (source.lift if source else None, target.lift if target else None)
    vias = [[m] for m in raised_midpoints(space, a, b, *lifts)] + via_sequences(*lifts, planner.start)
    keys = (source.node if source else START, target.node if target else START)
    found = free_motions(space, a, b, vias, stream_of(planner.seed, *keys))
    if isinstance(found, Unplanned):
        return found
    best: Transfer | None = None
    untimed = ""
    for motion in found:
        try:
            transfer = _timed_transfer(planner, motion, source, target, keys)
        except InfeasibleError as exc:  # another motion found may still be timed
            untimed = f"{len(found)} free motions found, none timed: {exc}"
            continue
        if best is None or transfer.timed.times[-1] < best.timed.times[-1]:
            best = transfer
    return Unplanned(UnplannedCause.NO_TIMING, untimed) if best is None else best


def _timed_transfer(
    planner: Planner, found: FreeMotion, source: Stop | None, target: Stop | None, keys: tuple[int, int]
) -> Transfer:
    """Release, a free motion (shortcut unless straight) and approach, corners blended, timed at once."""
    scene, space = planner.scene, planner.space
    free = list(found.waypoints)
    if found.method != Method.STRAIGHT:
        free = shortcut(space, free, np.random.default_rng([planner.seed, *(k + 1 for k in keys)]))
    path, kinds, keep = _with_verticals(free, source, target)
    path, keep, kinds = blend_corners(space, path, keep, kinds, SegmentType.FREE)
    route = scene.route
    speed = {
        SegmentType.FREE: scene.velocity_limit * route.velocity_scale_free,
        SegmentType.RELEASE: scene.velocity_limit * route.velocity_scale_near,
        SegmentType.APPROACH: scene.velocity_limit * route.velocity_scale_near,
    }
    limits = np.array([speed[k] for k in kinds])  # the force is released at rest, before the release moves
    timed = timed_in_balance(
        scene, planner.balance, planner.zmp, np.array(path), limits, _acceleration(scene), planner.torques
    )
    if len(timed.times) != len(path):
        raise RuntimeError("a transfer has repeated waypoints")  # a blend or shortcut never repeats a state
    return Transfer(timed, tuple(kinds), found.method)


def timed_release(scene: Scene, stop: Stop) -> Timed:
    """A route's last release, from the contact straight up to the standoff, timed as a transfer is.

    Within the joint limits at ``velocity_scale_near``, the ZMP inside the support polygon by
    the margin and the torques at speed within their limits (:func:`timed_in_balance`), as
    ``check`` verifies: the route ends there when no free motion leads back to the start.

    Example:
        >>> timed = timed_release(scene, stop)  # (m,) times s, (m, nj) positions rad, ...

    """
    up = np.vstack([stop.go_to_contact.positions[::-1], stop.approach[::-1][1:]])  # (m, nj) rad
    balance = Balance(scene)
    zmp = ZmpConstraint(scene, balance, scene.margins.zmp_m + GRID_SLACK_M)
    limit = scene.velocity_limit * scene.route.velocity_scale_near
    return timed_in_balance(scene, balance, zmp, up, limit, _acceleration(scene), MotionTorques(scene, balance))


def _acceleration(scene: Scene) -> FloatArray:
    return np.full(len(scene.joint_names), scene.route.acceleration_limit_rad_s2)


def _with_verticals(
    free: list[FloatArray], source: Stop | None, target: Stop | None
) -> tuple[list[FloatArray], list[SegmentType], list[bool]]:
    """Release + free + approach waypoints, their kinds, and which must stay (lower verticals, ends)."""
    release: list[FloatArray] = []
    if source is not None:
        contact = list(source.go_to_contact.positions[::-1])  # overshoot -> pre-contact
        release = contact + list(source.approach[::-1][1:])  # ... -> standoff
    approach = list(target.approach) if target is not None else []
    path = release + free[1:] + approach[1:] if release else free + approach[1:]
    kinds = (
        [SegmentType.RELEASE] * len(release)
        + [SegmentType.FREE] * (len(path) - len(release) - max(len(approach) - 1, 0))
        + [SegmentType.APPROACH] * max(len(approach) - 1, 0)
    )
    keep = [False] * len(path)
    if source is not None:
        fixed = len(source.go_to_contact.positions) + _kept(len(source.approach)) - 1  # from the table up
        keep[:fixed] = [True] * fixed
    if target is not None:
        fixed = _kept(len(target.approach))
        keep[len(path) - fixed :] = [True] * fixed
    keep[0] = keep[-1] = True
    return path, kinds, keep


def _kept(count: int) -> int:
    """How many approach waypoints (from the pre-contact one up) stay vertical; the standoff never does."""
    return min(count - 1, int(np.floor(KEEP_VERTICAL * (count - 1))) + 1)
