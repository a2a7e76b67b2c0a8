"""A route's summary: the figures ``posegen route`` prints and the route file records, re-derived from the file."""

import dataclasses

import pytest

from posegen.io import SegmentType, read_route
from posegen.route import RouteSummary

BASE_KEYS = [f.name for f in dataclasses.fields(RouteSummary)][:14]


def test_the_recorded_figures_agree_with_the_points(route_file):
    route = read_route(route_file)
    summary = RouteSummary(**route.summary)  # every recorded key is a field, and the file holds no other
    assert list(route.summary) == BASE_KEYS  # in the fields' order; the optional ones absent when unset
    holds = [s for s in route.segments if s.type == SegmentType.HOLD]
    assert summary.routed == len(holds) and summary.points == len(route.times)
    assert summary.duration_s == route.times[-1]
    assert sum(summary.robot_time_by_segment_s.values()) == pytest.approx(summary.duration_s)
    assert summary.robot_time_per_contact_s == pytest.approx(summary.duration_s / len(holds))
    assert summary.to_dict() == route.summary


def test_optional_figures_follow_the_base_ones_when_set(route_file):
    summary = RouteSummary(**read_route(route_file).summary)
    given = dataclasses.replace(summary, start_posture_rad=(0.5, -0.25), repeated=({"posture": 3, "same_as": 1},))
    data = given.to_dict()
    assert list(data) == [*BASE_KEYS, "start_posture_rad", "repeated"]
    assert data["start_posture_rad"] == [0.5, -0.25] and data["repeated"] == [{"posture": 3, "same_as": 1}]
