"""Argument types and defaults shared by the subcommands."""

from __future__ import annotations

import argparse

DEFAULT_CONFIG = "configs/talos_table.yaml"
EXIT_VIOLATIONS = 1  # a check found violations


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
