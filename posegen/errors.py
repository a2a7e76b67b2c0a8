"""The one exception family of posegen.

Library code raises these; only :mod:`posegen.cli` turns them into exit codes.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from typing import Any


class PosegenError(Exception):
    """Base class of every error posegen raises on purpose.

    Its message speaks the library's words: a parameter by its name (``k must be an
    integer from 1 to ...``, ``k=80: the pool has only 50 postures``), never by a
    command-line flag. ``parameter`` is those words, as the message writes them, when the
    error is about one parameter: :mod:`posegen.cli` shows its flag in their place.

    Example:
        >>> try:
        ...     posegen.load("not_there.yaml")
        ... except posegen.PosegenError as error:
        ...     print(error)  # one line, naming the file

    """

    def __init__(self, *args: object, parameter: str | None = None, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)  # kwargs: those of a second base (ImportError's ``name``)
        self.parameter = parameter  # the parameter's name as the message writes it (first occurrence)


class ConfigError(PosegenError):
    """A configuration file is malformed or names something the robot does not have."""


class InputError(PosegenError):
    """An input file (pool, selection, measurements) is malformed."""


class BackendError(PosegenError):
    """Work cannot run where it was sent (Dask scheduler unreachable, no worker, other version)."""


class ArgumentError(PosegenError):
    """A number given to a command (a seed, a count, a size) is out of its range."""


class OutputError(PosegenError):
    """An output cannot be written: its place is not writable, or another posegen is writing it."""


class InfeasibleError(PosegenError):
    """The problem has no solution (table out of reach, empty pool, rank-deficient design)."""


class ExtraError(PosegenError, ImportError):
    """An optional dependency is not installed: the message names the ``posegen[extra]`` to install."""


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
    close = difflib.get_close_matches(name, choices, n=3)
    hint = f"; did you mean {' or '.join(close)}?" if close else ""
    return f"unknown {kind} '{name}'; valid {kind}s: {shown}{hint}"


def reason(exc: BaseException) -> str:
    """An exception as one line for a message: its type and the first line of its text."""
    lines = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {lines[0]}" if lines else type(exc).__name__
