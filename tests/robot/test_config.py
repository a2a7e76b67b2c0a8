import copy

import numpy as np
import pytest
import yaml

from posegen.errors import ConfigError
from posegen.robot import Scene, load_config, parse_config
from posegen.robot.config import read_chains, read_margins, read_sampling, read_source, read_stance, read_table
from posegen.robot.config_reader import Reader
from tests.conftest import CONFIG


def raw():
    return yaml.safe_load(CONFIG.read_text())


def test_default_config_round_trips(config):
    again = parse_config(config.to_dict())
    assert again.to_dict() == config.to_dict()


def test_malformed_yaml_is_a_config_error(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("robot: [unclosed\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_config(bad)


def test_missing_key_names_its_path():
    data = raw()
    del data["table"]["size_m"]
    with pytest.raises(ConfigError, match=r"table\.size_m: missing"):
        parse_config(data)


def test_spot_off_the_table_is_rejected():
    data = raw()
    data["table"]["spots_y_m"] = [0.0, 0.9]
    with pytest.raises(ConfigError, match="spots must lie on the table"):
        parse_config(data)


@pytest.mark.parametrize(
    ("path", "value", "kind"),
    [
        (("chains", "left", "sole_frame"), "left_foot_link", "frame"),
        (("chains", "right", "fingertip_frames"), ["a_link", "b_link", "c_link"], "frame"),
        (("robot", "locked_joints"), {"neck_joint": 0.0}, "joint"),
    ],
)
def test_unknown_names_list_valid_ones(path, value, kind):
    data = copy.deepcopy(raw())
    node = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    with pytest.raises(ConfigError, match=f"unknown {kind} .* valid {kind}s: ") as err:
        Scene(parse_config(data))
    assert "\n" not in str(err.value)


def test_unknown_reference_posture():
    data = raw()
    data["stance"]["reference_posture"] = "crouching"
    with pytest.raises(ConfigError, match="half_sitting"):
        Scene(parse_config(data))


def test_recording_section_and_wrench_topics():
    data = raw()
    config = parse_config(data)
    assert config.recording.force_threshold_n == data["recording"]["force_threshold_n"]
    assert [c.wrench_topic for c in config.chains] == ["/left_wrist_ft", "/right_wrist_ft"]
    del data["recording"]
    del data["chains"]["left"]["wrench_topic"]
    defaults = parse_config(data)
    assert defaults.recording.min_duration_s == 0.5 and defaults.chains[0].wrench_topic == ""
    data["recording"] = {"force_threshold": 3.0}
    with pytest.raises(
        ConfigError, match=r"recording: unknown keys \['force_threshold'\]; valid keys: force_threshold_n"
    ):
        parse_config(data)
    data["recording"] = {"trim_s": -1.0}
    with pytest.raises(ConfigError, match=r"recording\.trim_s: must be >= 0"):
        parse_config(data)
    data["recording"] = {"match_ratio": 1.0}
    with pytest.raises(ConfigError, match=r"recording\.match_ratio: expected a fraction below 1, got 1"):
        parse_config(data)


@pytest.mark.parametrize(
    ("section", "key", "value", "message"),
    [
        ("route", "waypoint_step_rad", 0, r"route\.waypoint_step_rad: must be > 0, got 0"),
        ("route", "acceleration_limit_rad_s2", 0.0, r"route\.acceleration_limit_rad_s2: must be > 0"),
        ("route", "velocity_scale_free", 0, r"route\.velocity_scale_free: must be > 0"),
        ("route", "velocity_scale_contact", 0, r"route\.velocity_scale_contact: must be > 0"),
        ("route", "velocity_scale_near", 1.5, r"route\.velocity_scale_near: a fraction .* at most 1, got 1\.5"),
        ("route", "contact_force_n", 0, r"route\.contact_force_n: must be > 0"),
        ("recording", "speed_span_s", 0, r"recording\.speed_span_s: must be > 0"),
    ],
)
def test_a_number_a_stage_divides_by_must_be_positive(section, key, value, message):
    data = raw()
    data[section] = {key: value}
    with pytest.raises(ConfigError, match=message):
        parse_config(data)
    data[section] = {key: 0.1}  # a positive fraction is accepted
    assert getattr(getattr(parse_config(data), section), key) == 0.1


@pytest.mark.parametrize("field", ["contact_frame", "recorded_as", "wrench_topic"])
def test_two_chains_may_not_share_a_frame_a_recording_name_or_a_topic(field):
    data = raw()
    left, right = list(data["chains"])
    data["chains"][right][field] = data["chains"][left][field]
    with pytest.raises(ConfigError, match=rf"chains\.{right}\.{field}: '.*' is chains\.{left}'s too"):
        parse_config(data)


def test_read_source_makes_paths_absolute_from_the_config_folder(tmp_path):
    src = Reader({"urdf": "robot/r.urdf", "srdf": "package://pkg/r.srdf", "package_dirs": [".."]}, "robot.source")
    source = read_source(src, str(tmp_path / "configs" / "c.yaml"))
    assert source.urdf == str(tmp_path / "configs" / "robot" / "r.urdf")
    assert source.srdf == "package://pkg/r.srdf"  # resolved later, in the package dirs
    assert source.package_dirs == (str(tmp_path),)
    for both_or_neither in ({"urdf": "r.urdf", "example_robot_data": "talos"}, {}):
        with pytest.raises(ConfigError, match=r"^robot\.source: give either example_robot_data or urdf$"):
            read_source(Reader(both_or_neither, "robot.source"))
    with pytest.raises(ConfigError, match=r"is not a valid path"):
        read_source(Reader({"urdf": "r\0.urdf"}, "robot.source"))


def test_read_stance_and_chains_keep_the_files_order():
    data = raw()
    stance = read_stance(Reader(data["stance"], "stance"))
    assert stance.sole_frames == tuple(data["stance"]["sole_frames"]) and stance.root_rpy_deg is None
    data["stance"]["sole_frames"] *= 2
    with pytest.raises(ConfigError, match=r"^stance\.sole_frames: expected two different sole frames"):
        read_stance(Reader(data["stance"], "stance"))
    data["chains"] = dict(reversed(data["chains"].items()))
    assert [c.name for c in read_chains(Reader(data, ""))] == list(data["chains"]) == ["right", "left"]
    data["chains"] = {}
    with pytest.raises(ConfigError, match=r"^chains: expected a mapping"):
        read_chains(Reader(data, ""))


def test_read_table_wants_every_spot_on_the_table_and_served(config):
    data = raw()["table"]
    table = read_table(Reader(data, "table"), config.chains)
    assert table.spots_y_m == tuple(data["spots_y_m"]) and table.size_m == tuple(data["size_m"])
    left_only = tuple(c for c in config.chains if c.spot_y_range_m[0] > min(table.spots_y_m))
    assert 0 < len(left_only) < len(config.chains)  # a chain that serves some spots, not the rightmost
    with pytest.raises(ConfigError, match=r"^table\.spots_y_m: no chain's spot_y_range_m covers y = "):
        read_table(Reader(data, "table"), left_only)
    half = data["size_m"][0] / 2
    with pytest.raises(ConfigError, match=rf"^table\.spots_x_m: spots must lie on the table \(\|x\| <= {half} m\)"):
        read_table(Reader(dict(data, spots_x_m=[half + 0.01]), "table"), config.chains)


def test_read_margins_and_sampling_bound_their_numbers():
    data = raw()
    margins = read_margins(Reader(data["margins"], "margins"))
    assert margins.collision_m == data["margins"]["collision_m"]
    with pytest.raises(ConfigError, match=r"^margins\.com_m: must be >= 0"):
        read_margins(Reader(dict(data["margins"], com_m=-0.01), "margins"))
    assert read_sampling(Reader(data["sampling"], "sampling")).chunk_size == data["sampling"]["chunk_size"]
    with pytest.raises(ConfigError, match=r"^sampling\.chunk_size: expected an integer from 1 to 10000"):
        read_sampling(Reader(dict(data["sampling"], chunk_size=10_001), "sampling"))


def test_a_joints_own_limit_margin_is_read_checked_and_kept(config):
    data = raw()
    own = data["margins"]["joint_limit_rad_by_joint"]
    assert own and all(v > data["margins"]["joint_limit_rad"] for v in own.values())  # TALOS keeps its knees bent
    assert parse_config(config.to_dict()).margins.joint_limit_rad_by_joint == own
    cases = [
        ({"leg_left_4_joint": 0.01}, r"margins\.joint_limit_rad_by_joint\.leg_left_4_joint: 0\.01 rad is below"),
        ({"leg_left_4_joint": "bent"}, r"margins\.joint_limit_rad_by_joint: expected a mapping name -> number"),
    ]
    for value, message in cases:
        with pytest.raises(ConfigError, match=message):
            parse_config(dict(data, margins=dict(data["margins"], joint_limit_rad_by_joint=value)))
    with pytest.raises(ConfigError, match=r"^margins: unknown keys \['com_margin'\]"):
        parse_config(dict(data, margins=dict(data["margins"], com_margin=0.1)))
    with pytest.raises(ConfigError, match=r"^margins\.com_uncertainty_m: must be >= 0"):
        parse_config(dict(data, margins=dict(data["margins"], com_uncertainty_m=-0.01)))


def test_the_table_clearance_is_kept_below_the_approach_standoff_and_saved_only_when_set():
    data = raw()
    standoff = data["table"]["approach_standoff_m"]
    margins = {k: v for k, v in data["margins"].items() if k != "table_clearance_m"}
    unset = parse_config(dict(data, margins=margins))
    assert unset.margins.table_clearance_m == 0.0 and "table_clearance_m" not in unset.to_dict()["margins"]
    kept = parse_config(dict(data, margins=dict(margins, table_clearance_m=standoff / 2)))
    assert kept.to_dict()["margins"]["table_clearance_m"] == standoff / 2
    assert parse_config(kept.to_dict()).margins.table_clearance_m == standoff / 2
    message = rf"^margins\.table_clearance_m: must be below table\.approach_standoff_m \({standoff} m\), where free"
    with pytest.raises(ConfigError, match=message):
        parse_config(dict(data, margins=dict(margins, table_clearance_m=standoff)))
    with pytest.raises(ConfigError, match=r"^margins\.table_clearance_m: must be >= 0"):
        parse_config(dict(data, margins=dict(margins, table_clearance_m=-0.01)))


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ({"knee": 0.3}, r"unknown joint 'knee'.*margins\.joint_limit_rad_by_joint"),
        ({"leg_left_4_joint": 2.0}, r"margins\.joint_limit_rad_by_joint\.leg_left_4_joint: 2\.0 rad from both limits"),
    ],
)
def test_a_joints_own_margin_must_name_a_joint_and_leave_room(value, message):
    data = raw()
    with pytest.raises(ConfigError, match=message):
        Scene(parse_config(dict(data, margins=dict(data["margins"], joint_limit_rad_by_joint=value))))


def test_a_joints_own_margin_bounds_the_plan(scene):
    """The planning limits, the limit margin of a posture and the sampling keep each joint's own margin."""
    knee = scene.joint_index("leg_left_4_joint")
    own = scene.margins.joint_limit_rad_by_joint["leg_left_4_joint"]
    lower, upper = scene.planning_limits()
    assert lower[knee] == pytest.approx(scene.lower[knee] + own)
    assert upper[knee] == pytest.approx(scene.upper[knee] - own)
    others = np.ones(len(scene.joint_names), dtype=bool)
    others[[scene.joint_index(n) for n in scene.margins.joint_limit_rad_by_joint]] = False
    assert np.allclose((lower - scene.lower)[others], scene.margins.joint_limit_rad)
    posture = scene.reference.copy()
    posture[knee] = scene.lower[knee] + own - 0.01  # 0.01 rad inside its own margin, far outside the common one
    assert float(scene.limit_margin(posture)) == pytest.approx(scene.margins.joint_limit_rad - 0.01)


def test_the_foot_rectangle_s_centre_and_half_sizes(config):
    (x0, x1), (y0, y1) = config.stance.foot_x_m, config.stance.foot_y_m
    cx, cy = config.stance.foot_centre_m
    hx, hy = config.stance.foot_half_m
    assert (cx - hx, cx + hx) == pytest.approx((x0, x1)) and (cy - hy, cy + hy) == pytest.approx((y0, y1))
    assert hx > 0 and hy > 0


@pytest.mark.parametrize(
    ("section", "message"),
    [
        ((), r"^config: unknown keys \['tabel'\]; valid keys: robot, stance"),
        (("table",), r"^table: unknown keys \['tabel'\]; valid keys: top_center_m"),
        (("sampling",), r"^sampling: unknown keys \['tabel'\]; valid keys: soft_iterations"),
        (("stance",), r"^stance: unknown keys \['tabel'\]; valid keys: reference_posture"),
        (("chains", "left"), r"^chains\.left: unknown keys \['tabel'\]; valid keys: sole_frame"),
    ],
)
def test_a_misspelt_key_is_refused_in_every_section(section, message):
    data = raw()
    node = data
    for key in section:
        node = node[key]
    node["tabel"] = 1.0
    with pytest.raises(ConfigError, match=message):
        parse_config(data)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["stance"].update(sole_frames=["left_sole_link"] * 2), r"^stance\.sole_frames: expected two"),
        (
            lambda d: d["chains"]["left"].update(fingertip_frames=["gripper_left_fingertip_1_link"] * 3),
            r"^chains\.left\.fingertip_frames: a frame is listed twice",
        ),
        (
            lambda d: d["chains"]["left"].update(sole_frame="arm_left_7_link"),
            r"^chains\.left\.sole_frame: 'arm_left_7_link' is not one of stance\.sole_frames",
        ),
        (
            lambda d: d["chains"]["left"].update(fingertip_frames=d["chains"]["right"]["fingertip_frames"]),
            r"^chains\.left\.fingertip_frames: 'gripper_right_fingertip_1_link' is not carried by the chain's "
            r"gripper_frame 'gripper_left_base_link' \(another arm's\?\)$",
        ),
    ],
)
def test_frames_a_chain_or_the_stance_repeat_or_do_not_stand_on_are_refused(edit, message):
    data = raw()
    edit(data)
    with pytest.raises(ConfigError, match=message):
        Scene(parse_config(data))


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["stance"].update(foot_x_m=[-10.0, 10.0]), r"^stance\.foot_x_m: expected values within 0\.5 of 0"),
        (lambda d: d["stance"].update(foot_y_m=[-0.06, 0.9]), r"^stance\.foot_y_m: expected values within 0\.5 of 0"),
        (lambda d: d["table"].update(yaw_deg=1e30), r"^table\.yaw_deg: must be <= 360, got 1e\+30"),
        (
            lambda d: d["chains"]["left"].update(fingertip_length_m=10),
            r"^chains\.left\.fingertip_length_m: must be <= 0\.3",
        ),
    ],
)
def test_implausible_sizes_are_refused(edit, message):
    data = raw()
    edit(data)
    with pytest.raises(ConfigError, match=message):
        parse_config(data)
