"""The typed route file: what the route stage writes reads back as the same object, and writes back the same bytes."""

import dataclasses
import hashlib
import json

import numpy as np
import pytest
import yaml

from posegen.errors import InputError
from posegen.io import Route, SegmentType, read_route, sidecars_of, write_route


def same_route(a: Route, b: Route) -> None:
    for field in dataclasses.fields(Route):
        x, y = getattr(a, field.name), getattr(b, field.name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and np.array_equal(x, y), field.name
        else:
            assert x == y, field.name


def test_a_route_read_and_written_again_is_the_same_file(route_file, tmp_path):
    route = read_route(route_file)
    again = tmp_path / "route.yaml"
    written = write_route(again, route, csv_too=True)
    assert again.read_bytes() == route_file.read_bytes()  # every field kept, in the header's order
    assert [p.read_bytes() for p in sidecars_of(again)] == [p.read_bytes() for p in sidecars_of(route_file)]
    csv = again.with_name(f"route.yaml.{hashlib.sha256(again.read_bytes()).hexdigest()[:12]}.csv")  # its companion
    assert written == [again, sidecars_of(again)[0], csv] and csv.is_file()
    same_route(read_route(again), route)


def test_the_header_and_the_object_agree(route_file):
    route = read_route(route_file)
    header = yaml.safe_load(route_file.read_text())
    assert route.joint_names == tuple(header["trajectory"]["joint_names"])
    assert len(route.times) == header["trajectory"]["points"] and route.format_version == 2
    assert route.provenance == header["provenance"] and route.summary == header["summary"]
    for segment, row in zip(route.segments, header["segments"], strict=True):
        assert segment.type == SegmentType(row["type"]) and (segment.chain, segment.pool_id) == (
            row["chain"],
            row["pool_id"],
        )
        assert (segment.first_point, segment.last_point, segment.start_s) == (
            row["first_point"],
            row["last_point"],
            row["start_s"],
        )
    assert route.hold_pool_rows() == tuple(r["pool_id"] for r in header["segments"] if r["type"] == "hold")
    assert route.stored_dtype == np.float32


def test_a_json_header_reads_as_the_yaml_one(route_file, tmp_path):
    route = read_route(route_file)
    as_json = tmp_path / "route.json"
    write_route(as_json, route)
    assert json.loads(as_json.read_text())["format"] == "posegen-route"
    same_route(read_route(as_json), route)


def test_joint_columns_put_the_robot_order_and_name_what_is_wrong(route_file):
    route = read_route(route_file)
    names = route.joint_names
    assert route.joint_columns(names[::-1]) == list(range(len(names)))[::-1]
    with pytest.raises(InputError, match=r"r\.yaml: the robot model's joint 'extra' is missing"):
        route.joint_columns((*names, "extra"), "r.yaml")
    with pytest.raises(InputError, match=f"joint 0 '{names[0]}' is not a joint of the robot model"):
        route.joint_columns(names[1:])
    chains = sorted({s.chain for s in route.segments if s.type.in_contact and s.chain})
    route.check_chains(chains)
    with pytest.raises(InputError, match=rf"names chain '{chains[0]}'; valid: \['nowhere'\]"):
        route.check_chains(["nowhere"])
