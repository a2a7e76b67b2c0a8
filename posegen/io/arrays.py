"""Bulk numbers beside a YAML artefact: a ``.npz`` sidecar that the header names by hash.

The YAML file stays the human-readable header (provenance, summary); the arrays go to
``<header name>.<sha256 prefix>.npz`` next to it (``route.yaml.3fa2b1c4d5e6.npz``), and
the header records its file name and sha256, so a stale or swapped sidecar is refused
rather than read. Because the sidecar's name follows its content, a new artefact never
overwrites the old one's arrays: the new sidecar lands first, then the header (one
rename: the moment the artefact changes), then the old sidecar is removed. A kill at any
point leaves the old artefact or the new one readable, plus at most a sidecar no header
names, which the next write of that header removes. Headers of older posegen name
``<stem>.npz``; they are still read, and such a sidecar is never removed (two headers,
``r.yaml`` and ``r.json``, may share it). The bytes depend on the arrays only (zip
entries carry a fixed date), so same seed, same bytes holds for sidecars too; any
``numpy.load`` reads them. Entries are stored as they are, or deflated (``compress``:
smaller, slower to write; a route's points); each array keeps its memory order, so a
column-major time series, which deflate compresses better, loads column-major.
"""

from __future__ import annotations

import hashlib
import io
import json
import re
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from posegen.errors import InputError, reason
from posegen.io.artefact import dump_yaml
from posegen.io.atomic import crash_point, write_atomic
from posegen.io.companion import write_with_companions

SIDECAR_SUFFIX = ".npz"
_EPOCH = (1980, 1, 1, 0, 0, 0)  # the zip format's earliest date: no clock in the bytes
COMPRESS_LEVEL = 9  # deflate level of compressed sidecars
NAME_DIGITS = 12  # hex digits of the sha256 in a sidecar's name


def encode_arrays(arrays: Mapping[str, NDArray[Any]], compress: bool = False) -> bytes:
    """The ``.npz`` bytes of some named arrays, deterministic (deflated with ``compress``)."""
    buffer = io.BytesIO()
    method = zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED
    level = COMPRESS_LEVEL if compress else None
    with zipfile.ZipFile(buffer, "w", compression=method, compresslevel=level) as archive:
        for name, array in arrays.items():
            entry = zipfile.ZipInfo(f"{name}.npy", date_time=_EPOCH)
            entry.external_attr = 0o644 << 16
            entry.compress_type = method
            with archive.open(entry, "w", force_zip64=True) as handle:
                np.lib.format.write_array(handle, _ordered(np.asanyarray(array)), allow_pickle=False)
    return buffer.getvalue()


def _ordered(array: NDArray[Any]) -> NDArray[Any]:
    """The array as it is if C- or Fortran-contiguous (the .npy header says which), else a C copy."""
    if array.flags.c_contiguous or array.flags.f_contiguous:
        return array
    return np.ascontiguousarray(array)


def sidecar_path(path: str | Path, data: bytes) -> Path:
    """Where the arrays ``data`` of the artefact at ``path`` go: ``<name>.<sha256 prefix>.npz`` beside it."""
    path = Path(path)
    digest = hashlib.sha256(data).hexdigest()[:NAME_DIGITS]
    return path.with_name(f"{path.name}.{digest}{SIDECAR_SUFFIX}")


def sidecars_of(path: str | Path) -> list[Path]:
    """The sidecars named after the header at ``path`` that exist beside it (the current one and any orphans)."""
    path = Path(path)
    pattern = re.compile(re.escape(path.name) + rf"\.[0-9a-f]{{{NAME_DIGITS}}}" + re.escape(SIDECAR_SUFFIX))
    if not path.parent.is_dir():
        return []
    return sorted(p for p in path.parent.iterdir() if pattern.fullmatch(p.name))


def sidecar_reference(path: str | Path, data: bytes) -> dict[str, Any]:
    """What a header records of its sidecar: the file name (relative) and the sha256."""
    return {"file": sidecar_path(path, data).name, "sha256": hashlib.sha256(data).hexdigest()}


def read_arrays(
    path: str | Path, reference: Any, names: tuple[str, ...], rows: int | None = None
) -> dict[str, NDArray[Any]]:
    """Read the sidecar a header refers to, after checking its hash and its arrays.

    Args:
        path: The header (YAML) file; the sidecar is looked up beside it.
        reference: The header's record of the sidecar (``{file, sha256}``).
        names: Arrays that must be there.
        rows: The number of rows the header declares: every array must have it, checked
            from the arrays' headers before any is decompressed (a small file cannot make
            its reader allocate more than the header says).

    Raises:
        InputError: The reference is malformed, the sidecar is missing, changed, not an
            ``.npz``, lacks an array, or holds another number of rows than declared.

    """
    path = Path(path)
    if not isinstance(reference, dict) or not isinstance(reference.get("file"), str):
        raise InputError(f"{path}: 'arrays' must name its sidecar file and sha256")
    file = path.parent / Path(reference["file"]).name  # never outside the header's folder
    try:
        data = file.read_bytes()
    except OSError as exc:
        raise InputError(f"{path}: cannot read its arrays file {file}: {exc.strerror}") from exc
    if hashlib.sha256(data).hexdigest() != reference.get("sha256"):
        raise InputError(f"{path}: {file.name} is not the arrays file this header was written with (sha256 differs)")
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as archive:
            missing = [n for n in names if n not in archive.files]
            if missing:
                raise InputError(f"{file}: missing arrays {', '.join(missing)}")
            if rows is not None:
                _check_rows(file, archive.zip, names, rows)
            return {name: archive[name] for name in names}
    except InputError:
        raise
    except Exception as exc:  # numpy's readers raise many kinds on damaged bytes (SyntaxError, MemoryError...)
        raise InputError(f"{file}: not a readable .npz file ({reason(exc)})") from exc


def _check_rows(file: Path, archive: zipfile.ZipFile, names: tuple[str, ...], rows: int) -> None:
    """Every array has ``rows`` rows, read from its ``.npy`` header (nothing decompressed beyond it)."""
    for name in names:
        with archive.open(f"{name}.npy") as handle:
            major, _ = np.lib.format.read_magic(handle)
            read = np.lib.format.read_array_header_1_0 if major == 1 else np.lib.format.read_array_header_2_0
            shape = read(handle)[0]
        if not shape or shape[0] != rows:
            raise InputError(f"{file}: {name} holds {shape[0] if shape else 0} rows, the header declares {rows}")


def write_with_arrays(
    path: str | Path,
    header: dict[str, Any],
    arrays: Mapping[str, NDArray[Any]],
    compress: bool = False,
    companions: Mapping[str, bytes | None] | None = None,
) -> Path:
    """Write an artefact as a header (YAML, or JSON if the name ends in ``.json``) and its ``.npz`` sidecar.

    The sidecar lands first under a name of its own (its content's hash), the header that
    names it next, in one rename: until then the old header still reads its old arrays.
    Then the sidecars no header names any more (the old one, orphans of killed runs) are
    removed. If writing the header fails, the new sidecar is removed (unless it was
    already there: the same arrays as before).

    Args:
        path: The header's file.
        header: The header's data (without the sidecar's reference).
        arrays: The sidecar's arrays, by name.
        compress: Deflate the sidecar's entries.
        companions: Files that go with the header, by suffix (a route's CSV; None: none
            of that kind, an older one is removed): named by the header's hash, they land
            before it, replaced with it as one (:func:`posegen.io.companion.write_with_companions`).

    Returns:
        The sidecar's path.

    """
    path = Path(path)
    data = encode_arrays(arrays, compress)
    sidecar = sidecar_path(path, data)
    existed = sidecar.exists()
    write_atomic(sidecar, data)
    full = {**header, "arrays": sidecar_reference(path, data)}
    try:
        text = json.dumps(full, indent=1) if path.suffix.lower() == ".json" else dump_yaml(full)
        write_with_companions(path, text.encode(), companions or {})
    except BaseException:
        if not existed:
            sidecar.unlink(missing_ok=True)
        raise
    for stale in sidecars_of(path):
        if stale != sidecar:
            crash_point(f"before removing {stale.name}")
            stale.unlink(missing_ok=True)
    return sidecar
