"""Reading and writing recorded contacts.

Two inputs are read as they are:

* posegen's measurement format (YAML, ``format: posegen-measurements``)::

      format: posegen-measurements
      format_version: 1
      provenance: {...}
      joint_names: [...]
      contacts:
        - {chain: left, session: day1, kind: flush, label: contact_03, joints: [rad, ...]}

  ``kind`` is ``flush`` or ``point`` (a point contact measures its height only); a
  contact without one makes the kind its chain's ``contact_kind`` plans.

* recorded CSV files, one contact per row: ``gripper, <recorded gripper name>, handle,
  <target spot>, joint_states, <angles>``, with a header row holding ``joint_names``
  followed by the names of the angles (leading or trailing empty fields are tolerated).
  Each contact is of the kind its chain's ``contact_kind`` plans.

Every angle is checked against the URDF limits widened by a tolerance: a shifted column
shows up as text or as an angle far out of range. Such a CSV row is reported (file,
line, reason) and left out; posegen's own format is read strictly.
"""

from __future__ import annotations

import csv
import logging
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from posegen.errors import InputError, reason, unknown_name
from posegen.io import read_text_file, read_yaml, write_yaml
from posegen.model.contact_model import Contacts, planned_kinds
from posegen.numeric import is_finite_number
from posegen.robot import Scene, kind_named, registered_kinds

LOG = logging.getLogger(__name__)

MEASUREMENT_FORMAT = "posegen-measurements"
MEASUREMENT_VERSION = 1
LIMIT_TOLERANCE_RAD = 0.25  # real robots park joints a little past URDF limits (TALOS: arm_*_1 by 0.2 rad)
WINDOW_FIELDS = frozenset({"start_s", "end_s", "samples", "joint_std_rad", "force_n"})  # a contact `measure` found


def _check_angles(scene: Scene, names: Sequence[str], values: np.ndarray, where: str, tolerance: float) -> None:
    idx = [scene.joint_index(n) for n in names]
    low = scene.lower[idx] - tolerance
    high = scene.upper[idx] + tolerance
    missing = np.flatnonzero(~np.isfinite(values))
    if len(missing):
        k = int(missing[0])
        raise InputError(f"{where}: {names[k]} = {values[k]} is not a finite number (a joint angle, rad)")
    bad = np.flatnonzero((values < low) | (values > high))
    if len(bad):
        k = int(bad[0])
        raise InputError(
            f"{where}: {names[k]} = {values[k]:.6g} rad is outside its limits "
            f"[{scene.lower[idx[k]]:.3f}, {scene.upper[idx[k]]:.3f}] +/- {tolerance} rad (shifted column?)"
        )


def _check_names(scene: Scene, names: Sequence[str], path: Path) -> None:
    """Check that the recorded joint names are the model's, each once, every joint the config leaves free included.

    A joint the config locks may be absent (it keeps the reference posture's value); a
    free joint may not: its angle would be guessed.

    Raises:
        InputError: A name the model does not know (the valid names are listed), a name
            given twice, or a free joint missing (named).

    """
    for name in names:
        if name not in scene.joint_names:
            raise InputError(f"{path}: {unknown_name('joint', name, scene.joint_names)}")
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:
        raise InputError(f"{path}: joint column {', '.join(twice)} given twice")
    missing = [n for n, locked in zip(scene.joint_names, scene.locked, strict=True) if not locked and n not in names]
    if missing:
        raise InputError(
            f"{path}: no column for joint {', '.join(missing)} (only the joints the config locks may be absent)"
        )


def measurement_item(item: str) -> tuple[str, str | None]:
    """The file and the session of a ``FILE[@SESSION]`` item; ``@@`` is an ``@`` of the name.

    ``day@2.csv@morning`` is written ``day@@2.csv@morning``; ``day@@2.csv`` is the file
    ``day@2.csv`` with its own session.

    Raises:
        InputError: An ``@`` followed by no session name.

    """
    text, k = [], 0
    while k < len(item):
        if item.startswith("@@", k):
            text.append("@")
            k += 2
        elif item[k] == "@":
            session = item[k + 1 :].replace("@@", "@")
            if not session.strip():
                raise InputError(f"{item}: no session name after '@' (an '@' of a file name is written '@@')")
            return "".join(text), session
        else:
            text.append(item[k])
            k += 1
    return "".join(text), None


def existing_measurement_file(path: str | Path) -> Path:
    """``path``, a file that exists: a folder (a recorded bag, measured first) or nothing is refused.

    Example:
        >>> existing_measurement_file("plans/demo/measured.yaml")
        PosixPath('plans/demo/measured.yaml')

    Raises:
        InputError: ``path`` is a folder, or no file.

    """
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path}: a folder, not a measurement file (measure a recorded bag first)")
    if not path.is_file():
        raise InputError(f"measurement file not found: {path}")
    return path


def _full_joints(scene: Scene, names: Sequence[str], values: np.ndarray) -> np.ndarray:
    joints = scene.reference.copy()  # joints absent from a recording keep the reference value
    joints[[scene.joint_index(n) for n in names]] = values
    return joints


@dataclass(frozen=True)
class Measurements:
    """A measurement file read: its contacts, its provenance, and the rows that were not usable.

    Example:
        >>> measured = posegen.load("plans/measured.yaml")
        >>> len(measured.contacts.chains), measured.provenance.get("seed")

    """

    contacts: Contacts
    rejected: tuple[str, ...]  # one line per rejected row: "file:line: reason"
    provenance: dict[str, Any]  # what made the file (posegen's format: config, model hash, seed...); CSV: empty


def _parse_row(
    row: list[str], names: list[str], by_recording: dict[str, str], scene: Scene, where: str, tolerance: float
) -> tuple[np.ndarray, str, str]:
    """Joint angles (nj,), chain and spot of one data row.

    Raises:
        InputError: The row is not usable (the message says why).

    """
    if "joint_states" not in row:
        raise InputError(f"{where}: no 'joint_states' field in a data row")
    start = row.index("joint_states") + 1
    cells = row[start : start + len(names)]
    if len(cells) != len(names):
        raise InputError(f"{where}: expected {len(names)} angles, found {len(cells)}")
    try:
        values = np.array([float(c) for c in cells])
    except ValueError:
        bad = next(c for c in cells if not _is_float(c))
        raise InputError(f"{where}: angle field {bad!r} is not a number (shifted column?)") from None
    _check_angles(scene, names, values, where, tolerance)
    gripper = next((c.strip() for c in row[:start] if c.strip() in by_recording), None)
    if gripper is None:
        raise InputError(f"{where}: no known gripper in {row[: start - 1]}; known: {', '.join(sorted(by_recording))}")
    spot = next((c.strip() for c in row[:start] if c.strip().startswith(("table/", "contact"))), "")
    return _full_joints(scene, names, values), by_recording[gripper], spot


def read_csv(path: Path, scene: Scene, session: str, tolerance: float = LIMIT_TOLERANCE_RAD) -> Measurements:
    """Read a recorded CSV file (layout in the module docstring).

    A data row that is not usable (text or out-of-range angles, as a shifted column
    gives; a missing field; an unknown gripper) is reported in ``rejected`` and left out.

    Raises:
        InputError: Unreadable file, no header, an unknown joint, or no usable row.

    """
    try:
        rows = list(csv.reader(read_text_file(path, InputError).splitlines()))
    except csv.Error as exc:
        raise InputError(f"{path}: not a readable CSV file ({exc})") from exc
    header = next((r for r in rows if "joint_names" in r), None)
    if header is None:
        raise InputError(f"{path}: no header row with 'joint_names'")
    names = [c.strip() for c in header[header.index("joint_names") + 1 :] if c.strip()]
    _check_names(scene, names, path)
    by_recording = {c.recorded_as: c.name for c in scene.chains}
    joints, chains, labels, rejected = [], [], [], []
    for line, row in enumerate(rows, start=1):
        if row is header or not any(c.strip() for c in row):
            continue
        try:
            values, chain, spot = _parse_row(row, names, by_recording, scene, f"{path}:{line}", tolerance)
        except InputError as exc:
            rejected.append(str(exc))
            continue
        joints.append(values)
        chains.append(chain)
        labels.append(f"{path.name}:{line}:{spot or 'row'}")
    if not joints:
        first = f": {rejected[0]}" if rejected else ""
        raise InputError(f"{path}: no usable data row ({len(rejected)} rejected){first}")
    for message in rejected:
        LOG.warning("row left out: %s", message)
    made = tuple(chains)
    contacts = Contacts(np.array(joints), made, (session,) * len(chains), tuple(labels), planned_kinds(scene, made))
    return Measurements(contacts, tuple(rejected), {})


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_measurements(path: str | Path, scene: Scene, session: str | None = None) -> Measurements:
    """Read contacts from posegen's format (strict) or a recorded CSV file.

    Args:
        path: The file.
        scene: Scene the joints belong to.
        session: Table session of every contact (CSV default: the file name; YAML
            default: the session saved per contact).

    Raises:
        InputError: The file is missing or malformed.

    """
    path = existing_measurement_file(path)
    if path.suffix.lower() == ".csv":
        return read_csv(path, scene, session or path.stem)
    data = read_yaml(path, MEASUREMENT_FORMAT)
    provenance = _provenance(data, path)
    names = data.get("joint_names")
    raw = data.get("contacts")
    if not isinstance(names, list) or not isinstance(raw, list) or not raw:
        raise InputError(f"{path}: 'joint_names' and a non-empty 'contacts' list are required")
    if not all(isinstance(n, str) for n in names):
        raise InputError(f"{path}: 'joint_names' must be a list of names")
    _check_names(scene, names, path)
    chains_known = {c.name for c in scene.chains}
    kinds_known = ", ".join(k.value for k in registered_kinds())
    joints, chains, sessions, labels, kinds = [], [], [], [], []
    windowed = any(isinstance(item, dict) and not WINDOW_FIELDS.isdisjoint(item) for item in raw)
    for i, item in enumerate(raw):
        where = f"{path}: contact {i}"
        try:
            values = np.array([float(v) for v in item["joints"]])
            chain = str(item["chain"])
        except (KeyError, TypeError, ValueError, OverflowError) as exc:
            raise InputError(f"{where}: malformed ({reason(exc)})") from exc
        _check_contact(item, where, windowed)
        if chain not in chains_known:
            raise InputError(f"{where}: unknown chain '{chain}'; valid chains: {', '.join(sorted(chains_known))}")
        name = str(item.get("kind", scene.chain(chain).contact_kind.value))
        try:
            kind = kind_named(name)
        except ValueError:
            raise InputError(f"{where}: unknown contact kind '{name}'; valid kinds: {kinds_known}") from None
        if kind not in scene.chain(chain).kinds:
            declared = ", ".join(k.value for k in scene.chain(chain).kinds)
            raise InputError(f"{where}: chain '{chain}' makes no {name} contact in this config (it makes: {declared})")
        if len(values) != len(names):
            raise InputError(f"{where}: expected {len(names)} angles, got {len(values)}")
        _check_angles(scene, names, values, where, LIMIT_TOLERANCE_RAD)
        joints.append(_full_joints(scene, names, values))
        chains.append(chain)
        sessions.append(session or str(item.get("session", path.stem)))
        labels.append(f"{path.name}:{i}:{item.get('label', 'row')}")
        kinds.append(kind)
    contacts = Contacts(np.array(joints), tuple(chains), tuple(sessions), tuple(labels), tuple(kinds))
    return Measurements(contacts, (), provenance)


def _check_contact(item: dict[str, Any], where: str, windowed: bool) -> None:
    """A contact's names (session, label), and the window ``measure`` wrote when the file has windows.

    Raises:
        InputError: A name that is not one, or a window field missing or out of its range
            (a truncated or edited file), named.

    """
    for key in ("session", "label"):
        value = item.get(key)
        if value is not None and (isinstance(value, bool) or not isinstance(value, str | int)):
            raise InputError(f"{where}: '{key}' must be a name, got {value!r}")
    if not windowed:
        return
    missing = [key for key in sorted(WINDOW_FIELDS) if key not in item]
    if missing:
        raise InputError(f"{where}: no {', '.join(missing)}, which the other contacts have: a truncated or edited file")
    start, end, samples, spread, force = (item[k] for k in ("start_s", "end_s", "samples", "joint_std_rad", "force_n"))
    if not (is_finite_number(start) and is_finite_number(end) and start <= end):
        raise InputError(f"{where}: start_s {start!r}, end_s {end!r}: expected finite times (s), the start first")
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise InputError(f"{where}: samples {samples!r}: expected a count of 1 or more")
    if not is_finite_number(spread) or spread < 0.0 or not (force is None or is_finite_number(force)):
        raise InputError(f"{where}: joint_std_rad {spread!r}, force_n {force!r}: expected finite numbers")


def _provenance(data: dict[str, Any], path: Path) -> dict[str, Any]:
    provenance = data.get("provenance") or {}
    if not isinstance(provenance, dict):
        raise InputError(f"{path}: 'provenance' must be a mapping")
    return dict(provenance)


def measurement_provenance(path: str | Path) -> dict[str, Any]:
    """The provenance of a file in posegen's measurement format, read before any scene (its config makes one).

    Raises:
        InputError: The file is missing or not in posegen's measurement format.

    """
    return _provenance(read_yaml(existing_measurement_file(path), MEASUREMENT_FORMAT), Path(path))


def measurements_to_dict(scene: Scene, contacts: Contacts, provenance: dict[str, Any]) -> dict[str, Any]:
    """Plain data in posegen's measurement format."""
    return {
        "format": MEASUREMENT_FORMAT,
        "format_version": MEASUREMENT_VERSION,
        "provenance": provenance,
        "joint_names": list(scene.joint_names),
        "contacts": [
            {"chain": c, "session": s, "kind": k.value, "label": lbl, "joints": [float(v) for v in j]}
            for c, s, k, lbl, j in zip(
                contacts.chains, contacts.sessions, contacts.kinds, contacts.labels, contacts.joints, strict=True
            )
        ],
    }


def write_measurements(path: str | Path, scene: Scene, contacts: Contacts, provenance: dict[str, Any]) -> None:
    """Atomically write contacts in posegen's measurement format."""
    write_yaml(path, measurements_to_dict(scene, contacts, provenance))
