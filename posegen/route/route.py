"""One robot-ready trajectory through the selected contact postures.

1. **Order**: an open TSP path from the start posture (the reference posture, or where
   the robot stands, given) on rest-to-rest times
   (:mod:`posegen.route.ordering`).
2. **Stops**, one per posture, and **transfers**, one per consecutive pair
   (:mod:`posegen.route.planner`), planned as independent jobs on a backend (local
   processes or a Dask cluster, :mod:`posegen.parallel`); each job depends on its inputs
   only, so the route is the same, byte for byte, whatever the backend and the number of
   workers.
3. **No posture lost** (:mod:`posegen.route.repair`): a posture whose transfer fails after
   the whole ladder of attempts (:mod:`posegen.route.free_motion`) is taken out and tried
   at other places in the order; if none works, or if it has no vertical approach, the
   pool posture that restores the most information is routed instead. ``skipped`` lists
   only postures for which the pool had no reachable substitute (or no pool was given).
4. **Assembly**: transfer, go-to-contact, hold, transfer, ... and back to the start
   posture (or, if that is impossible or not wanted, a last release up to the standoff).

The robot is at rest at the start and the end, at every pre-contact pose (go-to-contact
begins there, under force control) and in contact; nowhere else.

Postures are numbered as nodes: ``0..n-1`` the input postures, ``n + r`` pool row ``r``
(a substitute), -1 the start posture.
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import logging
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from posegen.errors import InfeasibleError, InputError
from posegen.io import Posture, Segment, SegmentType
from posegen.parallel import Backend, Job, as_backend, job_name
from posegen.progress import Progress, ProgressCallback, ignore_progress
from posegen.robot import FloatArray, Scene, check_for_planning
from posegen.route.ordering import Order, order_postures, rest_to_rest_time
from posegen.route.planner import START, Planner, Stop, Transfer, plan_stop, plan_transfer, timed_release
from posegen.route.repair import (
    Substitutes,
    Substitution,
    insertion_places,
    ranked_substitutes,
    substitution,
)
from posegen.route.timing import SAFETY, Timed, hold
from posegen.route.unplanned import Unplanned

LOG = logging.getLogger(__name__)


@dataclass(frozen=True)
class PlannedRoute:
    """The timed trajectory and how it was made (written as a :class:`posegen.io.Route` by the route stage)."""

    joint_names: tuple[str, ...]
    times: FloatArray  # (m,) s, strictly increasing
    positions: FloatArray  # (m, nj) rad
    velocities: FloatArray  # (m, nj) rad/s
    accelerations: FloatArray  # (m, nj) rad/s^2
    segments: tuple[Segment, ...]
    order: Order  # the TSP order of the input postures (before any repair)
    skipped: tuple[tuple[int, str], ...]  # (posture node, reason): lost, with no substitute
    substitutions: tuple[Substitution, ...]
    methods: tuple[str, ...]  # how each transfer's free motion was found, in route order
    returns: bool  # whether the route ends at the start posture

    @property
    def visited(self) -> tuple[int, ...]:
        """Nodes of the postures touched, in order."""
        return tuple(s.posture for s in self.segments if s.type == SegmentType.HOLD and s.posture is not None)


def plan_route(
    scene: Scene,
    postures: Sequence[Posture],
    seed: int = 0,
    workers: int | Backend = 1,
    substitutes: Substitutes | None = None,
    progress: ProgressCallback = ignore_progress,
    from_posture: Sequence[float] | None = None,
) -> PlannedRoute:
    """Plan and time the visit of every posture.

    Args:
        scene: Scene.
        postures: Contact postures (a selection or a pool).
        seed: Seed of the TSP local search, of OMPL's streams and of the shortcuts.
        workers: Local worker processes planning stops and transfers (1: this process),
            or the backend to run them on.
        substitutes: The pool of a selection, to replace a posture that cannot be routed;
            None: such a posture is skipped.
        progress: Told after each planning job.
        from_posture: Where the robot stands when the route begins, (nj,) rad in the scene's
            joint order (e.g. the end of the route it played before); the route starts
            there (and returns there). None: the reference posture.

    Raises:
        InputError: A start posture of another size than the robot's joints.
        InfeasibleError: The start posture is invalid, or no posture can be reached.

    """
    given = None if from_posture is None else tuple(float(v) for v in from_posture)
    if given is not None and len(given) != len(scene.joint_names):
        raise InputError(f"the start posture has {len(given)} joint angles; the robot has {len(scene.joint_names)}")
    local = Planner(scene, seed, given)
    check_for_planning(scene, local.space.checker)
    start = local.start
    if start is None or not local.space.is_valid(start, None):
        what = "reference posture" if given is None else "the posture given"
        raise InfeasibleError(f"the start posture ({what}) is not balanced and collision-free")
    velocity = SAFETY * scene.velocity_limit * scene.route.velocity_scale_free
    acceleration = SAFETY * np.full(len(scene.joint_names), scene.route.acceleration_limit_rad_s2)
    joints = np.array([p.joints for p in postures], dtype=float).reshape(len(postures), -1)
    order = order_postures(start, joints, velocity, acceleration, seed)
    job = planning_job(scene, seed, given)
    backend = as_backend(workers)
    with contextlib.nullcontext() if backend is workers else backend:  # one made here keeps its workers, then stops
        run = _Routing(scene, postures, substitutes, start, _all_in_flight(backend, job), progress)
        run.plan(order.sequence)
    return run.assemble(order)


def _all_in_flight(
    backend: Backend, job: Job[Planner, tuple[str, Any], Stop | Transfer | Unplanned]
) -> Callable[[Sequence[tuple[str, Any]]], Iterator[Stop | Transfer | Unplanned]]:
    """The backend's map of the planning job with every item of a batch in flight (their costs differ 100-fold)."""
    return lambda requests: backend.map(job, requests, window=len(requests))


def _plan_one(planner: Planner, request: tuple[str, Any]) -> Stop | Transfer | Unplanned:
    """One job of a route: a stop (``("stop", ...)``) or a transfer (``("transfer", ...)``)."""
    kind, item = request
    return plan_stop(planner, item) if kind == "stop" else plan_transfer(planner, item)


def planning_job(
    scene: Scene, seed: int, start: tuple[float, ...] | None = None
) -> Job[Planner, tuple[str, Any], Stop | Transfer | Unplanned]:
    """The route's work: stops and transfers, each planned by a worker's planner (from ``start``; None: reference)."""
    parts: tuple[Any, ...] = (scene.config.to_dict(), scene.files.sha256(), seed)
    return Job(
        name=job_name("route", *parts, *([] if start is None else [list(start)])),
        setup=functools.partial(Planner.from_config, scene.config, seed, start),
        run=_plan_one,
    )


class _Routing:
    """The state of one planning: stops and transfers planned so far, the sequence, the repairs."""

    def __init__(
        self,
        scene: Scene,
        postures: Sequence[Posture],
        substitutes: Substitutes | None,
        start: FloatArray,
        run: Callable[[Sequence[tuple[str, Any]]], Iterator[Stop | Transfer | Unplanned]],
        progress: ProgressCallback,
    ) -> None:
        self.scene = scene
        self.postures = postures
        self.substitutes = substitutes
        self.start = start
        self.run = run  # the backend's map of the planning job
        self.progress = progress
        self.stops: dict[int, Stop | Unplanned] = {}
        self.transfers: dict[tuple[int, int], Transfer | Unplanned] = {}
        self.sequence: list[int] = []
        self.closed = scene.route.return_to_start
        self.skipped: list[tuple[int, str]] = []
        self.substitutions: list[Substitution] = []
        self.jobs, self.expected = 0, 2 * len(postures) + 1
        route = scene.route
        self._velocity = SAFETY * scene.velocity_limit * route.velocity_scale_free
        self._acceleration = SAFETY * np.full(len(scene.joint_names), route.acceleration_limit_rad_s2)

    # -- nodes --------------------------------------------------------------------------

    def posture(self, node: int) -> Posture:
        """The posture of a node."""
        if node < len(self.postures):
            return self.postures[node]
        assert self.substitutes is not None
        return self.substitutes.postures[node - len(self.postures)]

    def joints(self, node: int) -> FloatArray:
        """The joint angles of a node (the start posture for -1). Shape (nj,)."""
        return self.start if node == START else np.array(self.posture(node).joints, dtype=float)

    def row(self, node: int) -> int | None:
        """The pool row of a node, if known."""
        return self.substitutes.row(node, len(self.postures)) if self.substitutes is not None else None

    def time(self, a: int, b: int) -> float:
        """Rest-to-rest time between two nodes at the free velocity scale, s."""
        return float(rest_to_rest_time(self.joints(b) - self.joints(a), self._velocity, self._acceleration))

    # -- jobs ---------------------------------------------------------------------------

    def _report(self) -> None:
        self.jobs += 1
        self.expected = max(self.expected, self.jobs)
        self.progress(Progress(self.jobs, self.expected, "job"))

    def plan_stops(self, nodes: Sequence[int]) -> None:
        """Plan the stops not planned yet (one batch over the workers)."""
        todo = [n for n in dict.fromkeys(nodes) if n not in self.stops]
        requests = [("stop", (n, tuple(self.posture(n).joints), self.posture(n).chain)) for n in todo]
        for node, stop in zip(todo, self.run(requests), strict=True):
            assert not isinstance(stop, Transfer)
            self.stops[node] = stop
            self._report()

    def plan_transfers(self, pairs: Sequence[tuple[int, int]]) -> None:
        """Plan the transfers not planned yet (one batch over the workers)."""
        todo = [p for p in dict.fromkeys(pairs) if p not in self.transfers]
        requests = [("transfer", (self._stop(a), self._stop(b))) for a, b in todo]
        for pair, transfer in zip(todo, self.run(requests), strict=True):
            assert not isinstance(transfer, Stop)
            self.transfers[pair] = transfer
            if isinstance(transfer, Unplanned):
                LOG.info("transfer %s -> %s: %s", *pair, transfer)
            self._report()

    def _stop(self, node: int) -> Stop | None:
        if node == START:
            return None
        stop = self.stops[node]
        assert not isinstance(stop, Unplanned)
        return stop

    def pairs(self, sequence: Sequence[int], closed: bool) -> list[tuple[int, int]]:
        """Consecutive pairs of a visiting order, from the start posture (and back to it if closed)."""
        nodes = [START, *sequence, *([START] if closed and sequence else [])]
        return list(itertools.pairwise(nodes))

    # -- planning -----------------------------------------------------------------------

    def plan(self, order: Sequence[int]) -> None:
        """Plan stops and transfers, then place again or substitute what could not be reached."""
        self.plan_stops(order)
        lost: dict[int, Unplanned | str] = {n: s for n in order if isinstance(s := self.stops[n], Unplanned)}
        self.sequence = [n for n in order if n not in lost]
        unplaced: list[tuple[int, str]] = []
        while self.sequence:
            pairs = self.pairs(self.sequence, self.closed)
            self.plan_transfers(pairs)
            failed = [(a, b) for a, b in pairs if isinstance(self.transfers[(a, b)], Unplanned)]
            if not failed:
                break
            for a, b in failed:
                if b == START:
                    LOG.info("no free motion back to the start posture: the route ends above the last contact")
                    self.closed = False
                elif b in self.sequence:
                    self.sequence.remove(b)
                    unplaced.append((b, f"from posture {a}: {self.transfers[(a, b)]}"))
        for node, reason in unplaced:
            if not self.insert(node):
                lost[node] = reason
        for node in sorted(lost):
            if not self.substitute(node, str(lost[node])):
                self.skipped.append((node, str(lost[node])))
                LOG.info("posture %d skipped: %s", node, lost[node])
        if not self.sequence:
            node, reason = self.skipped[0]
            raise InfeasibleError(
                f"no posture could be reached ({len(self.skipped)} skipped; posture {node}: {reason})"
            )

    def insert(self, node: int) -> bool:
        """Try ``node`` at the cheapest other places in the order; True if placed."""
        places = insertion_places(self.sequence, self.closed, node, self.time)
        needed: list[tuple[int, int]] = []
        for k in places:
            trial = [*self.sequence[:k], node, *self.sequence[k:]]
            needed.extend(p for p in self.pairs(trial, self.closed) if node in p)
        self.plan_transfers(needed)
        for k in places:
            trial = [*self.sequence[:k], node, *self.sequence[k:]]
            if all(not isinstance(self.transfers[p], Unplanned) for p in self.pairs(trial, self.closed) if node in p):
                self.sequence = trial
                return True
        return False

    def substitute(self, lost: int, reason: str) -> bool:
        """Route the pool posture that restores the most information instead of ``lost``; True if done."""
        if self.substitutes is None:
            return False
        tried: set[int] = {r for n in self.stops if (r := self.row(n)) is not None and n >= len(self.postures)}
        routed = [r for n in self.sequence if (r := self.row(n)) is not None]
        rows = ranked_substitutes(self.substitutes, routed, tried)
        nodes = [len(self.postures) + r for r in rows]
        self.plan_stops(nodes)
        for node in nodes:
            if not isinstance(self.stops[node], Unplanned) and self.insert(node):
                row = node - len(self.postures)
                record = substitution(self.substitutes, lost, reason, row, [*routed, row])
                self.substitutions.append(record)
                LOG.info(
                    "posture %d replaced by pool posture %d (O1 %.2f -> %.2f): %s",
                    lost,
                    row,
                    record.o1_before,
                    record.o1_after,
                    reason,
                )
                return True
        return False

    # -- assembly -----------------------------------------------------------------------

    def assemble(self, order: Order) -> PlannedRoute:
        """Concatenate the timed pieces into one trajectory with its segment table."""
        route = self.scene.route
        pieces: list[tuple[Timed, list[tuple[SegmentType, int | None]]]] = []
        methods: list[str] = []
        previous = START
        for node in [*self.sequence, *([START] if self.closed else [])]:
            transfer = self.transfers[(previous, node)]
            assert isinstance(transfer, Transfer)
            methods.append(transfer.method.value)
            owner = {SegmentType.RELEASE: previous, SegmentType.FREE: node, SegmentType.APPROACH: node}
            pieces.append((transfer.timed, [(k, owner[k] if owner[k] != START else None) for k in transfer.kinds]))
            if node != START:
                stop = self._stop(node)
                assert stop is not None
                contact = stop.go_to_contact
                pieces.append((contact, [(SegmentType.GO_TO_CONTACT, node)] * len(contact.times)))
                pieces.append((hold(contact.positions[-1], route.hold_s), [(SegmentType.HOLD, node)] * 2))
            previous = node
        if not self.closed:  # straight up to the standoff, at rest
            stop = self._stop(previous)
            assert stop is not None
            timed = timed_release(self.scene, stop)
            pieces.append((timed, [(SegmentType.RELEASE, previous)] * len(timed.times)))
        return self._concatenate(pieces, order, tuple(methods))

    def _concatenate(
        self, pieces: list[tuple[Timed, list[tuple[SegmentType, int | None]]]], order: Order, methods: tuple[str, ...]
    ) -> PlannedRoute:
        times: list[FloatArray] = []
        rows: list[FloatArray] = []
        tags: list[tuple[SegmentType, int | None]] = []
        offset = 0.0
        for timed, kinds in pieces:
            skip = 1 if times else 0  # a piece starts where the previous one ended, at rest
            times.append(offset + timed.times[skip:])
            rows.append(np.hstack([timed.positions, timed.velocities, timed.accelerations])[skip:])
            if skip:
                tags[-1] = kinds[0]  # the shared point belongs to the later piece
            tags.extend(kinds[skip:])
            offset = float(times[-1][-1])
        stacked, at = np.vstack(rows), np.concatenate(times)
        nj = len(self.scene.joint_names)
        starts = [0] + [k for k in range(1, len(tags)) if tags[k] != tags[k - 1]]
        segments = []
        for i, first in enumerate(starts):
            kind, node = tags[first]
            chain = self.posture(node).chain if node is not None and kind != SegmentType.FREE else None
            last = starts[i + 1] if i + 1 < len(starts) else len(tags) - 1  # ends where the next begins
            segments.append(Segment(kind, chain, node, None, first, last, float(at[first]), float(at[last])))
        return PlannedRoute(
            joint_names=self.scene.joint_names,
            times=at,
            positions=stacked[:, :nj],
            velocities=stacked[:, nj : 2 * nj],
            accelerations=stacked[:, 2 * nj :],
            segments=tuple(segments),
            order=order,
            skipped=tuple(self.skipped),
            substitutions=tuple(self.substitutions),
            methods=methods,
            returns=self.closed,
        )
