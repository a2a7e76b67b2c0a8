"""``physics.yaml``: what a physics rehearsal measured, per route segment, as a typed object with its reader and writer.

Written in the bag's folder beside ``truth.yaml``. Every figure is the simulator's ground
truth (no controller reads it): the ZMP's margin inside the soles' support polygon, each
sole's slip on the floor since the route started, the free base's height against the
plan's, the largest joint torque over its effort limit, each hand's normal force on the
table, and every contact of another robot link with the floor or the table.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from posegen.errors import InputError
from posegen.io import read_yaml, write_yaml

PHYSICS_FORMAT = "posegen-physics"
PHYSICS_VERSION = 1
PHYSICS_FILE = "physics.yaml"


@dataclass(frozen=True)
class UnwantedContact:
    """A robot link that touched the floor or the table (other than the soles and the tips)."""

    time_s: float  # on the run's clock (the recording's)
    link: str
    obstacle: str  # floor or table
    depth_mm: float


@dataclass(frozen=True)
class SegmentFigures:
    """The ground truth of one route segment."""

    index: int
    type: str  # the route segment's type (free, approach, go_to_contact, hold, release)
    chain: str | None
    label: str  # posture 3 (pool 17), or "" for a free motion
    start_s: float  # route time
    end_s: float
    zmp_margin_min_m: float  # the ZMP's smallest margin inside the support polygon (negative: outside)
    slip_max_mm: tuple[float, ...]  # each sole's largest horizontal displacement since the route started
    pelvis_deviation_max_m: float  # the largest |base height - planned base height|
    torque_ratio_max: float  # the largest |joint torque| / effort limit
    torque_joint: str  # where
    force_min_n: float  # the chain's normal force on the table (0 without a chain)
    force_max_n: float
    unwanted: tuple[UnwantedContact, ...] = ()


@dataclass(frozen=True)
class PhysicsSummary:
    """The whole run's worst figures and what it achieved."""

    completed: bool  # the route ran to its end without a fall
    fell_at_s: float | None  # the fall's time on the run's clock (the recording's), if any
    duration_s: float  # robot time simulated
    contacts: int  # the route's contacts
    holds_in_range: int  # contacts whose hold force stayed within the range below
    hold_range_n: tuple[float, float]
    zmp_margin_min_m: float
    slip_max_mm: float
    pelvis_deviation_max_m: float
    torque_ratio_max: float
    torque_joint: str
    unwanted_contacts: int


@dataclass(frozen=True)
class PhysicsReport:
    """``physics.yaml``: the run's settings, its summary and its segments."""

    provenance: Mapping[str, Any]
    summary: PhysicsSummary
    segments: tuple[SegmentFigures, ...] = field(default_factory=tuple)


def _finite(value: float) -> float | None:
    return None if not math.isfinite(value) else round(float(value), 6)


def physics_to_dict(report: PhysicsReport) -> dict[str, Any]:
    """Plain data of ``physics.yaml`` (non-finite figures as null)."""

    def plain(item: Any) -> Any:
        if isinstance(item, float):
            return _finite(item)
        if isinstance(item, (list, tuple)):
            return [plain(v) for v in item]
        if isinstance(item, dict):
            return {k: plain(v) for k, v in item.items()}
        return item

    return {
        "format": PHYSICS_FORMAT,
        "format_version": PHYSICS_VERSION,
        "provenance": dict(report.provenance),
        "summary": plain(asdict(report.summary)),
        "route_segments": [plain(asdict(s)) for s in report.segments],
    }


def write_physics(path: str | Path, report: PhysicsReport) -> None:
    """Write ``physics.yaml`` atomically.

    Example:
        >>> write_physics("plans/physics_bag/physics.yaml", report)

    """
    write_yaml(path, physics_to_dict(report))


def _number(value: Any) -> float:
    return math.nan if value is None else float(value)


def _segment(entry: dict[str, Any]) -> SegmentFigures:
    unwanted = tuple(
        UnwantedContact(float(u["time_s"]), str(u["link"]), str(u["obstacle"]), float(u["depth_mm"]))
        for u in entry.get("unwanted") or ()
    )
    return SegmentFigures(
        index=int(entry["index"]),
        type=str(entry["type"]),
        chain=None if entry.get("chain") is None else str(entry["chain"]),
        label=str(entry.get("label") or ""),
        start_s=float(entry["start_s"]),
        end_s=float(entry["end_s"]),
        zmp_margin_min_m=_number(entry.get("zmp_margin_min_m")),
        slip_max_mm=tuple(_number(v) for v in entry.get("slip_max_mm") or ()),
        pelvis_deviation_max_m=_number(entry.get("pelvis_deviation_max_m")),
        torque_ratio_max=_number(entry.get("torque_ratio_max")),
        torque_joint=str(entry.get("torque_joint") or ""),
        force_min_n=_number(entry.get("force_min_n")),
        force_max_n=_number(entry.get("force_max_n")),
        unwanted=unwanted,
    )


def read_physics(path: str | Path) -> PhysicsReport:
    """Read ``physics.yaml``.

    Raises:
        InputError: Not a physics report, another version, or a malformed one.

    Example:
        >>> read_physics("plans/physics_bag/physics.yaml").summary.completed
        True

    """
    data = read_yaml(path, PHYSICS_FORMAT)
    if data.get("format_version") != PHYSICS_VERSION:
        raise InputError(f"{path}: physics report version {data.get('format_version')!r}, expected {PHYSICS_VERSION}")
    try:
        s = data["summary"]
        fell = s.get("fell_at_s")
        summary = PhysicsSummary(
            completed=bool(s["completed"]),
            fell_at_s=None if fell is None else float(fell),
            duration_s=float(s["duration_s"]),
            contacts=int(s["contacts"]),
            holds_in_range=int(s["holds_in_range"]),
            hold_range_n=(float(s["hold_range_n"][0]), float(s["hold_range_n"][1])),
            zmp_margin_min_m=_number(s.get("zmp_margin_min_m")),
            slip_max_mm=_number(s.get("slip_max_mm")),
            pelvis_deviation_max_m=_number(s.get("pelvis_deviation_max_m")),
            torque_ratio_max=_number(s.get("torque_ratio_max")),
            torque_joint=str(s.get("torque_joint") or ""),
            unwanted_contacts=int(s["unwanted_contacts"]),
        )
        segments = tuple(_segment(e) for e in data.get("route_segments") or ())
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise InputError(f"{path}: malformed physics report ({type(exc).__name__}: {exc})") from None
    return PhysicsReport(dict(data.get("provenance") or {}), summary, segments)
