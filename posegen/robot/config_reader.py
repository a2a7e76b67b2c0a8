"""Typed reading of a nested YAML mapping, with the key path in every error message."""

from __future__ import annotations

import math
from typing import Any

from posegen.arguments import is_finite_number
from posegen.errors import ConfigError


class Reader:
    """Reads typed fields from a nested mapping, with the key path in every error."""

    def __init__(self, data: Any, where: str) -> None:
        if not isinstance(data, dict):
            raise ConfigError(f"{where or 'config'}: expected a mapping, got {type(data).__name__}")
        self.data = data
        self.where = where

    def _path(self, key: str) -> str:
        return f"{self.where}.{key}" if self.where else key

    def raw(self, key: str, default: Any = ...) -> Any:
        """The value at ``key`` as it is; ``default`` if absent (an error if none is given)."""
        if key not in self.data:
            if default is ...:
                raise ConfigError(f"{self._path(key)}: missing")
            return default
        return self.data[key]

    def sub(self, key: str) -> Reader:
        """A reader of the mapping at ``key``."""
        return Reader(self.raw(key), self._path(key))

    def text(self, key: str, default: Any = ...) -> str:
        """A non-empty string."""
        value = self.raw(key, default)
        if not isinstance(value, str) or not value:
            raise ConfigError(f"{self._path(key)}: expected a non-empty string, got {value!r}")
        return value

    def optional_text(self, key: str) -> str | None:
        """A non-empty string, or None when absent or null."""
        return None if self.raw(key, None) is None else self.text(key)

    def number(self, key: str, default: Any = ..., minimum: float | None = None, maximum: float | None = None) -> float:
        """A finite number, at least ``minimum`` and at most ``maximum`` if given."""
        value = self.raw(key, default)
        if not is_finite_number(value):
            raise ConfigError(f"{self._path(key)}: expected a finite number, got {value!r}")
        if minimum is not None and value < minimum:
            raise ConfigError(f"{self._path(key)}: must be >= {minimum}, got {value}")
        if maximum is not None and value > maximum:
            raise ConfigError(f"{self._path(key)}: must be <= {maximum:g}, got {value:g}")
        return float(value)

    def integer(self, key: str, default: Any = ..., minimum: int = 1, maximum: int = 1_000_000) -> int:
        """An integer from ``minimum`` to ``maximum``."""
        value = self.raw(key, default)
        if isinstance(value, bool) or not isinstance(value, int) or not minimum <= value <= maximum:
            raise ConfigError(f"{self._path(key)}: expected an integer from {minimum} to {maximum}, got {value!r}")
        return value

    def numbers(self, key: str, length: int | None = None, default: Any = ...) -> tuple[float, ...]:
        """A non-empty list of numbers, of ``length`` if given."""
        value = self.raw(key, default)
        ok = isinstance(value, list) and all(is_finite_number(v) for v in value)
        if not ok or (length is not None and len(value) != length) or not value:
            size = f"{length} " if length is not None else ""
            raise ConfigError(f"{self._path(key)}: expected a list of {size}finite numbers, got {value!r}")
        return tuple(float(v) for v in value)

    def texts(self, key: str, default: Any = ...) -> tuple[str, ...]:
        """A list of non-empty strings."""
        value = self.raw(key, default)
        if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
            raise ConfigError(f"{self._path(key)}: expected a list of names, got {value!r}")
        return tuple(value)

    def interval(self, key: str, bound: float = math.inf) -> tuple[float, float]:
        """Two numbers ``[low, high]`` with low < high, each within ``bound`` of zero."""
        low, high = self.numbers(key, 2)
        if low >= high:
            raise ConfigError(f"{self._path(key)}: expected [low, high] with low < high")
        if max(abs(low), abs(high)) > bound:
            raise ConfigError(f"{self._path(key)}: expected values within {bound:g} of 0, got [{low:g}, {high:g}]")
        return low, high

    def angles(self, key: str) -> dict[str, float]:
        """A mapping name -> number (e.g. joint -> rad); empty if the key is absent."""
        value = self.raw(key, {})
        if not isinstance(value, dict) or not all(isinstance(k, str) and is_finite_number(v) for k, v in value.items()):
            raise ConfigError(f"{self._path(key)}: expected a mapping name -> number, got {value!r}")
        return {k: float(v) for k, v in value.items()}

    def keys_within(self, valid: tuple[str, ...]) -> None:
        """Reject keys this mapping does not know (a typo would otherwise be ignored)."""
        unknown = sorted(set(self.data) - set(valid))
        if unknown:
            where = self.where or "config"
            raise ConfigError(f"{where}: unknown keys {unknown}; valid keys: {', '.join(valid)}")
