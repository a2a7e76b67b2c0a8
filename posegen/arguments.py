"""Checks of the numbers a command is given (seeds, counts, sizes) and of the API's paths, made before any work.

The stages call these at the top of their public functions, naming the value by its
parameter (``seed``, ``k``); the command line uses the same checks as argument types, and
shows a stage's error with the flag in the parameter's place (:mod:`posegen.cli.options`).
"""

from __future__ import annotations

import os
from typing import TypeVar

from posegen.errors import ArgumentError
from posegen.numeric import is_finite_number  # here for the readers that import it from here

T = TypeVar("T")

MAX_SEED = 2**31 - 1  # every generator posegen seeds (numpy, OMPL, python-tsp) takes this range


def _integer(value: object, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ArgumentError(f"{name} must be an integer, got {value!r}", parameter=name)
    return value


def check_seed(value: object, name: str = "seed") -> int:
    """A random seed: an integer from 0 to :data:`MAX_SEED`.

    Raises:
        ArgumentError: It is not.

    """
    number = _integer(value, name)
    if not 0 <= number <= MAX_SEED:
        raise ArgumentError(f"{name} must be an integer from 0 to {MAX_SEED}, got {number}", parameter=name)
    return number


def check_count(value: object, name: str, minimum: int = 1, maximum: int = 10**9) -> int:
    """A number of things, from ``minimum`` to ``maximum``.

    Raises:
        ArgumentError: It is not.

    """
    number = _integer(value, name)
    if not minimum <= number <= maximum:
        raise ArgumentError(f"{name} must be an integer from {minimum} to {maximum}, got {number}", parameter=name)
    return number


def check_size(value: object, name: str, positive: bool = False) -> float:
    """A finite size, >= 0 (> 0 with ``positive``).

    Raises:
        ArgumentError: It is not.

    """
    if not is_finite_number(value):
        raise ArgumentError(f"{name} must be a finite number, got {value!r}", parameter=name)
    if value < 0 or (positive and value == 0):
        raise ArgumentError(f"{name} must be {'> 0' if positive else '>= 0'}, got {value}", parameter=name)
    return float(value)


def check_within(value: object, name: str, low: float, high: float) -> float:
    """A finite number from ``low`` to ``high``.

    Example:
        >>> check_within(3.0, "prior_scale", 1e-3, 1e3)
        3.0

    Raises:
        ArgumentError: It is not.

    """
    if not is_finite_number(value) or not low <= value <= high:
        raise ArgumentError(f"{name} must be a number from {low:g} to {high:g}, got {value!r}", parameter=name)
    return float(value)


def check_path(value: object, name: str) -> str:
    """A file's path, given as ``str`` or ``os.PathLike``, as a string.

    Example:
        >>> check_path(Path("plans/pool.yaml"), "pool")  # doctest: +SKIP
        'plans/pool.yaml'

    Raises:
        ArgumentError: It is something else (None, a number, a list).

    """
    if isinstance(value, str) and value:
        return value
    if isinstance(value, os.PathLike):
        return str(os.fspath(value))
    raise ArgumentError(f"{name} must be a path (str or pathlib.Path), got {value!r}", parameter=name)


def check_paths(value: object, name: str) -> list[str]:
    """Paths, given as a list of them or as one path (a string is one path, not its letters).

    Example:
        >>> check_paths("recorded.yaml", "measurements")
        ['recorded.yaml']

    Raises:
        ArgumentError: One of them is not a path, or ``value`` is no list of paths.

    """
    if isinstance(value, str | os.PathLike):
        return [check_path(value, name)]
    if not isinstance(value, list | tuple):
        raise ArgumentError(f"{name} must be a list of paths, got {value!r}", parameter=name)
    return [check_path(v, f"{name}[{i}]") for i, v in enumerate(value)]


def check_type(value: T, kind: type, name: str, called: str = "") -> T:
    """``value`` itself when it is a ``kind`` (or None); ``called``: the type's public name, if not its own.

    Raises:
        ArgumentError: It is of another type (e.g. a dict for a settings object).

    """
    if value is not None and not isinstance(value, kind):
        wanted = called or kind.__name__
        raise ArgumentError(f"{name} must be a {wanted} (or None), got a {type(value).__name__}", parameter=name)
    return value
