"""The calibration section of a config: defaults round-trip, bad values named."""

import pytest

from posegen.errors import ConfigError
from posegen.robot.calibration_config import calibration_to_dict, parse_calibration


def test_defaults_round_trip():
    config = parse_calibration({})
    assert parse_calibration(calibration_to_dict(config)) == config


@pytest.mark.parametrize("value", [0, 1, 1.0, 50, -0.1])
def test_the_outlier_false_alarm_rate_is_a_probability(value):
    """Outside (0, 1) the chi-square bound is NaN or 0: screening would be silently off, or drop every row."""
    with pytest.raises(ConfigError, match=r"calibration\.outlier_false_alarm"):
        parse_calibration({"outlier_false_alarm": value})


def test_a_probability_is_accepted():
    assert parse_calibration({"outlier_false_alarm": 0.01}).outlier_false_alarm == 0.01


@pytest.mark.parametrize(
    ("data", "where"),
    [
        ({"target_error_mm": float("nan")}, r"calibration\.target_error_mm"),
        ({"plausible_mm": float("inf")}, r"calibration\.plausible_mm"),
        ({"feet_tolerance_deg": float("nan")}, r"calibration\.feet_tolerance_deg"),
        ({"prior": {"joint_offset_deg": float("nan")}}, r"calibration\.prior\.joint_offset_deg"),
    ],
)
def test_a_threshold_or_sigma_is_finite(data, where):
    """NaN passed ``value <= 0`` and was taken: every comparison with it is false (no fit implausible, say)."""
    with pytest.raises(ConfigError, match=where + r": expected a positive finite number"):
        parse_calibration(data)


@pytest.mark.parametrize(
    ("data", "where"),
    [
        ({"fold": 3}, r"^calibration: unknown keys \['fold'\]; valid keys: prior, "),
        ({"prior": {"joint_offset": 0.1}}, r"^calibration\.prior: unknown keys \['joint_offset'\]"),
        (
            {"candidates": {"a": {"fit": ["arm.*"], "flor": True}}},
            r"^calibration\.candidates\.a: unknown keys \['flor'\]",
        ),
    ],
)
def test_a_misspelt_key_is_named(data, where):
    with pytest.raises(ConfigError, match=where):
        parse_calibration(data)
