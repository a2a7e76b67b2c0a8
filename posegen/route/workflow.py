"""The route stage's commands, from files to files: ``posegen route``, ``posegen check ROUTE``, ``posegen export``."""

from __future__ import annotations

import dataclasses
import hashlib
import logging
import statistics
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from posegen.arguments import check_seed, check_size
from posegen.errors import ArgumentError, InputError
from posegen.io import (
    OutputKind,
    SegmentRow,
    check_apart,
    check_bag_destination,
    check_writable,
    claim_output,
    write_trajectory_bag,
)
from posegen.model import Design, build_design
from posegen.parallel import Backend
from posegen.progress import Progress, ProgressCallback, ignore_progress
from posegen.robot import (
    Pool,
    Scene,
    SegmentType,
    Verification,
    geometry_coverage,
    load_plan,
    read_route,
    route_arrays,
    scene_for,
)
from posegen.route.check import MIN_DT_S, verify_route
from posegen.route.export import route_header, route_outputs, write_route
from posegen.route.repair import Substitutes, o1_figures
from posegen.route.route import Route, plan_route

LOG = logging.getLogger(__name__)

ROUTE_SUFFIXES = (".yaml", ".yml", ".json")


@dataclass(frozen=True)
class Routed:
    """What ``posegen route`` planned and wrote."""

    route: Route
    summary: dict[str, Any]  # the figures recorded in the route file
    written: tuple[Path, ...]  # the route file, its arrays (and the CSV if asked)
    planning_s: float  # wall time of the planning
    repair: str  # how a lost posture would be repaired: from which pool, or why not


def route_plan_file(
    plan_path: str,
    output: str,
    seed: int = 0,
    config_path: str | None = None,
    progress: ProgressCallback = ignore_progress,
    *,
    workers: int | Backend = 1,
    pool_path: str | None = None,
    csv: bool = False,
    from_posture: Sequence[float] | None = None,
) -> Routed:
    """Plan, time and export a trajectory through the postures of a selection (or pool) file.

    Args:
        plan_path: Selection or pool file.
        output: Route file, ``.yaml`` or ``.json``; its arrays go to ``.npz`` beside it.
        seed: Seed of the ordering, of OMPL's streams and of the shortcuts.
        config_path: Scene config; None: the one saved in the plan.
        progress: Told after each planning job.
        workers: Local worker processes planning the route's segments, or the backend to run them on.
        pool_path: The pool a selection came from (to substitute a posture that cannot
            be reached); None: the one the selection records, if it is still there.
        csv: Also write a CSV of the points beside the route (``<name>.<hash>.csv``, replaced with it).
        from_posture: Where the robot stands (nj,) rad, in the scene's joint order: the route
            starts there and returns there (recorded in the summary as
            ``start_posture_rad``). None: the reference posture.

    The seed, the plan, its robot model and the outputs' place are checked before any
    planning; the output is locked while it is made.

    Raises:
        PosegenError: Bad seed, bad or empty plan, another robot model, an output that
            cannot be written, or no posture reachable.

    """
    check_seed(seed, "--seed")
    path = Path(output)
    if path.suffix.lower() not in ROUTE_SUFFIXES:
        raise ArgumentError(f"-o {output}: a route file ends in {' or '.join(ROUTE_SUFFIXES)}")
    outputs = route_outputs(path)
    for output_path in outputs:
        check_writable(output_path)
    check_apart(outputs, [plan_path, pool_path, config_path])
    plan, entries = load_plan(plan_path)
    plan, entries, repeated = _without_repeats(plan, entries, plan_path)
    scene = scene_for(plan.provenance, config_path)
    scene.check_made_for(plan.provenance, plan_path)
    plan.check_joints(scene.joint_names, plan_path)
    plan.check_limits(scene.joint_names, scene.lower, scene.upper, plan_path)
    substitutes, pool_entries, repair = _substitutes(scene, plan, entries, plan_path, pool_path)
    with claim_output(path, beside=outputs[1:]):
        progress(Progress(0, 2 * len(plan.postures) + 1, "job"))
        start = time.perf_counter()
        route = plan_route(scene, plan.postures, seed, workers, substitutes, progress, from_posture)
        elapsed = time.perf_counter() - start
        n = len(entries)
        nodes = {i: entries[i] for i in range(n)}
        nodes.update({n + r: {"pool_id": r, **pool_entries[r]} for r in (s.substitute for s in route.substitutions)})
        summary = _summary(scene, route, len(plan.postures))
        summary["repair"] = repair  # where a lost posture's substitute would come from, or why none could
        if from_posture is not None:
            summary["start_posture_rad"] = [float(v) for v in from_posture]
        if repeated:
            summary["repeated"] = repeated  # postures of the input given twice: routed once
        if substitutes is not None and route.substitutions:
            rows = [r for v in route.visited if (r := substitutes.row(v, n)) is not None]
            summary["information"] = o1_figures(substitutes, rows)
        provenance = dict(plan.provenance)
        provenance.update(
            {
                "seed": seed,
                "selection": plan_path,
                "selection_sha256": hashlib.sha256(Path(plan_path).read_bytes()).hexdigest(),
            }
        )
        written = write_route(path, route, route_header(route, nodes, provenance, summary), csv)
    return Routed(route=route, summary=summary, written=tuple(written), planning_s=elapsed, repair=repair)


def _without_repeats(
    plan: Pool, entries: list[dict[str, Any]], plan_path: str
) -> tuple[Pool, list[dict[str, Any]], list[dict[str, int]]]:
    """The plan without the postures it holds twice (same chain, same joints), each one said.

    Returns:
        The plan and its entries, first occurrences kept; and each repeat as
        ``{posture, same_as}`` (indices in the input).

    """
    first: dict[tuple[str, tuple[float, ...]], int] = {}
    keep, repeated = [], []
    for k, posture in enumerate(plan.postures):
        seen = first.setdefault((posture.chain, posture.joints), k)
        if seen == k:
            keep.append(k)
        else:
            repeated.append({"posture": k, "same_as": seen})
            LOG.warning("%s: posture %d repeats posture %d (same chain and joints): routed once", plan_path, k, seen)
    if not repeated:
        return plan, entries, []
    postures = tuple(plan.postures[k] for k in keep)
    return dataclasses.replace(plan, postures=postures), [entries[k] for k in keep], repeated


def _substitutes(
    scene: Scene, plan: Pool, entries: list[dict[str, Any]], plan_path: str, pool_path: str | None
) -> tuple[Substitutes | None, list[dict[str, Any]], str]:
    """The pool a selection came from, if it can be found; and a word on what a repair can use."""
    if not all("pool_id" in e for e in entries):
        return None, [], "no repair: the input is a pool, not a selection"
    recorded = plan.provenance.get("pool")
    path = Path(pool_path) if pool_path else (Path(recorded) if recorded else None)
    if path is None or not path.exists():
        return None, [], f"no repair: the selection's pool {path} is not there (give it with --pool)"
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    expected = plan.provenance.get("pool_sha256")
    if expected and digest != expected:
        if pool_path:
            raise InputError(f"{path}: sha256 differs from the pool the selection {plan_path} was made from")
        return None, [], f"no repair: {path} changed since the selection was made (sha256 differs)"
    pool, pool_entries = load_plan(path)
    pool.check_joints(scene.joint_names, str(path))
    chains = [p.chain for p in pool.postures]

    def design() -> Design:
        return build_design(scene, pool.joints(), chains)[0]

    rows = tuple(int(e["pool_id"]) if 0 <= int(e["pool_id"]) < len(pool.postures) else None for e in entries)
    return Substitutes(pool.postures, rows, design), pool_entries, f"repair from {path}"


def _summary(scene: Scene, route: Route, postures: int) -> dict[str, Any]:
    """The figures a route file records (no wall time: the same seed gives the same file)."""
    per_contact = []  # from leaving the previous contact (or the start) to leaving this one
    previous_end = 0.0
    for seg in route.segments:
        if seg.type == SegmentType.HOLD:
            end = float(route.times[seg.last])
            per_contact.append(end - previous_end)
            previous_end = end
    by_type: dict[str, float] = {}
    for seg in route.segments:
        by_type[seg.type.value] = by_type.get(seg.type.value, 0.0) + float(
            route.times[seg.last] - route.times[seg.first]
        )
    visited = len(route.visited)
    methods: dict[str, int] = {}
    for method in route.methods:
        methods[method] = methods.get(method, 0) + 1
    return {
        "postures": postures,
        "routed": visited,
        "substituted": len(route.substitutions),
        "skipped": len(route.skipped),
        "points": len(route.times),
        "duration_s": float(route.times[-1]),
        "robot_time_per_contact_s": float(route.times[-1]) / max(visited, 1),
        "robot_time_per_contact_median_s": statistics.median(per_contact) if per_contact else 0.0,
        "robot_time_by_segment_s": by_type,
        "returns_to_start": route.returns,
        "free_motions": methods,
        "tsp_length_s": route.order.length_s,
        "nearest_neighbour_length_s": route.order.nearest_neighbour_s,
    }


def check_route_file(
    path: str,
    config_path: str | None,
    progress: ProgressCallback = ignore_progress,
    workers: int | Backend = 1,
    min_dt: float = MIN_DT_S,
) -> Verification:
    """Re-verify every point of a route file from its joint angles, on the robot's meshes.

    Args:
        path: Route file (YAML or JSON header; its ``.npz`` beside it).
        config_path: Scene config; None: the one saved in the route.
        progress: Told as points are checked.
        workers: Local processes checking collisions, or the backend to run them on.
        min_dt: Smallest allowed time step, s.

    Raises:
        PosegenError: Not a route, arrays missing or not the header's, or a route made
            for another robot model.

    """
    check_size(min_dt, "--min-dt", positive=True)
    data = read_route(path)
    recorded = data.get("provenance") or {}
    scene = scene_for(recorded, config_path)
    scene.check_made_for(recorded, path)
    result = verify_route(scene, data, min_dt, workers, progress)
    return dataclasses.replace(result, geometry=geometry_coverage(scene))


@dataclass(frozen=True)
class Exported:
    """What ``posegen export --bag`` wrote."""

    bag: Path
    messages: int
    segments: int
    points: int


def export_route_bag(route_path: str, bag: str, topic: str, segments_topic: str) -> Exported:
    """Write a route file as a rosbag2 (MCAP): its trajectory per segment and whole, and its segment table.

    Args:
        route_path: Route file.
        bag: Bag directory to write (a bag already there is replaced; anything else is kept).
        topic: ``trajectory_msgs/JointTrajectory`` topic (a trajectory controller's command topic).
        segments_topic: ``diagnostic_msgs/DiagnosticArray`` topic of the segment table.

    Raises:
        PosegenError: Not a route, or the destination is not a bag.

    """
    check_writable(bag, OutputKind.FOLDER)
    check_apart([bag], [route_path])
    check_bag_destination(bag)
    data = read_route(route_path)
    times, positions, velocities, accelerations = route_arrays(data, route_path)
    rows = [
        SegmentRow(
            type=str(s["type"]),
            chain=s.get("chain"),
            posture=s.get("posture"),
            pool_id=s.get("pool_id"),
            first_point=int(s["first_point"]),
            last_point=int(s["last_point"]),
            start_s=float(times[int(s["first_point"])]),
            end_s=float(times[int(s["last_point"])]),
        )
        for s in data["segments"]
    ]
    provenance = dict(data.get("provenance") or {})
    provenance.update({"route": route_path, "route_sha256": hashlib.sha256(Path(route_path).read_bytes()).hexdigest()})
    names = data["trajectory"]["joint_names"]
    with claim_output(bag, OutputKind.FOLDER):
        count = write_trajectory_bag(
            bag, names, times, (positions, velocities, accelerations), rows, topic, segments_topic, provenance
        )
    return Exported(bag=Path(bag), messages=count, segments=len(rows), points=len(times))
