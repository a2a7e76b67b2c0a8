"""The projection's stop rule: an iteration whose errors repeat is stuck, a shrinking one is not."""

from posegen.robot.projection import _cycling


def test_repeating_errors_are_stuck():
    alternating = [(0.18, 0.37), (0.19, 0.36), (0.18, 0.37), (0.19, 0.36), (0.18, 0.37)]
    assert _cycling(alternating)
    plateau = [(0.05, 0.2), (0.05, 0.2), (0.05, 0.2)]
    assert _cycling(plateau)


def test_shrinking_or_wandering_errors_go_on():
    shrinking = [(0.1 * 0.8**k, 0.5 * 0.8**k) for k in range(20)]
    assert not any(_cycling(shrinking[: k + 1]) for k in range(len(shrinking)))
    wandering = [(0.67, 2.6), (0.18, 1.9), (0.17, 2.3), (0.21, 1.9), (0.14, 2.0), (0.16, 2.2)]
    assert not any(_cycling(wandering[: k + 1]) for k in range(len(wandering)))
    slow = [(0.0079, 0.01), (0.0070, 0.01), (0.0051, 0.01), (0.0045, 0.01), (0.0034, 0.01)]
    assert not _cycling(slow)
