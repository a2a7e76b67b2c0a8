"""posegen's YAML artefacts: their text, provenance, atomic writes and kind-checked reads."""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import Any

import yaml

from posegen import __version__
from posegen.errors import InputError, PosegenError
from posegen.io.atomic import write_atomic

try:
    _Dumper: Any = yaml.CSafeDumper
    _Parser: Any = yaml.CSafeLoader
except AttributeError:  # PyYAML built without libyaml
    _Dumper = yaml.SafeDumper
    _Parser = yaml.SafeLoader
MERGE_TAG = "tag:yaml.org,2002:merge"  # ``<<: *anchor``: its keys may be given again (they override)


class _Loader(_Parser):
    """The safe loader, refusing a key given twice in one mapping (YAML keeps the last one without a word)."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen: set[tuple[str, str]] = set()
        for key_node, _ in node.value:
            if not isinstance(key_node, yaml.ScalarNode) or key_node.tag == MERGE_TAG:
                continue
            key = (key_node.tag, key_node.value)
            if key in seen:
                mark = key_node.start_mark
                raise yaml.constructor.ConstructorError(
                    None, None, f"the key '{key_node.value}' is given twice (line {mark.line + 1})", None
                )
            seen.add(key)
        return dict(super().construct_mapping(node, deep))


def provenance(config: dict[str, Any], model_sha256: str, seed: int | None) -> dict[str, Any]:
    """What made an artefact: config, robot model hash, seed and posegen version."""
    return {
        "posegen_version": __version__,
        "robot_model_sha256": model_sha256,
        "seed": seed,
        "config": config,
    }


def dump_yaml(data: dict[str, Any]) -> str:
    """YAML text of plain data: block mappings, lists of numbers inline."""
    return str(yaml.dump(data, Dumper=_Dumper, sort_keys=False, default_flow_style=None, width=1 << 16))


def write_yaml(path: str | Path, data: dict[str, Any]) -> None:
    """Atomically write plain data as YAML."""
    write_atomic(path, dump_yaml(data))


def load_yaml_file(path: Path, error: type[PosegenError]) -> Any:
    """Parse a YAML file; a missing file or bad YAML raises ``error`` with a one-line message."""
    text = read_text_file(path, error)
    try:
        return yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as exc:
        raise error(f"{path}: not valid YAML ({str(exc).splitlines()[0]})") from exc
    except RecursionError:
        raise error(f"{path}: not valid YAML (nested too deeply)") from None


def read_text_file(path: Path, error: type[PosegenError]) -> str:
    """The text of a UTF-8 file (a byte-order mark is dropped); unreadable or binary raises ``error``.

    Only a regular file is read: a FIFO would wait for a writer and a device (``/dev/zero``) never ends.
    """
    try:
        mode = os.stat(path).st_mode
        if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):  # a folder keeps the system's own message below
            raise error(f"{path}: not a regular file (a device, FIFO or socket is not read)")
        data = path.read_bytes()
    except OSError as exc:
        raise error(f"cannot read {path}: {exc.strerror}") from exc
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(f"{path}: not a text file (byte {exc.start} is not UTF-8)") from None


def read_yaml(path: str | Path, kind: str | tuple[str, ...]) -> dict[str, Any]:
    """Read a posegen artefact and check its kind.

    Args:
        path: File to read.
        kind: Expected value(s) of the ``format`` field ("posegen-pool", ...).

    Raises:
        InputError: The file is missing, not YAML, or not an artefact of that kind.

    """
    if not isinstance(path, (str, os.PathLike)) or not str(path):
        raise InputError(f"expected a file's path (str or pathlib.Path), got {path!r}")
    path = Path(path)
    data = load_yaml_file(path, InputError)
    kinds = (kind,) if isinstance(kind, str) else kind
    if not isinstance(data, dict) or data.get("format") not in kinds:
        found = data.get("format") if isinstance(data, dict) else type(data).__name__
        raise InputError(f"{path}: not a {' or '.join(kinds)} file (format: {found!r})")
    return data
