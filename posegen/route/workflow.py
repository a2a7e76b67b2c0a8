"""The route stage's commands, from files to files: ``posegen route``, ``posegen check ROUTE``, ``posegen export``."""

from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from posegen.io import SegmentRow, write_trajectory_bag
from posegen.progress import Progress, ProgressCallback, ignore_progress
from posegen.robot import Verification, load_plan, read_route, route_arrays, scene_for
from posegen.route.check import verify_route
from posegen.route.export import route_to_dict, write_route
from posegen.route.motion import seed_planner
from posegen.route.route import Route, plan_route


@dataclass(frozen=True)
class Routed:
    """What ``posegen route`` planned and wrote."""

    route: Route
    summary: dict[str, Any]  # the figures recorded in the route file
    csv_path: Path  # the CSV written beside the route file
    planning_s: float  # wall time of the planning


def route_plan_file(
    plan_path: str, output: str, seed: int, config_path: str | None, progress: ProgressCallback = ignore_progress
) -> Routed:
    """Plan, time and export a trajectory through the postures of a selection (or pool) file.

    Args:
        plan_path: Selection or pool file.
        output: Route file, ``.yaml`` or ``.json``; a ``.csv`` is written beside it.
        seed: Seed of the ordering and of OMPL (seeded once per process).
        config_path: Scene config; None: the one saved in the plan.
        progress: Told after each posture.

    Raises:
        PosegenError: Bad or empty plan, another robot model, or no posture reachable.

    """
    plan, entries = load_plan(plan_path)
    scene = scene_for(plan.provenance, config_path)
    scene.check_made_for(plan.provenance, plan_path)
    plan.check_joints(scene.joint_names, plan_path)
    seed_planner(seed)
    progress(Progress(0, len(plan.postures), "posture"))
    start = time.perf_counter()
    route = plan_route(scene, plan.postures, seed, progress)
    elapsed = time.perf_counter() - start
    visited = len(route.visited)
    summary = {
        "postures": len(plan.postures),
        "routed": visited,
        "skipped": len(route.skipped),
        "points": len(route.times),
        "duration_s": float(route.times[-1]),
        "robot_time_per_contact_s": float(route.times[-1]) / max(visited, 1),
        "tsp_length_s": route.order.length_s,
        "nearest_neighbour_length_s": route.order.nearest_neighbour_s,
    }
    provenance = dict(plan.provenance)
    provenance.update(
        {
            "seed": seed,
            "selection": plan_path,
            "selection_sha256": hashlib.sha256(Path(plan_path).read_bytes()).hexdigest(),
        }
    )
    csv_path = write_route(Path(output), route_to_dict(route, entries, provenance, summary))
    return Routed(route=route, summary=summary, csv_path=csv_path, planning_s=elapsed)


def check_route_file(path: str, config_path: str | None, progress: ProgressCallback = ignore_progress) -> Verification:
    """Re-verify every point of a route file from its joint angles, on the robot's meshes.

    Args:
        path: Route file (YAML or JSON).
        config_path: Scene config; None: the one saved in the route.
        progress: Told after each point.

    Raises:
        PosegenError: Not a route, or a route made for another robot model.

    """
    data = read_route(path)
    recorded = data.get("provenance") or {}
    scene = scene_for(recorded, config_path)
    scene.check_made_for(recorded, path)
    progress(Progress(0, len(data["trajectory"]["points"]), "point"))
    return verify_route(scene, data, progress)


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
    data = read_route(route_path)
    times, positions, velocities, accelerations = route_arrays(data)
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
    count = write_trajectory_bag(
        bag, names, times, (positions, velocities, accelerations), rows, topic, segments_topic, provenance
    )
    return Exported(bag=Path(bag), messages=count, segments=len(rows), points=len(times))
