"""What ``posegen view`` opens: a pool, a selection, a route or a calibration folder.

Each is read through the public reader of the layer that owns its format (postures and
routes from :mod:`posegen.robot`, calibrations from :mod:`posegen.calibrate`), so a
format change lands in one place. The scene is the one saved in the artefact (or
``--config``), checked against the artefact's robot model hash.
"""

from __future__ import annotations

import enum
import hashlib
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from posegen.calibrate import CALIBRATION_FORMAT, CalibrationRecord, read_calibration
from posegen.errors import InputError
from posegen.io import (
    POOL_FORMAT,
    SELECTION_FORMAT,
    Pool,
    Segment,
    is_route_file,
    load_yaml_file,
    pool_from_dict,
    postures_from_dict,
    postures_of,
    read_route,
    read_yaml,
)
from posegen.robot import FloatArray, Scene, load_config, scene_for

LOG = logging.getLogger(__name__)


class ArtefactKind(str, enum.Enum):
    """The kinds of artefact ``posegen view`` shows."""

    POOL = "pool"
    SELECTION = "selection"
    ROUTE = "route"
    CALIBRATION = "calibration"


@dataclass(frozen=True)
class PosturesArtefact:
    """A pool or a selection: postures to step through."""

    kind: ArtefactKind
    path: Path
    scene: Scene
    postures: Pool
    entries: tuple[dict[str, Any], ...]  # the postures' plain data (a selection's rank, weight, pool_id)
    pool: Pool | None  # a selection's pool, when its file is still there unchanged


@dataclass(frozen=True)
class RouteArtefact:
    """A timed route."""

    path: Path
    scene: Scene
    times: FloatArray  # (m,) s
    positions: FloatArray  # (m, nj) rad, in the scene's joint order
    segments: tuple[Segment, ...]
    selection: Pool | None  # the selection it routes, when its file is still there unchanged
    skipped: tuple[dict[str, Any], ...]  # {posture, pool_id, reason}


@dataclass(frozen=True)
class CalibrationArtefact:
    """A calibration folder: the nominal and the calibrated robot, and the contacts."""

    path: Path
    nominal: Scene
    calibrated: Scene
    record: CalibrationRecord


Artefact = PosturesArtefact | RouteArtefact | CalibrationArtefact


def _linked_file(recorded: Any, sha256: Any, beside: Path) -> Path | None:
    """A file an artefact names (as written, or relative to the artefact), if its hash still matches."""
    if not isinstance(recorded, str):
        return None
    for candidate in (Path(recorded), beside.parent / Path(recorded).name):
        if candidate.is_file():
            if sha256 and hashlib.sha256(candidate.read_bytes()).hexdigest() != sha256:
                LOG.info("%s changed since %s was made: not shown", candidate, beside)
                return None
            return candidate
    return None


def _postures(path: Path, data: dict[str, Any], config_path: str | None) -> PosturesArtefact:
    chosen, entries = postures_from_dict(data, str(path))
    scene = scene_for(chosen.provenance, config_path)
    scene.check_made_for(chosen.provenance, str(path))
    chosen.check_joints(scene.joint_names, str(path))
    chosen.check_names([c.name for c in scene.config.chains], [s.name for s in scene.spots], str(path))
    selection = data["format"] == SELECTION_FORMAT
    pool = None
    if selection:
        pool_path = _linked_file(chosen.provenance.get("pool"), chosen.provenance.get("pool_sha256"), path)
        pool = pool_from_dict(read_yaml(pool_path, POOL_FORMAT), str(pool_path)) if pool_path else None
    return PosturesArtefact(
        kind=ArtefactKind.SELECTION if selection else ArtefactKind.POOL,
        path=path,
        scene=scene,
        postures=chosen,
        entries=tuple(entries),
        pool=pool,
    )


def _route(path: Path, config_path: str | None) -> RouteArtefact:
    route = read_route(path)
    scene = scene_for(route.provenance, config_path)
    scene.check_made_for(route.provenance, str(path))
    order = route.joint_columns(scene.joint_names, str(path))
    route.check_chains([c.name for c in scene.config.chains], str(path))
    recorded = route.provenance
    selection_path = _linked_file(recorded.get("selection"), recorded.get("selection_sha256"), path)
    selection = None
    if selection_path is not None:
        selection = postures_of(read_yaml(selection_path, (POOL_FORMAT, SELECTION_FORMAT)), str(selection_path))
    return RouteArtefact(
        path=path,
        scene=scene,
        times=route.times,
        positions=np.ascontiguousarray(route.positions[:, order]),
        segments=route.segments,
        selection=selection,
        skipped=route.skipped,
    )


def _calibration(path: Path, config_path: str | None) -> CalibrationArtefact:
    record = read_calibration(path)
    nominal = scene_for(record.provenance, config_path)
    nominal.check_made_for(record.provenance, str(path))
    calibrated = Scene(load_config(str(record.calibrated_config)))
    if calibrated.joint_names != nominal.joint_names:
        raise InputError(f"{record.calibrated_config}: not the same joints as the nominal robot")
    chains = [c.name for c in calibrated.chains]
    for contact in record.contacts:
        if contact.chain not in chains:
            raise InputError(f"{path}: a residual of chain {contact.chain!r}; the robot's chains: {', '.join(chains)}")
    return CalibrationArtefact(path=path, nominal=nominal, calibrated=calibrated, record=record)


def open_artefact(path: str | Path, config_path: str | None = None) -> Artefact:
    """Read an artefact to view: a pool, selection or route file, or a calibration folder.

    Args:
        path: The artefact.
        config_path: Scene config to use instead of the one saved in the artefact.

    Raises:
        PosegenError: Missing, malformed, or not an artefact posegen shows; made for
            another robot model.

    """
    path = Path(path)
    if path.is_dir():
        return _calibration(path, config_path)
    if not path.exists():
        raise InputError(f"{path}: no such file or folder (a pool, selection, route or calibration folder)")
    if is_route_file(path):
        return _route(path, config_path)
    data = load_yaml_file(path, InputError)
    found = data.get("format") if isinstance(data, dict) else None
    if found == CALIBRATION_FORMAT:
        return _calibration(path.parent, config_path)
    if found not in (POOL_FORMAT, SELECTION_FORMAT):
        raise InputError(f"{path}: not a pool, selection or route file, nor a calibration folder (format: {found!r})")
    return _postures(path, data, config_path)
