"""The session index read back: every field typed and in its range, or one line naming the field.

``session.yaml`` is written by posegen (:func:`posegen.session.index.write_index`) and
vouches for the session's files; a hand-edited one must not make a command run on
values no step chose. :func:`read_index` refuses, naming the field (``settings.target_mm``,
``batches[1].recording.contacts``) and what it expects, any value of the wrong type or out
of the range its step checks (the settings as :func:`check_settings` checks them at
``start``), a batch state or verdict (``done``, ``at_floor``) that the batches do not
give, an assessment without a recording, a batch before the last that is not assessed,
and batches not numbered 1, 2, ...
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

from posegen.arguments import is_finite_number
from posegen.errors import ArgumentError, InputError
from posegen.io import read_yaml
from posegen.session.index import (
    INDEX_FILE,
    SESSION_FORMAT,
    SESSION_VERSION,
    Assessment,
    Batch,
    BatchState,
    Deliverable,
    Recording,
    SessionIndex,
    SessionSettings,
    check_settings,
)

_SHA256 = re.compile(r"[0-9a-f]{64}")
_EDITED = "was it edited by hand?"


class _FieldError(InputError):
    """A field of the index that is not what the session wrote (its path in the index, and why)."""


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _mapping(value: Any, where: str) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise _FieldError(f"{where}: expected a mapping, got {_shown(value)}")
    return value


def _get(data: dict[str, Any], key: str, where: str, check: Callable[[Any, str], Any]) -> Any:
    """``data[key]`` checked by ``check`` (given the value and the field's path)."""
    field = f"{where}.{key}" if where else key
    if key not in data:
        raise _FieldError(f"{field}: missing")
    return check(data[key], field)


def _text(value: Any, where: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise _FieldError(f"{where}: expected a non-empty name, got {_shown(value)}")
    return value


def _any_text(value: Any, where: str) -> str:
    if not isinstance(value, str):
        raise _FieldError(f"{where}: expected text, got {_shown(value)}")
    return value


def _sha256(value: Any, where: str) -> str:
    if not isinstance(value, str) or not _SHA256.fullmatch(value):
        raise _FieldError(f"{where}: expected a sha256 (64 hex digits), got {_shown(value)}")
    return value


def _count(value: Any, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise _FieldError(f"{where}: expected a whole number from 0, got {_shown(value)}")
    return value


def _seconds(value: Any, where: str) -> float:
    if not is_finite_number(value) or value < 0:
        raise _FieldError(f"{where}: expected a finite number of seconds from 0, got {_shown(value)}")
    return float(value)


def _flag(value: Any, where: str) -> bool:
    if not isinstance(value, bool):
        raise _FieldError(f"{where}: expected true or false, got {_shown(value)}")
    return value


def _rows(value: Any, where: str) -> tuple[int, ...]:
    if not isinstance(value, list):
        raise _FieldError(f"{where}: expected a list of pool rows, got {_shown(value)}")
    return tuple(_count(v, f"{where}[{i}]") for i, v in enumerate(value))


def _names(value: Any, where: str) -> tuple[str, ...]:
    if not isinstance(value, list):
        raise _FieldError(f"{where}: expected a list of names, got {_shown(value)}")
    return tuple(_text(v, f"{where}[{i}]") for i, v in enumerate(value))


def _settings(value: Any, where: str) -> SessionSettings:
    raw = _mapping(value, where)
    deliverables = [d.value for d in Deliverable]
    deliverable = _get(raw, "deliverable", where, _text)
    if deliverable not in deliverables:
        raise _FieldError(f"{where}.deliverable: expected one of {', '.join(deliverables)}, got {_shown(deliverable)}")
    candidates = _get(raw, "candidates", where, _names)
    settings = SessionSettings(
        target_mm=_get(raw, "target_mm", where, lambda v, w: v),
        seed=_get(raw, "seed", where, lambda v, w: v),
        margin=_get(raw, "margin", where, lambda v, w: v),
        batch_postures=_get(raw, "batch_postures", where, lambda v, w: v),
        deliverable=Deliverable(deliverable),
        candidates=candidates,
        fold_seeds=_get(raw, "fold_seeds", where, lambda v, w: v),
        prior_scale=_get(raw, "prior_scale", where, lambda v, w: v),
        joint_topic=_get(raw, "joint_topic", where, _text),
        trajectory_topic=_get(raw, "trajectory_topic", where, _text),
        segments_topic=_get(raw, "segments_topic", where, _text),
        patience=raw.get("patience", SessionSettings.patience),  # indexes before patience existed: its default
    )
    try:
        check_settings(settings)
    except ArgumentError as exc:
        raise _FieldError(f"{where}.{exc}") from exc
    return settings


def _recording(value: Any, where: str) -> Recording | None:
    if value is None:
        return None
    raw = _mapping(value, where)
    return Recording(
        bag=_get(raw, "bag", where, _text),
        bag_sha256=_get(raw, "bag_sha256", where, _sha256),
        table=_get(raw, "table", where, _text),
        contacts=_get(raw, "contacts", where, _count),
        duration_s=_get(raw, "duration_s", where, _seconds),
        missing=_get(raw, "missing", where, _rows),
    )


def _predicted(value: Any, where: str) -> dict[str, float]:
    raw = _mapping(value, where)
    out = {}
    for chain, mm in raw.items():
        if not isinstance(chain, str) or not is_finite_number(mm) or mm < 0:
            raise _FieldError(f"{where}.{chain}: expected a chain's error in mm (a finite number from 0), got {mm!r}")
        out[chain] = float(mm)
    return out


def _assessment(value: Any, where: str) -> Assessment | None:
    if value is None:
        return None
    raw = _mapping(value, where)
    return Assessment(
        contacts=_get(raw, "contacts", where, _count),
        deliverable=_get(raw, "deliverable", where, _any_text),
        candidate=_get(raw, "candidate", where, _any_text),
        predicted_z_mm=_get(raw, "predicted_z_mm", where, _predicted),
        done=_get(raw, "done", where, _flag),
        error=_any_text(raw.get("error", ""), f"{where}.error"),
    )


def _files(value: Any, where: str) -> dict[str, str]:
    raw = _mapping(value, where)
    for name in raw:
        inside = isinstance(name, str) and not Path(name).is_absolute() and ".." not in Path(name).parts
        if not inside or not name.strip():
            raise _FieldError(f"{where}: {_shown(name)} is not a file of the session (a path inside its folder)")
    return {name: _sha256(digest, f"{where}.{name}") for name, digest in raw.items()}


def _batch(value: Any, where: str) -> Batch:
    raw = _mapping(value, where)
    batch = Batch(
        number=_get(raw, "number", where, _count),
        pool_rows=_get(raw, "pool_rows", where, _rows),
        planned_s=_get(raw, "planned_s", where, _seconds),
        files=_get(raw, "files", where, _files),
        recording=_get(raw, "recording", where, _recording),
        assessment=_get(raw, "assessment", where, _assessment),
    )
    if batch.assessment is not None and batch.recording is None:
        raise _FieldError(f"{where}.assessment: a batch assessed but not recorded")
    states = [s.value for s in BatchState]
    state = _get(raw, "state", where, _text)
    if state not in states:
        raise _FieldError(f"{where}.state: expected one of {', '.join(states)}, got {_shown(state)}")
    if state != batch.state.value:
        raise _FieldError(f"{where}.state: {state}, but the batch is {batch.state.value}")
    return batch


def _batches(value: Any, where: str) -> tuple[Batch, ...]:
    if not isinstance(value, list) or not value:
        raise _FieldError(
            f"{where}: expected the list of batches (a session has one from its start), got {_shown(value)}"
        )
    batches = tuple(_batch(entry, f"{where}[{i}]") for i, entry in enumerate(value))
    if [b.number for b in batches] != list(range(1, len(batches) + 1)):
        raise _FieldError(f"{where}: batches are not numbered 1, 2, ...")
    for batch in batches[:-1]:
        if batch.state is not BatchState.ASSESSED:
            raise _FieldError(f"{where}: batch {batch.number} is {batch.state.value}, but a later batch follows it")
    return batches


def _index(data: dict[str, Any]) -> SessionIndex:
    index = SessionIndex(
        provenance=_get(data, "provenance", "", _mapping),
        pool=_get(data, "pool", "", _text),
        pool_sha256=_get(data, "pool_sha256", "", _sha256),
        settings=_get(data, "settings", "", _settings),
        batches=_get(data, "batches", "", _batches),
    )
    for key, derived in (("done", index.done), ("at_floor", index.at_floor)):
        if _get(data, key, "", _flag) != derived:
            raise _FieldError(f"{key}: {str(not derived).lower()}, but the batches say {str(derived).lower()}")
    return index


def read_index(folder: Path) -> SessionIndex:
    """Read a session's index, every field checked.

    Raises:
        InputError: No session there, another format or version, or a malformed index
            (the field named, and what it expects).

    Example:
        >>> index = read_index(Path("plans/session"))
        >>> [b.state for b in index.batches]

    """
    path = Path(folder) / INDEX_FILE
    if not path.is_file():
        raise InputError(f"{folder}: not a posegen session (no {INDEX_FILE}; start one with posegen session start)")
    data = read_yaml(path, SESSION_FORMAT)
    version = data.get("format_version")
    if version != SESSION_VERSION or isinstance(version, bool):
        raise InputError(f"{path}: session format version {version!r}; this posegen reads version {SESSION_VERSION}")
    try:
        return _index(data)
    except _FieldError as exc:
        raise InputError(f"{path}: not a valid session index ({exc}); {_EDITED}") from exc
