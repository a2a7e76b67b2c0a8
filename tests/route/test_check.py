"""``posegen check ROUTE``: each defect a controller would choke on fails with a message that names it.

What no reader accepts (non-finite values, times, counts, segment table) is refused by
the one reader, :func:`posegen.io.read_route`, check included; check adds the robot's
names and the physics.
"""

import shutil

import numpy as np
import pytest
import yaml

from posegen.errors import InputError
from posegen.io import (
    ROUTE_ARRAYS,
    SegmentType,
    encode_arrays,
    read_arrays,
    read_route,
    write_route,
    write_with_arrays,
)
from posegen.route import PoseInvariant, RouteInvariant, plan_route, route_artefact, verify_route

ROWS = [4, 5]


@pytest.fixture(scope="module")
def route_file(scene, example_pool, tmp_path_factory):
    postures = [example_pool.postures[i] for i in ROWS]
    route = plan_route(scene, postures, seed=0)
    entries = {i: example_pool.to_dict()["postures"][r] for i, r in enumerate(ROWS)}
    path = tmp_path_factory.mktemp("good") / "route.yaml"
    write_route(path, route_artefact(route, entries, dict(example_pool.provenance), {}))
    return path


def corrupted(route_file, tmp_path, edit_arrays=None, edit_header=None):
    """A copy of the route with edited arrays and header; the header's hash is updated (a consistent file)."""
    path = tmp_path / "route.yaml"
    shutil.copy(route_file, path)
    header = yaml.safe_load(route_file.read_text())
    arrays = {k: v.copy() for k, v in read_arrays(route_file, header["arrays"], ROUTE_ARRAYS).items()}
    if edit_arrays:
        edit_arrays(arrays, header)
    if edit_header:
        edit_header(header)
    del header["arrays"]
    write_with_arrays(path, header, arrays, compress=True)
    return path


def verdict(scene, path, **kwargs):
    result = verify_route(scene, read_route(path), **kwargs)
    return result, {w.invariant: w for w in result.worst}


def a_free_point(header):
    seg = next(s for s in header["segments"] if s["type"] == SegmentType.FREE.value)
    return (seg["first_point"] + seg["last_point"]) // 2


def test_the_planned_route_passes(scene, route_file):
    result, _ = verdict(scene, route_file)
    assert result.ok


def test_a_step_below_the_minimum(scene, route_file):
    result, worst = verdict(scene, route_file, min_dt=1.0)
    assert not result.ok and "minimum 1.000e+00 s" in worst[RouteInvariant.TIMES].detail


def test_a_renamed_joint(scene, route_file, tmp_path):
    def edit(header):
        header["trajectory"]["joint_names"][15] = "arm_left_2_joint_renamed"

    route = read_route(corrupted(route_file, tmp_path, edit_header=edit))  # a name: any reader takes it
    message = "joint 15 'arm_left_2_joint_renamed' is not a joint of the robot model .'arm_left_2_joint' here"
    with pytest.raises(InputError, match=message):
        verify_route(scene, route)  # not this robot's: nothing can be checked


def test_a_dropped_point(scene, route_file, tmp_path):
    def edit(arrays, header):
        k = a_free_point(header)
        for name in arrays:
            arrays[name] = np.delete(arrays[name], k, axis=0)

    with pytest.raises(InputError, match=r"holds \d+ rows, the header declares \d+"):
        read_route(corrupted(route_file, tmp_path, edit))  # every reader refuses it, check included


def test_arrays_larger_than_declared_are_refused_before_they_are_read(route_file, tmp_path):
    """A small sidecar deflating to many points (the 9.6 MB file of 4 M points) is refused from its headers."""

    def edit(arrays, header):
        m = 2_000_000
        arrays["time_from_start"] = np.zeros(m)
        for name in ROUTE_ARRAYS[1:]:
            arrays[name] = np.zeros((m, arrays[name].shape[1]), dtype=np.float32)

    path = corrupted(route_file, tmp_path, edit)
    assert sum(f.stat().st_size for f in tmp_path.glob("route.yaml.*.npz")) < 1e6  # deflate: ~1 kB per MB of zeros
    with pytest.raises(InputError, match=r"holds 2000000 rows, the header declares"):
        read_route(path)


@pytest.mark.parametrize(
    ("edit_header", "message"),
    [
        (lambda h: h.update(format_version=3), "format_version 3: this posegen reads versions 1 and 2"),
        (lambda h: h["segments"][1].update(start_s=float("nan")), "segment times must be finite"),
        (lambda h: h["trajectory"].update(points=-1), "trajectory.points must be the number of points, not -1"),
        (lambda h: h["trajectory"]["joint_names"].__setitem__(1, h["trajectory"]["joint_names"][0]), "named twice"),
        (lambda h: h["segments"][1].update(type="crawl"), r"segments\[1\]\.type must be one of free, .*, not 'crawl'"),
        (lambda h: h["segments"][1].update(pool_id="17"), r"segments\[1\]\.pool_id must be an index \(a whole number"),
        (lambda h: h.update(skipped={"posture": 1}), "skipped must be a list of mappings"),
    ],
    ids=[
        "format_version 3",
        "NaN segment time",
        "negative point count",
        "a joint named twice",
        "unknown segment type",
        "pool_id a string",
        "skipped not a list",
    ],
)
def test_headers_no_reader_accepts(route_file, tmp_path, edit_header, message):
    with pytest.raises(InputError, match=message):
        read_route(corrupted(route_file, tmp_path, edit_header=edit_header))


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda a, h: a["time_from_start"].__setitem__(5, np.nan), "time_from_start at point 5 is not a finite"),
        (lambda a, h: a["time_from_start"].__setitem__(-1, 1e39), r"end within 1e\+06 s"),
        (lambda a, h: a["time_from_start"].__setitem__(5, a["time_from_start"][4]), "increase by at least"),
        (lambda a, h: a["time_from_start"].__setitem__(5, a["time_from_start"][3]), "increase by at least"),
        (lambda a, h: a["positions"].__setitem__((3, 2), np.nan), "positions at point 3 is not a finite"),
        (lambda a, h: a["velocities"].__setitem__((3, 2), np.inf), "velocities at point 3 is not a finite"),
        (lambda a, h: a["velocities"].__setitem__((3, 2), np.nan), "velocities at point 3 is not a finite"),
        (lambda a, h: a["time_from_start"].__setitem__(-1, np.nan), "time_from_start at point .* is not a finite"),
        (lambda a, h: h.update(segments=[]), "the segment table is empty"),
        (lambda a, h: h["segments"].pop(), "the segments end at point"),
    ],
    ids=[
        "NaN time",
        "last time 1e39",
        "repeated time",
        "reversed time",
        "NaN position",
        "inf velocity",
        "NaN velocity",
        "NaN last time",
        "no segment",
        "a segment missing",
    ],
)
def test_the_reader_refuses_what_no_controller_can_run(route_file, tmp_path, edit, message):
    """check, export, simulate --bag, measure --route and view read routes through read_route: one set of rules."""
    with pytest.raises(InputError, match=message):
        read_route(corrupted(route_file, tmp_path, edit))


def test_positions_jumping_between_two_points(scene, route_file, tmp_path):
    def edit(arrays, header):
        k = a_free_point(header)
        arrays["positions"][k, 16] += 0.05  # one joint, one point: 3 degrees off the path

    result, worst = verdict(scene, corrupted(route_file, tmp_path, edit))
    assert not result.ok
    consistency = worst[RouteInvariant.CONSISTENCY]
    assert consistency.violations == 2  # into the point and out of it
    assert "arm_left_3_joint" in consistency.detail and "mean velocity" in consistency.detail


def test_a_sidecar_that_is_not_the_headers(route_file, tmp_path):
    path = tmp_path / "route.yaml"
    shutil.copy(route_file, path)
    arrays = read_arrays(route_file, yaml.safe_load(route_file.read_text())["arrays"], ROUTE_ARRAYS)
    arrays["positions"][0, 0] += 1e-3
    sidecar = tmp_path / yaml.safe_load(path.read_text())["arrays"]["file"]
    sidecar.write_bytes(encode_arrays(arrays, compress=True))
    with pytest.raises(InputError, match="sha256"):
        read_route(path)
    sidecar.unlink()
    with pytest.raises(InputError, match="cannot read its arrays"):
        read_route(path)


def test_a_moving_hold(scene, route_file, tmp_path):
    def edit(arrays, header):
        seg = next(s for s in header["segments"] if s["type"] == SegmentType.HOLD.value)
        arrays["velocities"][seg["last_point"], 18] = 1e-3

    result, worst = verdict(scene, corrupted(route_file, tmp_path, edit))
    assert not result.ok and "must be at rest" in worst[RouteInvariant.REST].detail


def test_a_version_1_route_with_inline_points_is_still_read_and_checked(scene, route_file, tmp_path):
    from posegen.io import stamp

    read = read_route(route_file)
    times, positions, velocities, accelerations = read.times, read.positions, read.velocities, read.accelerations
    header = yaml.safe_load(route_file.read_text())
    header["format_version"] = 1
    del header["arrays"]
    header["trajectory"]["points"] = [
        {
            "positions": positions[k].tolist(),
            "velocities": velocities[k].tolist(),
            "accelerations": accelerations[k].tolist(),
            "effort": [],
            "time_from_start": stamp(float(times[k])),
        }
        for k in range(len(times))
    ]
    old = tmp_path / "old.yaml"
    old.write_text(yaml.safe_dump(header, sort_keys=False))
    result = verify_route(scene, read_route(old))
    assert result.ok and result.checked == len(times)


def test_joints_in_another_order_are_checked_in_the_models(scene, route_file, tmp_path):
    order = None

    def edit(arrays, header):
        nonlocal order
        order = list(range(len(header["trajectory"]["joint_names"])))[::-1]
        header["trajectory"]["joint_names"] = [header["trajectory"]["joint_names"][i] for i in order]
        for name in ("positions", "velocities", "accelerations"):
            arrays[name] = arrays[name][:, order]

    result, _ = verdict(scene, corrupted(route_file, tmp_path, edit))
    assert result.ok


def test_a_missing_joint(scene, route_file, tmp_path):
    def edit(arrays, header):
        del header["trajectory"]["joint_names"][31]
        for name in ("positions", "velocities", "accelerations"):
            arrays[name] = arrays[name][:, :31]

    with pytest.raises(InputError, match="the robot model's joint 'head_2_joint' is missing"):
        verify_route(scene, read_route(corrupted(route_file, tmp_path, edit)))


def test_a_contact_on_a_chain_the_robot_lacks(scene, route_file, tmp_path):
    def edit(header):
        next(s for s in header["segments"] if s["type"] == SegmentType.HOLD.value)["chain"] = "tail"

    with pytest.raises(InputError, match=r"segment \d+ \(hold\) names chain 'tail'"):
        verify_route(scene, read_route(corrupted(route_file, tmp_path, edit_header=edit)))


def test_a_knee_inside_its_own_margin(config, route_file):
    """``margins.joint_limit_rad_by_joint``: a joint closer to a limit than its own margin fails, named with it."""
    import dataclasses

    from posegen.robot import Scene

    route = read_route(route_file)
    knee = "leg_right_4_joint"
    closest = float(np.min(route.positions[:, list(route.joint_names).index(knee)]))  # rad, its lower limit is 0
    margins = dict(config.margins.joint_limit_rad_by_joint, **{knee: closest + 0.05})
    strict_margins = dataclasses.replace(config.margins, joint_limit_rad_by_joint=margins)
    strict = Scene(dataclasses.replace(config, margins=strict_margins))
    result = verify_route(strict, route)
    limits = {w.invariant: w for w in result.worst}[RouteInvariant.JOINT_LIMITS]
    assert not result.ok and limits.violations > 0
    assert knee in limits.detail and f"margin {closest + 0.05:g} rad" in limits.detail


def test_a_route_run_three_times_faster_asks_its_legs_for_more_than_they_have(scene, route_file, tmp_path):
    """Planned: every torque at speed (flat feet) within its allowed ratio; three times faster, not."""
    from posegen.route.load_check import LoadInvariant

    _, planned = verdict(scene, route_file)
    assert planned[LoadInvariant.TORQUE_AT_SPEED].violations == 0

    def faster(arrays, header):
        arrays["time_from_start"] /= 3.0
        arrays["velocities"] *= 3.0
        arrays["accelerations"] *= 9.0
        for seg in header["segments"]:
            seg["start_s"], seg["end_s"] = seg["start_s"] / 3.0, seg["end_s"] / 3.0

    result, worst = verdict(scene, corrupted(route_file, tmp_path, faster))
    at_speed = worst[LoadInvariant.TORQUE_AT_SPEED]
    assert not result.ok and at_speed.violations > 0
    assert "x its effort limit at speed (flat feet)" in at_speed.detail


def test_a_free_motion_that_comes_down_to_the_table(scene, route_file, tmp_path):
    """An approach relabelled free: its last points are 1 cm above the table, below the free motions' clearance."""

    def edit(header):
        seg = next(s for s in header["segments"] if s["type"] == SegmentType.APPROACH.value)
        seg.update(type=SegmentType.FREE.value, chain=None)

    clearance = scene.margins.table_clearance_m
    assert clearance > scene.route.pre_contact_m  # TALOS's config
    result, worst = verdict(scene, corrupted(route_file, tmp_path, edit_header=edit))
    collision = worst[PoseInvariant.COLLISION]
    assert not result.ok and collision.violations > 0
    assert "table" in collision.detail and f"{clearance} m from the table (meshes)" in collision.detail
    good, worst = verdict(scene, route_file)
    assert good.ok and f"free motions {clearance} m above the table" in worst[PoseInvariant.COLLISION].detail


def test_a_table_margin_below_the_collision_margin_is_judged_as_the_checker_found_it(scene, example_pool):
    """The table's pairs keep the larger margin (:meth:`CollisionChecker.pair_margins`), in the reported excess too."""
    from posegen.robot import TABLE
    from posegen.route.pose_check import _collisions, _meshes

    state = _meshes(scene.config)
    joints = np.array(example_pool.postures[0].joints)  # a hand on the table
    margin, table = 0.004, 0.001
    hits = state[1].colliding_pairs(scene.configuration(joints), None, margin, table)  # no chain: fingertips count
    assert any(TABLE in hit.pair for hit in hits) and all(hit.margin_m == margin for hit in hits)
    [(excess, detail)] = _collisions(state, (joints[None], [None], np.array([margin]), np.array([table])))
    nearest = hits[0]
    assert TABLE in nearest.pair and nearest.pair[0] in detail
    assert excess == pytest.approx(margin - nearest.distance_m, abs=1e-9)  # not table - distance: 3 mm less
