"""The URDF ``posegen robot init`` writes beside a draft made from an MJCF model.

The stages read a URDF, so an MJCF model is converted (:func:`posegen.draft.mjcf.convert_mjcf`)
and written next to the draft config, as ``<config stem>.urdf``; the draft names it in
``robot.source.urdf`` with a ``# CHECK:`` line giving the MJCF it came from (path,
SHA-256) and what the URDF does not carry. An existing file there is never
overwritten: it is kept if it holds this very conversion (a re-run), refused otherwise.
If drafting fails, a URDF this run wrote is removed (no URDF without its draft), and
the error names the MJCF file rather than that URDF.
"""

from __future__ import annotations

import contextlib
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from posegen.draft.mjcf import convert_mjcf, is_mjcf
from posegen.draft.mjcf_text import MAX_INCLUDE_DEPTH, flattened_mjcf, parse_xml
from posegen.errors import ConfigError, OutputError
from posegen.io import write_atomic


@dataclass(frozen=True)
class ConvertedSource:
    """The URDF a draft reads, converted from an MJCF model."""

    urdf: Path  # written beside the draft config
    check: str  # the draft's ``# CHECK:`` line about the conversion
    note: str  # what ``robot init`` says about it


def mjcf_source(robot: str) -> Path | None:
    """The MJCF file ``robot`` names, or None (an example-robot-data name, a URDF).

    Example:
        >>> mjcf_source("robot.urdf") is None  # doctest: +SKIP
        True

    """
    path = Path(robot)
    return path if path.is_file() and is_mjcf(path) else None


def mjcf_files(mjcf: Path) -> tuple[Path, ...]:
    """The files a conversion of ``mjcf`` reads: the model, its includes and its mesh files (those that exist).

    A model that cannot be read yields the file alone (its conversion says what is wrong).

    Example:
        >>> mjcf_files(Path("humanoid.xml"))  # doctest: +SKIP
        (PosixPath('humanoid.xml'), PosixPath('/models/materials.xml'))

    """
    found = [mjcf]
    try:
        found += _includes(mjcf, parse_xml(mjcf), 0)
        root = flattened_mjcf(mjcf)
    except ConfigError:
        return tuple(found)
    meshdir = Path(next((c.get("meshdir", "") for c in root.findall("compiler") if c.get("meshdir")), "."))
    found += [meshdir / str(m.get("file")) for m in root.iter("mesh") if (meshdir / str(m.get("file", ""))).is_file()]
    return tuple(dict.fromkeys(found))


def _includes(path: Path, root: ET.Element, depth: int) -> list[Path]:
    """The files ``<include>``d from ``root`` (read from the main file's folder, as MuJoCo does), recursively."""
    found = []
    for element in root.iter("include"):
        included = path.parent / element.get("file", "")
        if included.is_file() and depth < MAX_INCLUDE_DEPTH:
            found += [included, *_includes(path, parse_xml(included), depth + 1)]
    return found


def urdf_beside(output: str | Path) -> Path:
    """Where the URDF converted for the draft ``output`` goes: ``<output stem>.urdf`` beside it.

    Example:
        >>> urdf_beside("configs/h1_table.yaml")
        PosixPath('configs/h1_table.urdf')

    """
    return Path(output).with_suffix(".urdf")


@contextlib.contextmanager
def converted_urdf(mjcf: Path, output: str | Path) -> Iterator[ConvertedSource]:
    """Convert ``mjcf``, write its URDF beside the draft ``output`` (atomically), and remove it if the block fails.

    Args:
        mjcf: The MJCF model.
        output: The draft config to be written.

    Yields:
        The URDF's path, with the draft's ``# CHECK:`` line and a note about it.

    Raises:
        ConfigError: The MJCF cannot be converted (see :func:`~posegen.draft.mjcf.convert_mjcf`).
        OutputError: The URDF's place is ``output`` itself, or holds another file.

    Example:
        >>> with converted_urdf(Path("humanoid.xml"), "configs/h.yaml") as source:  # doctest: +SKIP
        ...     draft = draft_robot(str(source.urdf))

    """
    urdf = urdf_beside(output).absolute()
    if urdf == Path(output).absolute():
        raise OutputError(
            f"{output}: the draft's name ends in .urdf, where its converted URDF goes: give an output ending in .yaml",
            parameter="output",
        )
    converted = convert_mjcf(mjcf)
    created = not urdf.exists()
    if not created and urdf.read_bytes() != converted.text.encode():
        raise OutputError(
            f"{urdf} exists and is not this MJCF's conversion: not overwriting it (move it, or give another output)",
            parameter="output",
        )
    if created:
        write_atomic(urdf, converted.text)
    dropped = "; ".join(converted.dropped) or "nothing"
    check = (
        f"robot.source.urdf was converted by posegen from the MJCF {converted.mjcf} (sha256 {converted.sha256}); "
        f"the stages read the URDF, not the MJCF: re-run robot init if the MJCF changes. Not carried: {dropped} "
        "(nor ever joint damping, armature, friction; infinite speed limits are written as 0)"
    )
    try:
        yield ConvertedSource(urdf, check, f"MJCF {mjcf} converted to {urdf}")
    except BaseException as exc:
        if created:
            urdf.unlink(missing_ok=True)
        if isinstance(exc, ConfigError) and str(urdf) in str(exc):  # the user's file named, not the URDF removed
            raise ConfigError(str(exc).replace(str(urdf), str(mjcf)), parameter=exc.parameter) from exc
        raise
