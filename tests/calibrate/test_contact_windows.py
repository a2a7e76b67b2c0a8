"""Contact windows on synthetic sessions whose contacts, pauses and faults are known."""

import dataclasses

import numpy as np
import pytest

from posegen.calibrate.contact_windows import (
    PlannedContact,
    find_windows,
    joint_speed,
    match_windows,
    still_shares,
    wrist_force,
)
from posegen.robot import RecordingConfig

RATE = 500.0
SETTINGS = RecordingConfig()


def synthetic(holds, n_joints=6, noise=1e-4, seed=0):
    """Move between postures (2 s), hold each (3 s, pressing from 0.5 s after the stop); forces by wrist.

    ``holds``: per contact, (planned arm, wrists pressed: "left", "right" or "left+right", press time
    in s, drift of the held posture in rad/s).
    """
    rng = np.random.default_rng(seed)
    targets = rng.uniform(-1, 1, (len(holds), n_joints))
    times = np.arange(int(5 * len(holds) * RATE)) / RATE
    positions = np.zeros((len(times), n_joints))
    forces = {"left": np.zeros(len(times)), "right": np.zeros(len(times))}
    previous = np.zeros(n_joints)
    for k, (_, wrists, press, drift) in enumerate(holds):
        start = 5.0 * k
        move = (times >= start) & (times < start + 2)
        s = (times[move] - start) / 2
        positions[move] = previous + (s * s * (3 - 2 * s))[:, None] * (targets[k] - previous)
        hold = (times >= start + 2) & (times < start + 5)
        positions[hold] = targets[k] + drift * (times[hold] - start - 2)[:, None]
        for name in wrists.split("+"):
            forces[name][(times >= start + 2.5) & (times < start + 2.5 + press)] = 40.0
        previous = targets[k]
    positions += rng.normal(0, noise, positions.shape)
    planned = [PlannedContact(chain, f"p{k}", targets[k]) for k, (chain, _, _, _) in enumerate(holds)]
    return times, positions, forces, planned, targets


CLEAN = [("left", "left", 2.0, 0), ("right", "right", 2.0, 0), ("left", "left", 2.0, 0)]


def windows_of(times, positions, forces, planned):
    """Find the windows, then match them to the route's contacts (when given)."""
    windows, rejected = find_windows(times, positions, forces, SETTINGS)
    if planned is not None:
        heights = None if forces is not None else [0.0] * len(windows)
        windows = match_windows(windows, planned, SETTINGS.match_tolerance_rad, rejected, heights)
    return windows, rejected


def test_clean_contacts_are_found_and_averaged():
    times, positions, forces, planned, targets = synthetic(CLEAN)
    windows, rejected = windows_of(times, positions, forces, planned)
    assert rejected == []
    assert [w.label for w in windows] == ["p0", "p1", "p2"] and [w.chain for w in windows] == ["left", "right", "left"]
    for window, target in zip(windows, targets, strict=True):
        assert np.abs(window.joints - target).max() < 5 * 1e-4 / np.sqrt(window.samples) * 3
        assert window.start_s == pytest.approx(times[np.searchsorted(times, 2.5 + 5 * int(window.label[1:]))], abs=0.01)
        assert window.force_n == pytest.approx(40.0)
    alone, rejected = windows_of(times, positions, forces, None)  # without the route: the wrist names the arm
    assert [w.chain for w in alone] == ["left", "right", "left"] and rejected == []


def test_faulty_windows_are_reported_with_their_time_and_left_out():
    holds = [
        ("left", "left", 2.0, 0),
        ("right", "right", 0.3, 0),  # too short
        ("left", "left", 2.0, 0.01),  # the arm slips slowly (still by speed): too noisy
        ("right", "left+right", 2.0, 0),  # both wrists: ambiguous
        ("right", "left", 2.0, 0),  # the force on the wrist the route does not name
    ]
    times, positions, forces, planned, _ = synthetic(holds)
    windows, rejected = windows_of(times, positions, forces, planned)
    assert [w.label for w in windows] == ["p0"]
    reasons = [(round(r.start_s, 1), r.reason) for r in rejected]
    assert reasons[0] == (7.5, "too short (0.30 s)")
    assert reasons[1][0] == 12.5 and reasons[1][1].startswith("too noisy")
    assert reasons[2] == (17.5, "force on left and right wrist")
    assert reasons[3] == (22.5, "force on the left wrist; the route has the right arm at p4")
    assert len(reasons) == 4


def test_joint_speed_alone_needs_the_route():
    times, positions, _, planned, _ = synthetic(CLEAN[:2])
    windows, rejected = windows_of(times, positions, None, planned)
    assert [(w.label, w.chain) for w in windows] == [("p0", "left"), ("p1", "right")]
    assert np.isnan(windows[0].force_n) and rejected == []  # stops at other postures are pauses, not reported


def test_windows_out_of_route_order_or_repeated_are_left_out():
    times, positions, forces, planned, _ = synthetic(CLEAN)
    swapped = [planned[1], planned[0], planned[2]]  # the route said p1 first; the robot went to p0 first
    windows, rejected = windows_of(times, positions, forces, swapped)
    assert [w.label for w in windows] == ["p0", "p2"]
    assert [r.reason for r in rejected] == ["out of route order (p1 after p0)"]
    forces["left"][(times >= 3.3) & (times < 3.6)] = 0.0  # the first contact lets go and presses again
    windows, rejected = windows_of(times, positions, forces, planned)
    assert [w.label for w in windows] == ["p1", "p2"]
    assert [r.reason for r in rejected] == ["one of 2 windows at p0", "one of 2 windows at p0"]


def test_speed_and_force_signals():
    times = np.arange(1000) / RATE
    positions = np.column_stack([0.3 * times, np.zeros(1000)])
    assert np.allclose(joint_speed(times, positions, 0.04), 0.3)
    forces = np.tile([1.0, 2.0, 3.0], (1000, 1))
    forces[400:600, 2] += 30.0
    magnitude = wrist_force(times, times, forces)
    assert np.allclose(magnitude[400:600], 30.0) and np.allclose(magnitude[:400], 0.0)  # offset removed


def test_without_force_the_lowest_window_at_a_contact_is_the_contact():
    from posegen.calibrate.contact_windows import Window

    posture = np.zeros(3)
    planned = [PlannedContact("left", "p0", posture)]

    def still(start, offset):
        return Window(start, start + 1.0, "", "", posture + offset, 500, 1e-4, float("nan"))

    windows = [still(1.0, 0.03), still(3.0, 0.0), still(5.0, 0.03)]  # approach pause, hold, approach pause
    rejected = []
    accepted = match_windows(windows, planned, SETTINGS.match_tolerance_rad, rejected, heights=[0.73, 0.68, 0.73])
    assert [w.start_s for w in accepted] == [3.0] and accepted[0].chain == "left"
    assert [r.reason for r in rejected] == ["a pause 5.0 cm above the contact window at p0"] * 2


def test_a_stabilized_hold_beyond_the_tolerance_holds_its_unambiguous_contact():
    from posegen.calibrate.contact_windows import Window

    planned = [
        PlannedContact("left", "p0", np.zeros(3)),
        PlannedContact("right", "p1", np.array([1.0, 0.0, 0.0])),
        PlannedContact("left", "p2", np.array([0.0, 1.0, 0.0])),
    ]

    def held(start, chain, joints):
        return Window(start, start + 1.0, chain, "", np.array(joints), 500, 1e-4, 30.0)

    windows = [
        held(1.0, "left", [0.0, 0.0, 0.25]),  # p0, its legs 0.25 rad off: the others are >= 1 rad away
        held(3.0, "right", [0.75, 0.0, 0.2]),  # p1, 0.25 rad off against p0's 0.75: within the ratio
        held(5.0, "left", [0.0, 0.45, 0.0]),  # between p0 and p2: ambiguous
        held(7.0, "right", [0.0, 0.95, 0.2]),  # near p2, but with force on the other wrist
    ]
    reasons = [
        "holds no route contact (nearest: p0, 0.250 rad away)",
        "holds no route contact (nearest: p1, 0.250 rad away)",
        "holds no route contact (nearest: p0, 0.450 rad away)",
        "holds no route contact (nearest: p2, 0.200 rad away)",
    ]
    strict: list = []
    assert match_windows(windows, planned, SETTINGS.match_tolerance_rad, strict, ratio=0.0) == []
    assert [r.reason for r in strict] == reasons
    rejected: list = []
    accepted = match_windows(windows, planned, SETTINGS.match_tolerance_rad, rejected, ratio=SETTINGS.match_ratio)
    assert [(w.label, w.chain, w.start_s) for w in accepted] == [("p0", "left", 1.0), ("p1", "right", 3.0)]
    assert [r.reason for r in rejected] == reasons[2:]


def test_the_shares_of_still_and_pressed_samples_explain_a_recording_without_windows():
    times, positions, forces, _, _ = synthetic(CLEAN)  # per contact 5 s: 3 s still, pressed 2 s of them
    assert still_shares(times, positions, forces, SETTINGS) == (
        "the joints still in 60% of the samples (their speed over recording.speed_span_s 0.04 s below "
        "recording.speed_threshold_rad_s), a wrist above recording.force_threshold_n in 40%, both at once in 40%"
    )
    narrow = dataclasses.replace(SETTINGS, speed_span_s=1e-6)  # one sample period: the encoder noise is a speed
    assert find_windows(times, positions, forces, narrow)[0] == []
    assert still_shares(times, positions, None, narrow).startswith("the joints still in 0% of the samples")
