"""A run's ground truth reduced to the figures of ``physics.yaml``: per route segment, and the worst of the run."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from posegen.io import Route, SegmentType
from posegen.physics.contact_control import ContactTimes
from posegen.physics.monitor import Truth
from posegen.physics.physics_file import PhysicsReport, PhysicsSummary, SegmentFigures, UnwantedContact
from posegen.physics.plan import Plan
from posegen.robot import FloatArray


def hold_range_n(force_n: float) -> tuple[float, float]:
    """The normal forces (N) a hold of target ``force_n`` should stay within: a third of it to twice it.

    Example:
        >>> hold_range_n(30.0)
        (10.0, 60.0)

    """
    return force_n / 3.0, 2.0 * force_n


def _label(route: Route, index: int) -> str:
    segment = route.segments[index]
    if segment.posture is None:
        return ""
    return f"posture {segment.posture}" + ("" if segment.pool_id is None else f" (pool {segment.pool_id})")


def _worst(values: FloatArray, low: bool) -> float:
    finite = values[np.isfinite(values)]
    if not len(finite):
        return float("nan")
    return float(finite.min() if low else finite.max())


def segment_figures(
    route: Route, plan: Plan, truth: Truth, route_index: NDArray[np.int64], joint_names: tuple[str, ...]
) -> tuple[SegmentFigures, ...]:
    """The figures of each route segment the run reached (route times; samples at the control rate).

    Args:
        route: The route that was run.
        plan: Its sampled plan (``route_start_s`` before the route's time 0).
        truth: The run's ground truth, one entry per sample run.
        route_index: (n,) the plan's sample each sample ran (the route's clock waits for the contacts).
        joint_names: The scene's joints (names the worst torque's joint).

    """
    period = float(plan.times_s[1] - plan.times_s[0])
    route_time = plan.times_s[route_index] - plan.route_start_s  # (n,)
    started = np.flatnonzero(route_time >= 0.0)
    origin = truth.soles_xy[started[0] if len(started) else 0]
    slip = np.linalg.norm(truth.soles_xy - origin, axis=2) * 1e3  # (n, 2) mm
    pelvis = np.abs(truth.pelvis_z - plan.pelvis_z[route_index])
    out = []
    for k, segment in enumerate(route.segments):
        rows = np.flatnonzero((route_time >= segment.start_s - 1e-9) & (route_time <= segment.end_s + 1e-9))
        if not len(rows):
            break
        force = truth.contact_force[segment.chain][rows] if segment.chain in truth.contact_force else np.zeros(1)
        worst = rows[int(np.argmax(truth.torque_ratio[rows]))]
        touched = tuple(
            UnwantedContact(round(t.time_s, 3), t.link, t.obstacle, round(1e3 * t.depth_m, 3))
            for t in truth.touches
            if rows[0] <= round(t.time_s / period) <= rows[-1]
        )
        out.append(
            SegmentFigures(
                index=k,
                type=segment.type.value,
                chain=segment.chain,
                label=_label(route, k),
                start_s=float(segment.start_s),
                end_s=float(segment.end_s),
                zmp_margin_min_m=_worst(truth.zmp_margin[rows], low=True),
                slip_max_mm=tuple(float(v) for v in slip[rows].max(axis=0)),
                pelvis_deviation_max_m=_worst(pelvis[rows], low=False),
                torque_ratio_max=_worst(truth.torque_ratio[rows], low=False),
                torque_joint=joint_names[int(truth.worst_joint[worst])],
                force_min_n=float(force.min()),
                force_max_n=float(force.max()),
                unwanted=touched,
            )
        )
    return tuple(out)


def summarize(
    segments: tuple[SegmentFigures, ...],
    contacts: tuple[ContactTimes, ...],
    fell_at_s: float | None,
    duration_s: float,
    force_n: float,
) -> PhysicsSummary:
    """The run's worst figures, and how many holds kept their force within :func:`hold_range_n` of ``force_n``."""
    holds = [s for s in segments if s.type == SegmentType.HOLD.value]
    low, high = hold_range_n(force_n)
    in_range = sum(1 for s in holds if s.force_min_n >= low and s.force_max_n <= high)
    worst_torque = max(segments, key=lambda s: s.torque_ratio_max if np.isfinite(s.torque_ratio_max) else -1.0)
    return PhysicsSummary(
        completed=fell_at_s is None,
        fell_at_s=fell_at_s,
        duration_s=duration_s,
        contacts=len(contacts),
        holds_in_range=in_range,
        hold_range_n=(low, high),
        zmp_margin_min_m=_worst(np.array([s.zmp_margin_min_m for s in segments]), low=True),
        slip_max_mm=_worst(np.array([max(s.slip_max_mm) for s in segments]), low=False),
        pelvis_deviation_max_m=_worst(np.array([s.pelvis_deviation_max_m for s in segments]), low=False),
        torque_ratio_max=worst_torque.torque_ratio_max,
        torque_joint=worst_torque.torque_joint,
        unwanted_contacts=sum(len(s.unwanted) for s in segments),
    )


def physics_report(
    provenance: Mapping[str, Any],
    route: Route,
    plan: Plan,
    truth: Truth,
    route_index: NDArray[np.int64],
    joint_names: tuple[str, ...],
    contacts: tuple[ContactTimes, ...],
    fell_at_s: float | None,
    force_n: float,
) -> PhysicsReport:
    """The report of a run (``physics.yaml``); a fall's time is given on the run's clock.

    ``force_n``: the holds' target force (``route.contact_force_n``), which sets their range.

    Example:
        >>> report = physics_report(prov, route, plan, result.truth, result.route_index, names, contacts, None, 30.0)

    """
    segments = segment_figures(route, plan, truth, route_index, joint_names)
    fell = None if fell_at_s is None else round(fell_at_s, 3)
    duration = float(len(truth.pelvis_z) * (plan.times_s[1] - plan.times_s[0]))
    return PhysicsReport(provenance, summarize(segments, contacts, fell, duration, force_n), segments)
