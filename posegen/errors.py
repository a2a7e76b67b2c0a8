"""The one exception family of posegen.

Library code raises these; only :mod:`posegen.cli` turns them into exit codes.
"""

from __future__ import annotations

from collections.abc import Iterable


class PosegenError(Exception):
    """Base class of every error posegen raises on purpose."""


class ConfigError(PosegenError):
    """A configuration file is malformed or names something the robot does not have."""


class InputError(PosegenError):
    """An input file (pool, selection, measurements) is malformed."""


class BackendError(PosegenError):
    """Work cannot run where it was sent (Dask scheduler unreachable, no worker, other version)."""


class InfeasibleError(PosegenError):
    """The problem has no solution (table out of reach, empty pool, rank-deficient design)."""


def unknown_name(kind: str, name: str, valid: Iterable[str]) -> str:
    """Format the message for an unknown name, listing the valid choices.

    Args:
        kind: What the name designates ("frame", "joint", ...).
        name: The name that was not found.
        valid: The valid names.

    Returns:
        A one-line message.

    """
    choices = sorted(valid)
    shown = ", ".join(choices[:40]) + (", ..." if len(choices) > 40 else "")
    return f"unknown {kind} '{name}'; valid {kind}s: {shown}"
