"""The figures a route file records about its route (``summary``), as one typed object.

No wall time: the same seed gives the same file. Written into the route file's header
as plain data (:meth:`RouteSummary.to_dict`, keys in this order; the optional ones only
when set), and printed by ``posegen route``.
"""

from __future__ import annotations

import statistics
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from posegen.io import SegmentType
from posegen.route.route import PlannedRoute


@dataclass(frozen=True)
class RouteSummary:
    """What ``posegen route`` planned, in figures."""

    postures: int  # postures of the input (repeats routed once)
    routed: int  # postures touched
    substituted: int  # postures replaced by a pool posture
    skipped: int  # postures lost, with no substitute
    points: int
    duration_s: float  # robot time of the whole route
    robot_time_per_contact_s: float  # mean
    robot_time_per_contact_median_s: float  # from leaving the previous contact (or the start) to leaving this one
    robot_time_by_segment_s: dict[str, float]  # by segment type
    returns_to_start: bool
    free_motions: dict[str, int]  # how each transfer's free motion was found: count by method
    tsp_length_s: float  # the visiting order's length, rest-to-rest times at the free speed
    nearest_neighbour_length_s: float  # the nearest-neighbour order's, for comparison
    repair: str  # where a lost posture's substitute would come from, or why none could
    start_posture_rad: tuple[float, ...] | None = None  # where the robot stood, when given (nj,) rad
    repeated: tuple[dict[str, int], ...] = ()  # postures of the input given twice: {posture, same_as}
    information: dict[str, Any] | None = None  # O1 and rank before and after substitutions

    def to_dict(self) -> dict[str, Any]:
        """Plain data, as the route file records it."""
        data: dict[str, Any] = {
            "postures": self.postures,
            "routed": self.routed,
            "substituted": self.substituted,
            "skipped": self.skipped,
            "points": self.points,
            "duration_s": self.duration_s,
            "robot_time_per_contact_s": self.robot_time_per_contact_s,
            "robot_time_per_contact_median_s": self.robot_time_per_contact_median_s,
            "robot_time_by_segment_s": dict(self.robot_time_by_segment_s),
            "returns_to_start": self.returns_to_start,
            "free_motions": dict(self.free_motions),
            "tsp_length_s": self.tsp_length_s,
            "nearest_neighbour_length_s": self.nearest_neighbour_length_s,
            "repair": self.repair,
        }
        if self.start_posture_rad is not None:
            data["start_posture_rad"] = list(self.start_posture_rad)
        if self.repeated:
            data["repeated"] = [dict(r) for r in self.repeated]
        if self.information is not None:
            data["information"] = self.information
        return data


def summarize(
    route: PlannedRoute,
    postures: int,
    repair: str,
    from_posture: Sequence[float] | None = None,
    repeated: Sequence[dict[str, int]] = (),
    information: dict[str, Any] | None = None,
) -> RouteSummary:
    """The figures of a planned route.

    Args:
        route: The timed route.
        postures: How many postures the input held (repeats routed once).
        repair: Where a lost posture's substitute would come from, or why none could.
        from_posture: Where the robot stood (nj,) rad, when given.
        repeated: The input's repeated postures, ``{posture, same_as}``.
        information: O1 and rank before and after substitutions, when any.

    """
    per_contact = []  # from leaving the previous contact (or the start) to leaving this one
    previous_end = 0.0
    for seg in route.segments:
        if seg.type == SegmentType.HOLD:
            per_contact.append(seg.end_s - previous_end)
            previous_end = seg.end_s
    by_type: dict[str, float] = {}
    for seg in route.segments:
        by_type[seg.type.value] = by_type.get(seg.type.value, 0.0) + float(
            route.times[seg.last_point] - route.times[seg.first_point]
        )
    visited = len(route.visited)
    methods: dict[str, int] = {}
    for method in route.methods:
        methods[method] = methods.get(method, 0) + 1
    return RouteSummary(
        postures=postures,
        routed=visited,
        substituted=len(route.substitutions),
        skipped=len(route.skipped),
        points=len(route.times),
        duration_s=float(route.times[-1]),
        robot_time_per_contact_s=float(route.times[-1]) / max(visited, 1),
        robot_time_per_contact_median_s=statistics.median(per_contact) if per_contact else 0.0,
        robot_time_by_segment_s=by_type,
        returns_to_start=route.returns,
        free_motions=methods,
        tsp_length_s=route.order.length_s,
        nearest_neighbour_length_s=route.order.nearest_neighbour_s,
        repair=repair,
        start_posture_rad=None if from_posture is None else tuple(float(v) for v in from_posture),
        repeated=tuple(repeated),
        information=information,
    )
