"""A run's summary: a hold is in range relative to the config's target force."""

from __future__ import annotations

import pytest

from posegen.physics.figures import hold_range_n, summarize
from posegen.physics.physics_file import SegmentFigures


def _hold(index: int, low_n: float, high_n: float) -> SegmentFigures:
    return SegmentFigures(
        index,
        "hold",
        "left",
        f"posture {index}",
        float(index),
        index + 1.0,
        0.02,
        (0.1, 0.1),
        0.001,
        0.5,
        "j",
        low_n,
        high_n,
        (),
    )


def test_a_hold_is_in_range_from_a_third_to_twice_its_target() -> None:
    holds = (_hold(0, 8.0, 9.0), _hold(1, 25.0, 31.0), _hold(2, 35.0, 65.0))
    talos = summarize(holds, (), None, 10.0, 30.0)
    assert talos.hold_range_n == (10.0, 60.0) and talos.holds_in_range == 1  # the issue's [10, 60] N at 30 N
    light = summarize(holds, (), None, 10.0, 10.0)  # a light touch (iCub's 10 N)
    assert light.hold_range_n == pytest.approx((10.0 / 3.0, 20.0)) and light.holds_in_range == 1  # the 8-9 N hold
    assert hold_range_n(30.0) == (10.0, 60.0)
