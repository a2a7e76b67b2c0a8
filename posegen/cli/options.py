"""Argument types and defaults shared by the subcommands."""

from __future__ import annotations

import argparse
import os

DEFAULT_CONFIG = "configs/talos_table.yaml"
EXIT_VIOLATIONS = 1  # a check found violations
JOINT_STATES_TOPIC = "/joint_states"  # ROS 2 convention (joint_state_broadcaster)


def positive(text: str) -> int:
    """A positive integer argument."""
    value = int(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {value}")
    return value


def fraction(text: str) -> float:
    """A fraction in (0, 1]."""
    value = float(text)
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
