"""Contact postures and the files that carry them from stage to stage (pool, selection).

A pool file is what ``posegen pool`` makes and ``select``, ``route`` and ``simulate``
read; a selection file reads like a pool plus the selection's fields (written by
:mod:`posegen.select`), so every reader of postures takes either.

Pool file format (YAML, ``format: posegen-pool``), version 2 as ``posegen pool`` writes
it: a header, and the postures as arrays in a ``.npz`` sidecar beside it (same stem)::

    format: posegen-pool
    format_version: 2
    provenance: {posegen_version, robot_model_sha256, seed, config}
    joint_names: [...]          # order of the columns of ``joints``
    summary: {attempted, accepted, rejected: {reason: count}, per_spot: {spot: {chain: count}}}
    chains: [...]               # values of the ``chain`` array
    spots: [...]                # values of the ``spot`` array
    arrays: {file: pool.npz, sha256}
    # pool.npz: sample (n,) int64, chain (n,) and spot (n,) indices into the lists above,
    #   joints (n, nj) rad, contact_xy_m (n, 2) table frame, contact_yaw_rad (n,),
    #   min_distance_m (n,), com_margin_m (n,)

Version 1 (read, and written for small artefacts and selections) has the postures inline::

    postures:
      - {id, sample, chain, spot, joints: [rad...], contact_xy_m: [x, y] (table frame),
         contact_yaw_rad, min_distance_m, com_margin_m}
"""

from __future__ import annotations

import collections
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from posegen.errors import InputError, reason, unknown_name
from posegen.io.arrays import read_arrays, write_with_arrays
from posegen.io.artefact import read_yaml
from posegen.numeric import FloatArray

POOL_FORMAT = "posegen-pool"
SELECTION_FORMAT = "posegen-selection"  # its reader: posegen.io.selection_file
POOL_VERSION = 1  # postures inline
POOL_ARRAYS_VERSION = 2  # postures in a .npz sidecar
_SCALARS = ("contact_yaw_rad", "min_distance_m", "com_margin_m")  # float fields, one value per posture
ARRAY_NAMES = ("sample", "chain", "spot", "joints", "contact_xy_m", *_SCALARS)
LIMIT_SLACK_RAD = 1e-6  # a posture this far past a joint limit is still taken as within it


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

    def to_dict(self, row: int) -> dict[str, Any]:
        """The posture as plain data: its entry in a pool or selection file, ``row`` its pool row (``id``).

        Example:
            >>> pool.postures[3].to_dict(3)["chain"]

        """
        return {
            "id": row,
            "sample": self.sample,
            "chain": self.chain,
            "spot": self.spot,
            "joints": list(self.joints),
            "contact_xy_m": list(self.contact_xy_m),
            "contact_yaw_rad": self.contact_yaw_rad,
            "min_distance_m": self.min_distance_m,
            "com_margin_m": self.com_margin_m,
        }


@dataclass(frozen=True)
class Pool:
    """Feasible contact postures with their provenance.

    Example:
        >>> pool = posegen.load("plans/pool.yaml")
        >>> pool.postures[0].joints[:3], len(pool.postures)

    """

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

    def check_names(self, chains: Sequence[str], spots: Sequence[str], where: str) -> None:
        """Check that every posture's chain and spot are the config's (``chains``, ``spots``).

        Raises:
            InputError: The first posture naming another chain or spot, with the valid names.

        """
        for k, posture in enumerate(self.postures):
            for kind, name, valid in (("chain", posture.chain, chains), ("spot", posture.spot, spots)):
                if name not in valid:
                    raise InputError(f"{where}: posture {k}: {unknown_name(kind, name, valid)} (of the config)")

    def check_limits(self, names: tuple[str, ...], lower: FloatArray, upper: FloatArray, where: str) -> None:
        """Check that every posture lies within the joint limits (rad, shape (nj,) each), to 1e-6 rad.

        Raises:
            InputError: One does not; the first is named (``posegen check`` lists them all).

        """
        joints = self.joints()
        outside = (joints < lower - LIMIT_SLACK_RAD) | (joints > upper + LIMIT_SLACK_RAD)
        if outside.any():
            k, j = (int(i) for i in np.argwhere(outside)[0])
            raise InputError(
                f"{where}: posture {k}: {names[j]} = {joints[k, j]:.4f} rad is outside its limits "
                f"[{lower[j]:.4f}, {upper[j]:.4f}] (posegen check lists every violation)"
            )

    def per_spot(self) -> dict[str, dict[str, int]]:
        """Number of postures per target spot and chain."""
        counts: dict[str, dict[str, int]] = collections.defaultdict(dict)
        for p in self.postures:
            counts[p.spot][p.chain] = counts[p.spot].get(p.chain, 0) + 1
        return {spot: dict(sorted(c.items())) for spot, c in sorted(counts.items())}

    def entry(self, index: int) -> dict[str, Any]:
        """One posture as plain data (an entry of ``postures`` in the inline format)."""
        return self.postures[index].to_dict(index)

    def header(self) -> dict[str, Any]:
        """Plain data of everything but the postures."""
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
        }

    def to_dict(self) -> dict[str, Any]:
        """Plain data in the inline pool file format (version 1)."""
        return {**self.header(), "postures": [self.entry(i) for i in range(len(self.postures))]}

    def to_arrays(self) -> tuple[dict[str, Any], dict[str, NDArray[Any]]]:
        """The version-2 header (without its sidecar reference) and the postures as arrays."""
        chains = sorted({p.chain for p in self.postures})
        spots = sorted({p.spot for p in self.postures})
        chain_of = {c: i for i, c in enumerate(chains)}
        spot_of = {s: i for i, s in enumerate(spots)}
        n, nj = len(self.postures), len(self.joint_names)
        arrays: dict[str, NDArray[Any]] = {
            "sample": np.array([p.sample for p in self.postures], dtype=np.int64),
            "chain": np.array([chain_of[p.chain] for p in self.postures], dtype=np.int32),
            "spot": np.array([spot_of[p.spot] for p in self.postures], dtype=np.int32),
            "joints": np.array([p.joints for p in self.postures], dtype=float).reshape(n, nj),
            "contact_xy_m": np.array([p.contact_xy_m for p in self.postures], dtype=float).reshape(n, 2),
            **{f: np.array([getattr(p, f) for p in self.postures], dtype=float) for f in _SCALARS},
        }
        header = {**self.header(), "format_version": POOL_ARRAYS_VERSION, "chains": chains, "spots": spots}
        return header, arrays


def posture_from_dict(raw: Any, n_joints: int, where: str) -> Posture:
    """Parse one posture entry (shared by pools and selections).

    Raises:
        InputError: A field is missing or malformed.

    """
    try:
        if not isinstance(raw["chain"], str) or not isinstance(raw["spot"], str):
            raise TypeError("chain and spot must be names")
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
    except (KeyError, TypeError, ValueError, IndexError, OverflowError) as exc:
        raise InputError(f"{where}: malformed posture ({reason(exc)})") from exc
    if len(joints) != n_joints:
        raise InputError(f"{where}: expected {n_joints} joint angles (one per joint name), got {len(joints)}")
    if not np.all(np.isfinite(joints)):
        raise InputError(f"{where}: joint angle {int(np.argmin(np.isfinite(joints)))} is not a finite number")
    numbers = (*posture.contact_xy_m, posture.contact_yaw_rad, posture.min_distance_m, posture.com_margin_m)
    if len(xy) != 2 or not np.all(np.isfinite(numbers)):
        raise InputError(f"{where}: contact_xy_m (2 values), contact_yaw_rad and the margins must be finite numbers")
    return posture


def _postures_from_arrays(data: dict[str, Any], n_joints: int, where: str) -> tuple[Posture, ...]:
    """Postures of a version-2 pool, read from the sidecar beside the header file ``where``."""
    chains, spots = data.get("chains"), data.get("spots")
    if not isinstance(chains, list) or not isinstance(spots, list):
        raise InputError(f"{where}: 'chains' and 'spots' must be lists")
    arrays = read_arrays(where, data.get("arrays"), ARRAY_NAMES)
    if arrays["sample"].ndim != 1:
        raise InputError(f"{where}: the sidecar's 'sample' is of shape {arrays['sample'].shape}, not one per posture")
    n = len(arrays["sample"])
    shapes = {name: a.shape for name, a in arrays.items()}
    expected = {name: (n,) for name in ARRAY_NAMES} | {"joints": (n, n_joints), "contact_xy_m": (n, 2)}
    if shapes != expected:
        raise InputError(f"{where}: arrays of inconsistent shapes {shapes}; expected {expected}")
    integers = all(np.issubdtype(arrays[name].dtype, np.integer) for name in ("sample", "chain", "spot"))
    numbers = all(_is_real(arrays[name].dtype) for name in ("joints", "contact_xy_m", *_SCALARS))  # not complex
    if not integers or not numbers:
        raise InputError(f"{where}: arrays of the wrong kinds (sample, chain, spot: integers; the rest: real numbers)")
    if not all(isinstance(name, str) for name in (*chains, *spots)):
        raise InputError(f"{where}: 'chains' and 'spots' must be lists of names")
    for name, vocabulary in (("chain", chains), ("spot", spots)):
        codes = arrays[name]
        if n and (codes.min() < 0 or codes.max() >= len(vocabulary)):
            raise InputError(f"{where}: array '{name}' indexes outside its {len(vocabulary)} names")
    floats = np.column_stack([arrays["joints"], arrays["contact_xy_m"], *(arrays[f] for f in _SCALARS)])
    if not np.all(np.isfinite(floats)):
        raise InputError(f"{where}: the arrays hold NaN or infinite values")
    columns = {name: arrays[name].tolist() for name in ("sample", "chain", "spot", *_SCALARS)}
    joints, xy = arrays["joints"].tolist(), arrays["contact_xy_m"].tolist()
    return tuple(
        Posture(
            sample=int(columns["sample"][i]),
            chain=str(chains[columns["chain"][i]]),
            spot=str(spots[columns["spot"][i]]),
            joints=tuple(joints[i]),
            contact_xy_m=(xy[i][0], xy[i][1]),
            contact_yaw_rad=columns["contact_yaw_rad"][i],
            min_distance_m=columns["min_distance_m"][i],
            com_margin_m=columns["com_margin_m"][i],
        )
        for i in range(n)
    )


def pool_from_dict(data: dict[str, Any], where: str = "pool") -> Pool:
    """Parse and validate plain data in the pool file format.

    Args:
        data: The file's content.
        where: The file's path (a version-2 pool's arrays are read beside it), or a
            name for messages.

    Raises:
        InputError: The data is not a valid pool.

    """
    version = data.get("format_version")
    if isinstance(version, bool) or version not in (POOL_VERSION, POOL_ARRAYS_VERSION):
        raise InputError(
            f"{where}: unsupported format_version {version!r} (this posegen reads {POOL_VERSION} and "
            f"{POOL_ARRAYS_VERSION})"
        )
    names = data.get("joint_names")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise InputError(f"{where}: 'joint_names' must be a list of names")
    if version == POOL_ARRAYS_VERSION:
        postures = _postures_from_arrays(data, len(names), where)
    else:
        raw_postures = data.get("postures")
        if not isinstance(raw_postures, list):
            raise InputError(f"{where}: 'postures' must be a list")
        postures = tuple(
            posture_from_dict(raw, len(names), f"{where}: posture {i}") for i, raw in enumerate(raw_postures)
        )
    summary = data.get("summary") or {}
    provenance = data.get("provenance") or {}
    if not isinstance(summary, dict) or not isinstance(provenance, dict):
        raise InputError(f"{where}: 'summary' and 'provenance' must be mappings")
    attempted = summary.get("attempted", len(postures))
    rejected = summary.get("rejected") or {}
    counts = [attempted, *rejected.values()] if isinstance(rejected, dict) else None
    if counts is None or not all(isinstance(c, int) and not isinstance(c, bool) and c >= 0 for c in counts):
        raise InputError(f"{where}: summary: 'attempted' and the 'rejected' counts must be non-negative integers")
    return Pool(
        joint_names=tuple(names),
        postures=postures,
        provenance=dict(provenance),
        attempted=attempted,
        rejected={str(k): v for k, v in rejected.items()},
    )


def _is_real(dtype: np.dtype[Any]) -> bool:
    return bool(np.issubdtype(dtype, np.floating) or np.issubdtype(dtype, np.integer))


def load_pool(path: str | Path) -> Pool:
    """Read a pool file.

    Raises:
        InputError: The file is missing or not a valid pool.

    """
    return pool_from_dict(read_yaml(path, POOL_FORMAT), str(path))


def write_pool(path: str | Path, pool: Pool) -> None:
    """Write a pool file in the current format: YAML header and ``.npz`` sidecar, atomically each."""
    header, arrays = pool.to_arrays()
    write_with_arrays(path, header, arrays)
