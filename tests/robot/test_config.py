import copy

import pytest
import yaml

from posegen.errors import ConfigError
from posegen.robot import Scene, load_config, parse_config
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
