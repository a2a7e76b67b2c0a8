"""The route stage's commands, from files to files: ``posegen route``, ``posegen check ROUTE``, ``posegen export``."""

from __future__ import annotations

import dataclasses
import hashlib
import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from posegen.arguments import check_seed, check_size
from posegen.errors import ArgumentError, InputError
from posegen.io import (
    OutputKind,
    Pool,
    check_apart,
    check_bag_destination,
    check_topics,
    check_writable,
    claim_output,
    load_postures,
    read_route,
    route_outputs,
    write_route,
    write_trajectory_bag,
)
from posegen.model import Design, build_design
from posegen.parallel import Backend
from posegen.progress import Progress, ProgressCallback, ignore_progress
from posegen.robot import Scene, Verification, geometry_coverage, scene_for, scene_for_postures
from posegen.route.check import MIN_DT_S, verify_route
from posegen.route.export import route_artefact
from posegen.route.repair import Substitutes, o1_figures
from posegen.route.route import PlannedRoute, plan_route
from posegen.route.summary import RouteSummary, summarize

LOG = logging.getLogger(__name__)

ROUTE_SUFFIXES = (".yaml", ".yml", ".json")


@dataclass(frozen=True)
class Routed:
    """What ``posegen route`` planned and wrote."""

    route: PlannedRoute
    summary: RouteSummary  # the figures recorded in the route file
    written: tuple[Path, ...]  # the route file, its arrays (and the CSV if asked)
    planning_s: float  # wall time of the planning
    repair: str  # how a lost posture would be repaired: from which pool, or why not


def route_postures_file(
    postures_path: str,
    output: str,
    seed: int = 0,
    config_path: str | None = None,
    progress: ProgressCallback = ignore_progress,
    *,
    workers: int | Backend = 1,
    pool_path: str | None = None,
    csv: bool = False,
    from_posture: Sequence[float] | None = None,
    held_rows: Sequence[int] = (),
) -> Routed:
    """Plan, time and export a trajectory through the postures of a selection (or pool) file.

    Args:
        postures_path: Selection or pool file.
        output: Route file, ``.yaml`` or ``.json``; its arrays go to ``.npz`` beside it.
        seed: Seed of the ordering, of OMPL's streams and of the shortcuts.
        config_path: Scene config; None: the one saved in the postures file.
        progress: Told after each planning job.
        workers: Local worker processes planning the route's segments, or the backend to run them on.
        pool_path: The pool a selection came from (to substitute a posture that cannot
            be reached); None: the one the selection records, if it is still there.
        csv: Also write a CSV of the points beside the route (``<name>.<hash>.csv``, replaced with it).
        from_posture: Where the robot stands (nj,) rad, in the scene's joint order: the route
            starts there and returns there (recorded in the summary as
            ``start_posture_rad``). None: the reference posture.
        held_rows: Pool rows a repair must not route in place of a lost posture (a session's
            earlier batches held them already).

    The seed, the postures file, its robot model and the outputs' place are checked before any
    planning; the output is locked while it is made.

    Raises:
        PosegenError: Bad seed, a bad or empty postures file, another robot model, an output that
            cannot be written, or no posture reachable.

    """
    check_seed(seed, "seed")
    path = Path(output)
    if path.suffix.lower() not in ROUTE_SUFFIXES:
        raise ArgumentError(f"output={output}: a route file ends in {' or '.join(ROUTE_SUFFIXES)}", parameter="output")
    outputs = route_outputs(path)
    for output_path in outputs:
        check_writable(output_path)
    check_apart(outputs, [postures_path, pool_path, config_path])
    chosen, entries = load_postures(postures_path)
    chosen, entries, repeated = _without_repeats(chosen, entries, postures_path)
    scene = scene_for_postures(chosen, postures_path, config_path)
    substitutes, pool_entries, repair = _substitutes(scene, chosen, entries, postures_path, pool_path, held_rows)
    with claim_output(path, beside=outputs[1:]):
        progress(Progress(0, 2 * len(chosen.postures) + 1, "job"))
        start = time.perf_counter()
        route = plan_route(scene, chosen.postures, seed, workers, substitutes, progress, from_posture)
        elapsed = time.perf_counter() - start
        n = len(entries)
        nodes = {i: entries[i] for i in range(n)}
        nodes.update({n + r: {"pool_id": r, **pool_entries[r]} for r in (s.substitute for s in route.substitutions)})
        information = None
        if substitutes is not None and route.substitutions:
            rows = [r for v in route.visited if (r := substitutes.row(v, n)) is not None]
            information = o1_figures(substitutes, rows)
        summary = summarize(route, len(chosen.postures), repair, from_posture, repeated, information)
        provenance = dict(chosen.provenance)
        provenance.update(
            {
                "seed": seed,
                "selection": postures_path,
                "selection_sha256": hashlib.sha256(Path(postures_path).read_bytes()).hexdigest(),
            }
        )
        written = write_route(path, route_artefact(route, nodes, provenance, summary.to_dict()), csv)
    return Routed(route=route, summary=summary, written=tuple(written), planning_s=elapsed, repair=repair)


def _without_repeats(
    chosen: Pool, entries: list[dict[str, Any]], postures_path: str
) -> tuple[Pool, list[dict[str, Any]], list[dict[str, int]]]:
    """The postures without those held twice (same chain, same joints), each one said.

    Returns:
        The postures and their entries, first occurrences kept; and each repeat as
        ``{posture, same_as}`` (indices in the input).

    """
    first: dict[tuple[str, tuple[float, ...]], int] = {}
    keep, repeated = [], []
    for k, posture in enumerate(chosen.postures):
        seen = first.setdefault((posture.chain, posture.joints), k)
        if seen == k:
            keep.append(k)
        else:
            repeated.append({"posture": k, "same_as": seen})
            LOG.warning(
                "%s: posture %d repeats posture %d (same chain and joints): routed once", postures_path, k, seen
            )
    if not repeated:
        return chosen, entries, []
    postures = tuple(chosen.postures[k] for k in keep)
    return dataclasses.replace(chosen, postures=postures), [entries[k] for k in keep], repeated


def _substitutes(
    scene: Scene,
    chosen: Pool,
    entries: list[dict[str, Any]],
    postures_path: str,
    pool_path: str | None,
    held_rows: Sequence[int],
) -> tuple[Substitutes | None, list[dict[str, Any]], str]:
    """The pool a selection came from, if it can be found; and a word on what a repair can use."""
    if not all("pool_id" in e for e in entries):
        return None, [], "no repair: the input is a pool, not a selection"
    for k, entry in enumerate(entries):
        if isinstance(entry["pool_id"], bool) or not isinstance(entry["pool_id"], int):
            raise InputError(f"{postures_path}: posture {k}: pool_id {entry['pool_id']!r} is not a posture number")
    recorded = chosen.provenance.get("pool")
    if recorded is not None and not isinstance(recorded, str):
        raise InputError(f"{postures_path}: provenance.pool {recorded!r} is not a path")
    path = Path(pool_path) if pool_path else (Path(recorded) if recorded else None)
    if path is None or not path.is_file():
        return None, [], f"no repair: the selection's pool {path} is not there (give it with --pool)"
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    expected = chosen.provenance.get("pool_sha256")
    if expected and digest != expected:
        if pool_path:
            raise InputError(f"{path}: sha256 differs from the pool the selection {postures_path} was made from")
        return None, [], f"no repair: {path} changed since the selection was made (sha256 differs)"
    pool, pool_entries = load_postures(path)
    pool.check_joints(scene.joint_names, str(path))
    chains = [p.chain for p in pool.postures]

    def design() -> Design:
        return build_design(scene, pool.joints(), chains)[0]

    rows = tuple(int(e["pool_id"]) if 0 <= int(e["pool_id"]) < len(pool.postures) else None for e in entries)
    held = frozenset(int(r) for r in held_rows)
    return Substitutes(pool.postures, rows, design, held), pool_entries, f"repair from {path}"


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
    check_size(min_dt, "min_dt", positive=True)
    route = read_route(path)
    scene = scene_for(route.provenance, config_path)
    scene.check_made_for(route.provenance, path)
    result = verify_route(scene, route, min_dt, workers, progress, where=path)
    return dataclasses.replace(result, geometry=geometry_coverage(scene))


@dataclass(frozen=True)
class Exported:
    """What ``posegen export --bag`` wrote."""

    bag: Path
    messages: int
    segments: int
    points: int


def export_route_bag(
    route_path: str, bag: str, topic: str, segments_topic: str, config_path: str | None = None
) -> Exported:
    """Write a route file as a rosbag2 (MCAP): its trajectory per segment and whole, and its segment table.

    Args:
        route_path: Route file.
        bag: Bag directory to write (a bag posegen wrote there is replaced; a recording, or a
            folder holding anything else, is refused and kept).
        topic: ``trajectory_msgs/JointTrajectory`` topic (a trajectory controller's command topic).
        segments_topic: ``diagnostic_msgs/DiagnosticArray`` topic of the segment table.
        config_path: Scene config; None: the one saved in the route.

    The route is read as ``check`` reads it: its joints are the robot model's (each once, in
    any order) and every contact segment names one of the config's chains.

    Raises:
        PosegenError: Not a route, one of another robot or of names the robot lacks, topics
            that are no ROS 2 names or one name twice, or a destination that is not posegen's bag.

    """
    check_topics({"topic": topic, "segments_topic": segments_topic})
    check_writable(bag, OutputKind.FOLDER)
    check_apart([bag], [route_path, config_path])
    check_bag_destination(bag)
    route = read_route(route_path)
    scene = scene_for(route.provenance, config_path)
    scene.check_made_for(route.provenance, route_path)
    route.joint_columns(scene.joint_names, route_path)
    route.check_chains([c.name for c in scene.config.chains], route_path)
    provenance = dict(route.provenance)
    provenance.update({"route": route_path, "route_sha256": hashlib.sha256(Path(route_path).read_bytes()).hexdigest()})
    arrays = (route.positions, route.velocities, route.accelerations)
    with claim_output(bag, OutputKind.FOLDER):
        count = write_trajectory_bag(
            bag, route.joint_names, route.times, arrays, route.segments, topic, segments_topic, provenance
        )
    return Exported(bag=Path(bag), messages=count, segments=len(route.segments), points=len(route.times))
