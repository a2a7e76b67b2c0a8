"""Contact postures and the files that carry them from stage to stage (pool, selection).

A pool file is what ``posegen pool`` makes and ``select``, ``route`` and ``simulate``
read; a selection file reads like a pool plus the selection's fields (written by
:mod:`posegen.select`), so every reader of postures takes either.

Pool file format (YAML, ``format: posegen-pool``)::

    format: posegen-pool
    format_version: 1
    provenance: {posegen_version, robot_model_sha256, seed, config}
    joint_names: [...]          # order of every ``joints`` list
    summary: {attempted, accepted, rejected: {reason: count}, per_spot: {spot: {chain: count}}}
    postures:
      - {id, sample, chain, spot, joints: [rad...], contact_xy_m: [x, y] (table frame),
         contact_yaw_rad, min_distance_m, com_margin_m}
"""

from __future__ import annotations

import collections
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from posegen.errors import InputError
from posegen.io import read_yaml
from posegen.robot.geometry import FloatArray

POOL_FORMAT = "posegen-pool"
SELECTION_FORMAT = "posegen-selection"  # a pool's fields plus the selection's (posegen.select.report)
POOL_VERSION = 1


@dataclass(frozen=True)
class Posture:
    """A feasible contact posture."""

    sample: int  # index of the random sample it came from
    chain: str
    spot: str
    joints: tuple[float, ...]  # rad, in the scene's joint order
    contact_xy_m: tuple[float, float]  # contact frame origin in the table frame
    contact_yaw_rad: float  # contact frame yaw in the table frame
    min_distance_m: float  # closest pair of bodies (convex hulls)
    com_margin_m: float  # CoM projection's distance inside the support polygon


@dataclass(frozen=True)
class Pool:
    """Feasible contact postures with their provenance."""

    joint_names: tuple[str, ...]
    postures: tuple[Posture, ...]
    provenance: dict[str, Any]
    attempted: int
    rejected: dict[str, int]

    def joints(self) -> FloatArray:
        """All postures' joint angles (rad). Shape (n, nj)."""
        return np.array([p.joints for p in self.postures], dtype=float).reshape(-1, len(self.joint_names))

    def check_joints(self, joint_names: tuple[str, ...], where: str) -> None:
        """Check that the postures' joints are a robot model's (``joint_names``, in order).

        Raises:
            InputError: They are not.

        """
        if self.joint_names != joint_names:
            raise InputError(f"{where}: joint names differ from the robot model's")

    def per_spot(self) -> dict[str, dict[str, int]]:
        """Number of postures per target spot and chain."""
        counts: dict[str, dict[str, int]] = collections.defaultdict(dict)
        for p in self.postures:
            counts[p.spot][p.chain] = counts[p.spot].get(p.chain, 0) + 1
        return {spot: dict(sorted(c.items())) for spot, c in sorted(counts.items())}

    def to_dict(self) -> dict[str, Any]:
        """Plain data in the pool file format."""
        return {
            "format": POOL_FORMAT,
            "format_version": POOL_VERSION,
            "provenance": self.provenance,
            "joint_names": list(self.joint_names),
            "summary": {
                "attempted": self.attempted,
                "accepted": len(self.postures),
                "rejected": dict(self.rejected),
                "per_spot": self.per_spot(),
            },
            "postures": [
                {
                    "id": i,
                    "sample": p.sample,
                    "chain": p.chain,
                    "spot": p.spot,
                    "joints": list(p.joints),
                    "contact_xy_m": list(p.contact_xy_m),
                    "contact_yaw_rad": p.contact_yaw_rad,
                    "min_distance_m": p.min_distance_m,
                    "com_margin_m": p.com_margin_m,
                }
                for i, p in enumerate(self.postures)
            ],
        }


def posture_from_dict(raw: Any, n_joints: int, where: str) -> Posture:
    """Parse one posture entry (shared by pools and selections).

    Raises:
        InputError: A field is missing or malformed.

    """
    try:
        joints = tuple(float(v) for v in raw["joints"])
        xy = tuple(float(v) for v in raw["contact_xy_m"])
        posture = Posture(
            sample=int(raw["sample"]),
            chain=str(raw["chain"]),
            spot=str(raw["spot"]),
            joints=joints,
            contact_xy_m=(xy[0], xy[1]),
            contact_yaw_rad=float(raw["contact_yaw_rad"]),
            min_distance_m=float(raw["min_distance_m"]),
            com_margin_m=float(raw["com_margin_m"]),
        )
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise InputError(f"{where}: malformed posture ({type(exc).__name__}: {exc})") from exc
    if len(joints) != n_joints or not np.all(np.isfinite(joints)):
        raise InputError(f"{where}: expected {n_joints} finite joint angles, got {len(joints)}")
    return posture


def pool_from_dict(data: dict[str, Any], where: str = "pool") -> Pool:
    """Parse and validate plain data in the pool file format.

    Raises:
        InputError: The data is not a valid pool.

    """
    if data.get("format_version") != POOL_VERSION:
        raise InputError(f"{where}: unsupported format_version {data.get('format_version')!r}")
    names = data.get("joint_names")
    raw_postures = data.get("postures")
    if not isinstance(names, list) or not isinstance(raw_postures, list):
        raise InputError(f"{where}: 'joint_names' and 'postures' must be lists")
    postures = tuple(posture_from_dict(raw, len(names), f"{where}: posture {i}") for i, raw in enumerate(raw_postures))
    summary = data.get("summary") or {}
    return Pool(
        joint_names=tuple(str(n) for n in names),
        postures=postures,
        provenance=dict(data.get("provenance") or {}),
        attempted=int(summary.get("attempted", len(postures))),
        rejected={str(k): int(v) for k, v in (summary.get("rejected") or {}).items()},
    )


def load_pool(path: str | Path) -> Pool:
    """Read a pool file.

    Raises:
        InputError: The file is missing or not a valid pool.

    """
    return pool_from_dict(read_yaml(path, POOL_FORMAT), str(path))


def load_plan(path: str | Path) -> tuple[Pool, list[dict[str, Any]]]:
    """Read a pool or a selection that has postures: the postures, and their entries as plain data.

    Raises:
        InputError: The file is missing, malformed, neither a pool nor a selection, or empty.

    """
    data = read_yaml(path, (POOL_FORMAT, SELECTION_FORMAT))
    plan = pool_from_dict(data, str(path))
    if not plan.postures:
        raise InputError(f"{path}: no postures")
    return plan, list(data["postures"])
