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
