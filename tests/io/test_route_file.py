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
    first = next(s.chain for s in route.segments if s.type.in_contact)  # the first contact segment is named
    with pytest.raises(InputError, match=rf"names chain '{first}'; valid: \['nowhere'\]"):
        route.check_chains(["nowhere"])


def _with_sidecar_arrays(route_file, folder, change):
    """A copy of the route whose sidecar's arrays are ``change(arrays)``, its header naming the new sidecar's hash."""
    header = yaml.safe_load(route_file.read_text())
    arrays = dict(np.load(route_file.parent / header["arrays"]["file"]))
    change(arrays)
    sidecar = folder / "route.npz"
    np.savez(sidecar, **arrays)
    header["arrays"] = {"file": sidecar.name, "sha256": hashlib.sha256(sidecar.read_bytes()).hexdigest()}
    path = folder / "route.yaml"
    path.write_text(yaml.safe_dump(header, sort_keys=False))
    return path


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda a: a.update(positions=a["positions"].astype(complex)), "positions holds complex128 values"),
        (lambda a: a.update(velocities=a["velocities"].astype(str)), "velocities holds <U"),
        (lambda a: a.update(positions=np.round(a["positions"]).astype(np.int64)), "positions holds int64 values"),
        (lambda a: a.update(accelerations=a["accelerations"] != 0), "accelerations holds bool values"),
        (lambda a: a["positions"].__setitem__((3, 2), 1e30), "positions at point 3 holds 1e\\+30: beyond"),
        (lambda a: a["velocities"].__setitem__((4, 1), -1e30), "velocities at point 4 holds 1e\\+30: beyond"),
        (lambda a: a.update(positions=a["positions"].astype(float)) or a["positions"].__setitem__((5, 0), 1e39),
         "positions at point 5 holds 1e\\+39"),
    ],
)  # fmt: skip
def test_sidecar_arrays_of_other_kinds_or_no_joint_s_values_are_refused(change, message, route_file, tmp_path):
    path = _with_sidecar_arrays(route_file, tmp_path, change)
    with pytest.raises(InputError, match=message):
        read_route(path)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda h: h["segments"][0].update(first_point=[1]), r"segments\[0\]\.first_point must be an index"),
        (lambda h: h["trajectory"].update(joint_names=5), r"trajectory\.joint_names must be a list of joint names"),
        (lambda h: h.update(segments={"a": 1}), r"segments must be a list of segments"),
        (lambda h: h["trajectory"].update(points=-1), r"trajectory\.points must be the number of points, not -1"),
        (lambda h: h["segments"][2].update(type="fly"), r"segments\[2\]\.type must be one of free, "),
    ],
)
def test_a_malformed_header_names_the_field_and_what_it_expects(edit, message, route_file, tmp_path):
    header = yaml.safe_load(route_file.read_text())
    edit(header)
    path = tmp_path / "route.yaml"
    path.write_text(yaml.safe_dump(header, sort_keys=False))
    for sidecar in sidecars_of(route_file):
        (tmp_path / sidecar.name).write_bytes(sidecar.read_bytes())
    with pytest.raises(InputError, match=message) as error:
        read_route(path)
    assert "TypeError" not in str(error.value) and "expected -1" not in str(error.value)
