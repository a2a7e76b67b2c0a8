"""The checks of a command's numbers, shared by the command line and the stages."""

import pytest

from posegen.arguments import MAX_SEED, check_count, check_seed, check_size
from posegen.errors import ArgumentError


@pytest.mark.parametrize("value", [0, 1, MAX_SEED])
def test_seeds_in_range(value):
    assert check_seed(value) == value


@pytest.mark.parametrize("value", [-1, MAX_SEED + 1, 2**70, 1.5, True, "3", None])
def test_seeds_out_of_range(value):
    with pytest.raises(ArgumentError, match="seed"):
        check_seed(value)


def test_counts_and_sizes():
    assert check_count(0, "runs", minimum=0) == 0
    assert check_size(0, "error_mm") == 0.0 and check_size(2, "x", positive=True) == 2.0
    for bad in (0, -3, 2.0, False):
        with pytest.raises(ArgumentError, match=r"^n must be") as caught:
            check_count(bad, "n")
        assert caught.value.parameter == "n"  # the library's word, which the command line shows as its flag
    for bad in (float("nan"), float("inf"), -1e-9, "1", None):
        with pytest.raises(ArgumentError, match=r"^error_mm must be") as caught:
            check_size(bad, "error_mm")
        assert caught.value.parameter == "error_mm"
    with pytest.raises(ArgumentError, match="> 0"):
        check_size(0.0, "prior_scale", positive=True)
