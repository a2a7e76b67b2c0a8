"""A planned route as the typed route file (:class:`posegen.io.Route`): its points as stored, its segment table.

The file format, its reader and its writer are in :mod:`posegen.io` (below the stages, so
that any of them may read a route); here the planner's :class:`~posegen.route.route.PlannedRoute`
becomes the artefact: pool rows numbered, postures, skips and substitutions as plain data.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from posegen.io import Route, stored_arrays
from posegen.route.route import PlannedRoute

CSV_SUFFIX = ".csv"  # a route's CSV: ``<name>.<sha256 prefix of the header>.csv``


def route_arrays_of(route: PlannedRoute) -> dict[str, np.ndarray]:
    """The sidecar's arrays of a planned route, in their stored types and resolutions."""
    return stored_arrays(route.times, route.positions, route.velocities, route.accelerations)


def route_artefact(
    route: PlannedRoute,
    entries: dict[int, dict[str, Any]],
    provenance: dict[str, Any],
    summary: dict[str, Any],
) -> Route:
    """The route file of a planned route: its points as stored (float64 copies), every posture numbered.

    Args:
        route: The timed route.
        entries: The plain data (selection or pool entry) of every node the route
            mentions (visited, skipped, substituted), by node.
        provenance: Provenance block.
        summary: Figures to record.

    """

    def pool_id(node: int | None) -> int | None:
        if node is None:
            return None
        entry = entries[node]
        return int(entry.get("pool_id", entry.get("id", node)))

    stored = route_arrays_of(route)
    times, positions, velocities, accelerations = (np.array(a, dtype=float, order="C") for a in stored.values())
    return Route(
        joint_names=tuple(route.joint_names),
        times=times,
        positions=positions,
        velocities=velocities,
        accelerations=accelerations,
        segments=tuple(dataclasses.replace(s, pool_id=pool_id(s.posture)) for s in route.segments),
        provenance=provenance,
        postures=tuple(entries[i] for i in route.visited),
        skipped=tuple({"posture": i, "pool_id": pool_id(i), "reason": reason} for i, reason in route.skipped),
        substitutions=tuple(
            {
                "posture": s.lost,
                "pool_id": pool_id(s.lost),
                "reason": s.reason,
                "substitute_pool_id": s.substitute,
                "log_det_gain": s.gain,
                "o1_before": s.o1_before,
                "o1_after": s.o1_after,
                "rank_before": s.rank_before,
                "rank_after": s.rank_after,
            }
            for s in route.substitutions
        ),
        summary=summary,
    )
