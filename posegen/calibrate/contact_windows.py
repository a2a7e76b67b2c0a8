"""Static contact windows in a recorded session.

A contact is held where the wrist force exceeds a threshold while every joint is still
(the criterion of the paper's force controller), for at least a minimum time. Without a
wrench topic the joints' stillness alone marks candidate windows, and the route's planned
postures tell contacts from other pauses (a pause that holds no planned posture, or a
stop too short to be a contact, is not reported; of the pauses near one contact, the
contact is the lowest, the others are at its approach posture).

Each window is trimmed at both ends (the force controller settles there) and its joint
angles are averaged. A window is reported, with its times and the reason, and left out
when it is too short, too noisy (a joint varying more than a bound within it), or when
the force is on both wrists. With the route, windows are matched in order to its contacts
by their planned posture (:func:`match_windows`); a window that holds no planned posture,
or several, or one already passed, or one another window also holds, or whose force is on
the other wrist, is reported and left out: never guessed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from posegen.robot import FloatArray, RecordingConfig


@dataclass(frozen=True)
class PlannedContact:
    """A contact of the route, in visiting order."""

    chain: str
    label: str  # e.g. "posture 12 (pool 345)"
    joints: FloatArray  # (nj,) rad, the planned posture, in the recording's joint order


@dataclass(frozen=True)
class Window:
    """A contact window."""

    start_s: float
    end_s: float
    chain: str  # the arm at the table ("" until known, without a wrench topic)
    label: str  # the route contact it holds ("" without the route)
    joints: FloatArray  # (nj,) rad, mean over the trimmed window
    samples: int  # samples averaged
    std_rad: float  # largest joint standard deviation within the trimmed window
    force_n: float  # mean wrist force over the trimmed window (nan without a wrench topic)


@dataclass(frozen=True)
class Rejection:
    """A window left out, and why."""

    start_s: float
    end_s: float
    reason: str


def joint_speed(times: FloatArray, positions: FloatArray, span_s: float, block: int = 1 << 16) -> FloatArray:
    """Largest joint speed (n,) in rad/s, by central differences over ``span_s`` (works without velocities).

    The first and last half spans take the nearest central value. Computed ``block`` rows
    at a time, so that a long recording needs no (n, nj) temporaries.
    """
    n = len(times)
    h = max(1, round(0.5 * span_s * (n - 1) / max(float(times[-1] - times[0]), 1e-12))) if n > 1 else 1
    if n <= 2 * h:
        return np.zeros(n)
    speed = np.empty(n)
    for start in range(h, n - h, block):
        stop = min(start + block, n - h)
        step = np.abs(positions[start + h : stop + h] - positions[start - h : stop - h]).max(axis=1)
        speed[start:stop] = step / np.maximum(times[start + h : stop + h] - times[start - h : stop - h], 1e-12)
    speed[:h], speed[n - h :] = speed[h], speed[n - h - 1]
    return speed


def still_shares(
    times: FloatArray, positions: FloatArray, forces: Mapping[str, FloatArray] | None, settings: RecordingConfig
) -> str:
    """Why a recording may hold no window: the share of samples still, pressed, and both (for a message).

    Args:
        times: (n,) s, increasing.
        positions: (n, nj) rad.
        forces: Per chain, the force magnitude (n,) in N at ``times``; None without a wrench topic.
        settings: Thresholds.

    """
    still = joint_speed(times, positions, settings.speed_span_s) < settings.speed_threshold_rad_s
    shares = (
        f"the joints still in {still.mean():.0%} of the samples (their speed over recording.speed_span_s "
        f"{settings.speed_span_s:g} s below recording.speed_threshold_rad_s)"
    )
    if forces:
        pressed = np.logical_or.reduce([force > settings.force_threshold_n for force in forces.values()])
        shares += (
            f", a wrist above recording.force_threshold_n in {pressed.mean():.0%}, both at once in "
            f"{(still & pressed).mean():.0%}"
        )
    return shares


def wrist_force(times: FloatArray, wrench_times: FloatArray, forces: FloatArray) -> FloatArray:
    """Force magnitude (n,) in N at ``times``, each component's offset (its median over the session) removed."""
    magnitude = np.linalg.norm(forces - np.median(forces, axis=0), axis=1)
    return np.asarray(np.interp(times, wrench_times, magnitude))


def _runs(mask: NDArray[np.bool_], max_gap: int) -> list[tuple[int, int]]:
    """[first, stop) index ranges where ``mask`` holds; interruptions up to ``max_gap`` samples bridged."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    runs: list[tuple[int, int]] = []
    for first, stop in zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist(), strict=True):
        if runs and first - runs[-1][1] <= max_gap:
            runs[-1] = (runs[-1][0], stop)
        else:
            runs.append((first, stop))
    return runs


def find_windows(
    times: FloatArray, positions: FloatArray, forces: Mapping[str, FloatArray] | None, settings: RecordingConfig
) -> tuple[list[Window], list[Rejection]]:
    """Candidate contact windows and the rejected ones, in time order.

    Args:
        times: (n,) s, increasing.
        positions: (n, nj) rad.
        forces: Per chain, the force magnitude (n,) in N at ``times``; None without a wrench topic
            (every still window is a candidate: :func:`match_windows` tells contacts from pauses).
        settings: Thresholds.

    """
    rate = (len(times) - 1) / max(float(times[-1] - times[0]), 1e-12)
    mask = joint_speed(times, positions, settings.speed_span_s) < settings.speed_threshold_rad_s
    pressed = {chain: force > settings.force_threshold_n for chain, force in (forces or {}).items()}
    if pressed:
        mask &= np.logical_or.reduce(list(pressed.values()))
    trim = round(settings.trim_s * rate)
    windows: list[Window] = []
    rejected: list[Rejection] = []
    for first, stop in _runs(mask, round(settings.max_gap_s * rate)):
        start_s, end_s = float(times[first]), float(times[stop - 1])
        if end_s - start_s < settings.min_duration_s or stop - first <= 2 * trim:
            if forces is not None:  # without force, a short stop is a motion's end, not a contact
                rejected.append(Rejection(start_s, end_s, f"too short ({end_s - start_s:.2f} s)"))
            continue
        inner = positions[first + trim : stop - trim]
        std = float(inner.std(axis=0).max())
        chain, force = "", float("nan")
        if forces is not None:
            on = sorted(c for c, p in pressed.items() if np.mean(p[first:stop]) > 0.5)
            if len(on) != 1:
                rejected.append(Rejection(start_s, end_s, f"force on {' and '.join(on) or 'no'} wrist"))
                continue
            chain = on[0]
            force = float(np.mean(forces[chain][first + trim : stop - trim]))
        if std > settings.max_std_rad:
            rejected.append(Rejection(start_s, end_s, f"too noisy (a joint varies by {std:.1e} rad std)"))
            continue
        windows.append(Window(start_s, end_s, chain, "", inner.mean(axis=0), len(inner), std, force))
    return windows, rejected


def _unambiguous(deviation: FloatArray, ratio: float, chain: str, planned: Sequence[PlannedContact]) -> bool:
    """Whether the nearest contact (deviations (m,) rad) is at most ``ratio`` as far as the next, on ``chain``."""
    if ratio <= 0.0 or not chain:
        return False
    order = np.argsort(deviation)
    nearest = int(order[0])
    if planned[nearest].chain != chain:
        return False
    return len(order) == 1 or bool(deviation[nearest] <= ratio * deviation[order[1]])


def match_windows(
    windows: Sequence[Window],
    planned: Sequence[PlannedContact],
    tolerance: float,
    rejected: list[Rejection],
    heights: Sequence[float] | None = None,
    ratio: float = 0.0,
) -> list[Window]:
    """Name each window after the route contact whose planned posture it holds, in route order.

    A window holds a contact when every joint is within ``tolerance`` of its planned
    posture. A stabilized robot holds a contact further from its plan (its legs fitted to
    the floor, its hand to the table): with wrist forces, a window beyond the tolerance
    still holds the contact nearest to it (largest joint deviation) when that contact is
    on the wrist that feels the force and at most ``ratio`` as far as every other contact
    of the route (the postures a route visits lie far apart, so that the nearest is
    unambiguous).

    Args:
        windows: Candidate windows, in time order.
        planned: The route's contacts, in visiting order.
        tolerance: Largest joint deviation (rad) of a window from its planned posture.
        rejected: Where the windows left out are reported (appended, then sorted by time).
        heights: Without a wrench topic, the height (m) of each window's gripper: of the
            still windows near one contact, the contact is the lowest (the others are pauses
            above it, at its approach posture; they are reported). Windows that hold no
            planned posture are then pauses and not reported. None: with wrenches, several
            windows at one contact are all ambiguous.
        ratio: With wrenches, the nearest contact's deviation over the next nearest's below
            which a window beyond the tolerance holds it; 0: the tolerance alone.

    Returns:
        The accepted windows, with the arm and the label of their contact.

    """
    targets = np.array([p.joints for p in planned])  # (m, nj)
    claims: dict[int, list[int]] = {}
    last = -1
    for k, window in enumerate(windows):
        deviation = np.abs(targets - window.joints).max(axis=1)  # (m,)
        near = np.flatnonzero(deviation <= tolerance).tolist()
        if not near and heights is None and _unambiguous(deviation, ratio, window.chain, planned):
            near = [int(np.argmin(deviation))]
        if not near:
            if heights is None:
                best = int(np.argmin(deviation))
                reason = f"holds no route contact (nearest: {planned[best].label}, {deviation[best]:.3f} rad away)"
                rejected.append(Rejection(window.start_s, window.end_s, reason))
        elif len(near) > 1:
            labels = ", ".join(planned[j].label for j in near)
            rejected.append(Rejection(window.start_s, window.end_s, f"holds several route contacts ({labels})"))
        elif near[0] < last:
            reason = f"out of route order ({planned[near[0]].label} after {planned[last].label})"
            rejected.append(Rejection(window.start_s, window.end_s, reason))
        else:
            last = near[0]
            claims.setdefault(last, []).append(k)
    accepted = []
    for index, claimed in sorted(claims.items()):
        contact = planned[index]
        lowest = None if heights is None else min(claimed, key=lambda k: heights[k])
        for k in claimed:
            window = windows[k]
            if lowest is not None and heights is not None and k != lowest:
                above = 100 * (heights[k] - heights[lowest])
                reason = f"a pause {above:.1f} cm above the contact window at {contact.label}"
            elif len(claimed) > 1 and lowest is None:
                reason = f"one of {len(claimed)} windows at {contact.label}"
            elif window.chain and window.chain != contact.chain:
                reason = f"force on the {window.chain} wrist; the route has the {contact.chain} arm at {contact.label}"
            else:
                accepted.append(replace(window, chain=contact.chain, label=contact.label))
                continue
            rejected.append(Rejection(window.start_s, window.end_s, reason))
    rejected.sort(key=lambda r: r.start_s)
    return accepted
