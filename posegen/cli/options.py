"""Argument types and defaults shared by the subcommands.

The types run the checks of :mod:`posegen.arguments`, so a bad value is refused by the
parser, before any file is read, with the message a library caller would get.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable
from typing import TypeVar

from posegen.arguments import check_count, check_seed, check_size
from posegen.errors import PosegenError

DEFAULT_CONFIG = "configs/talos_table.yaml"
EXIT_VIOLATIONS = 1  # a check found violations
JOINT_STATES_TOPIC = "/joint_states"  # ROS 2 convention (joint_state_broadcaster)

T = TypeVar("T")


def _checked(parse: Callable[[str], object], check: Callable[[object], T]) -> Callable[[str], T]:
    def convert(text: str) -> T:
        try:
            value = parse(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        try:
            return check(value)
        except PosegenError as exc:
            raise argparse.ArgumentTypeError(str(exc).replace("value ", "", 1)) from None

    return convert


positive = _checked(int, lambda v: check_count(v, "value"))
non_negative = _checked(int, lambda v: check_count(v, "value", minimum=0))
seed = _checked(int, lambda v: check_seed(v, "value"))
size = _checked(float, lambda v: check_size(v, "value"))
port = _checked(int, lambda v: check_count(v, "value", minimum=0, maximum=65535))
positive_size = _checked(float, lambda v: check_size(v, "value", positive=True))


def fraction(text: str) -> float:
    """A fraction in (0, 1]."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not 0.0 < value <= 1.0:
        raise argparse.ArgumentTypeError(f"must be in (0, 1], got {value}")
    return value


def add_backend_arguments(parser: argparse.ArgumentParser) -> None:
    """``--workers`` and ``--scheduler``: where a command's independent jobs run."""
    parser.add_argument(
        "--workers", type=positive, default=os.cpu_count() or 1, help="local worker processes (default: cores)"
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        default=None,
        help="run on the Dask cluster of this scheduler (tcp://host:8786) instead of local processes",
    )


def name(text: str) -> str:
    """A non-empty name without path separators or control characters."""
    if not text.strip() or any(c in text for c in "/\\") or not text.isprintable():
        raise argparse.ArgumentTypeError(f"not a usable name: {text!r}")
    return text
