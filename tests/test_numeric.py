"""The number checks every layer shares."""

import pytest
import yaml

from posegen.errors import ConfigError
from posegen.numeric import is_finite_number
from tests.conftest import CONFIG


@pytest.mark.parametrize(
    ("value", "finite"),
    [(0, True), (-2.5, True), (float("nan"), False), (float("inf"), False), (True, False), ("1", False), (None, False)],
)
def test_finite_numbers_are_ints_and_floats_within_range(value, finite):
    assert is_finite_number(value) is finite


def test_an_int_beyond_a_float_is_not_finite_and_a_config_says_so_in_one_line():
    """``math.isfinite(10**400)`` raises OverflowError: a config holding it ended in a traceback."""
    from posegen.robot import parse_config

    assert is_finite_number(10**400) is False
    data = yaml.safe_load(CONFIG.read_text())
    data.setdefault("margins", {})["collision_m"] = 10**400
    with pytest.raises(ConfigError, match=r"^margins\.collision_m: expected a finite number"):
        parse_config(data)
