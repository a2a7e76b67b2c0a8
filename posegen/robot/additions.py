"""What a config adds to a robot description, applied at load and never written to its files.

A robot description rarely has everything posegen needs: a frame at the point a hand
touches the table, velocity limits on every joint (some URDFs give 0 or 100 rad/s),
collision pairs that touch at rest and must not be checked, or collision shapes that
match the kinematics. The config declares them under ``robot:``; this module holds
their typed form and reads them. Names are checked against the model by the scene.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Any

from posegen.errors import ConfigError
from posegen.robot.config_reader import Reader

Vector3 = tuple[float, float, float]


class PairReason(str, enum.Enum):
    """Why a collision pair is not checked (the categories of MoveIt's setup assistant)."""

    ADJACENT = "adjacent"  # links joined by a joint (or through links without geometry)
    DEFAULT = "default"  # touching at the reference posture: the meshes overlap at rest
    ALWAYS = "always"  # touching in (almost) every random posture
    USER = "user"  # declared by hand


@dataclass(frozen=True)
class FrameConfig:
    """A frame the description lacks, fixed to an existing one (e.g. a point on a hand)."""

    name: str
    parent: str  # an existing link
    xyz_m: Vector3  # origin in the parent frame
    rpy_deg: Vector3 = (0.0, 0.0, 0.0)  # URDF roll, pitch, yaw in the parent frame


@dataclass(frozen=True)
class DisabledPair:
    """Two links whose collision geometries are never checked against each other."""

    link_a: str
    link_b: str
    reason: PairReason = PairReason.USER


@dataclass(frozen=True)
class Capsule:
    """A capsule in a link's frame: the segment from ``from_m`` to ``to_m``, swept by a sphere."""

    link: str
    from_m: Vector3
    to_m: Vector3
    radius_m: float


@dataclass(frozen=True)
class Box:
    """A box in a link's frame."""

    link: str
    center_m: Vector3
    size_m: Vector3  # along the box's own axes
    rpy_deg: Vector3 = (0.0, 0.0, 0.0)  # the box's orientation in the link frame


@dataclass(frozen=True)
class VisualHull:
    """The convex hull of each of a link's visual meshes, as its collision geometry."""

    link: str


Shape = Capsule | Box | VisualHull


@dataclass(frozen=True)
class CollisionConfig:
    """Collision pairs not checked, and links whose URDF collision geometry is replaced."""

    disabled_pairs: tuple[DisabledPair, ...] = ()
    shapes: tuple[Shape, ...] = ()  # a link listed here keeps only these shapes

    def replaced_links(self) -> set[str]:
        """Links whose URDF collision geometry the config replaces."""
        return {shape.link for shape in self.shapes}


def read_frames(robot: Reader) -> tuple[FrameConfig, ...]:
    """``robot.frames``: name -> {parent, xyz_m, rpy_deg}."""
    if "frames" not in robot.data:
        return ()
    frames = robot.sub("frames")
    out = []
    for name in frames.data:
        entry = frames.sub(str(name))
        entry.keys_within(("parent", "xyz_m", "rpy_deg"))
        out.append(
            FrameConfig(
                name=str(name),
                parent=entry.text("parent"),
                xyz_m=_vector(entry, "xyz_m"),
                rpy_deg=_vector(entry, "rpy_deg", (0.0, 0.0, 0.0)),
            )
        )
    return tuple(out)


def read_velocity_limits(robot: Reader) -> dict[str, float]:
    """``robot.velocity_limits_rad_s``: joint -> rad/s, each positive."""
    limits = robot.angles("velocity_limits_rad_s")
    for joint, value in limits.items():
        if value <= 0:
            raise ConfigError(f"robot.velocity_limits_rad_s.{joint}: must be > 0 rad/s, got {value}")
    return limits


def read_collision(robot: Reader) -> CollisionConfig:
    """``robot.collision``: ``disabled_pairs`` ([link, link, reason]) and ``shapes`` (link -> list)."""
    if "collision" not in robot.data:
        return CollisionConfig()
    section = robot.sub("collision")
    section.keys_within(("disabled_pairs", "shapes"))
    pairs = []
    raw_pairs = section.raw("disabled_pairs", [])
    if not isinstance(raw_pairs, list):
        raise ConfigError("robot.collision.disabled_pairs: expected a list of [link, link, reason]")
    valid = ", ".join(r.value for r in PairReason)
    for k, item in enumerate(raw_pairs):
        where = f"robot.collision.disabled_pairs[{k}]"
        ok = isinstance(item, list) and len(item) in (2, 3) and all(isinstance(v, str) and v for v in item)
        if not ok:
            raise ConfigError(f"{where}: expected [link, link] or [link, link, reason], got {item!r}")
        if item[0] == item[1]:
            raise ConfigError(f"{where}: '{item[0]}' paired with itself (a link is never checked against itself)")
        reason = item[2] if len(item) == 3 else PairReason.USER.value
        if reason not in {r.value for r in PairReason}:
            raise ConfigError(f"{where}: unknown reason '{reason}'; valid reasons: {valid}")
        pairs.append(DisabledPair(item[0], item[1], PairReason(reason)))
    shapes: list[Shape] = []
    if "shapes" in section.data:
        by_link = section.sub("shapes")
        for link in by_link.data:
            shapes.extend(_read_shapes(by_link, str(link)))
    return CollisionConfig(disabled_pairs=tuple(pairs), shapes=tuple(shapes))


def _read_shapes(by_link: Reader, link: str) -> list[Shape]:
    items = by_link.raw(link)
    where = f"{by_link.where}.{link}"
    if not isinstance(items, list) or not items:
        raise ConfigError(f"{where}: expected a list of shapes ({{capsule: ...}}, {{box: ...}}, {{visual_hull: {{}}}})")
    out: list[Shape] = []
    for k, item in enumerate(items):
        if not isinstance(item, dict) or len(item) != 1 or next(iter(item)) not in ("capsule", "box", "visual_hull"):
            raise ConfigError(
                f"{where}[{k}]: expected {{capsule: {{...}}}}, {{box: {{...}}}} or {{visual_hull: {{}}}}, got {item!r}"
            )
        kind = next(iter(item))
        entry = Reader(item[kind] if item[kind] is not None else {}, f"{where}[{k}].{kind}")
        if kind == "visual_hull":
            entry.keys_within(())
            out.append(VisualHull(link))
        elif kind == "capsule":
            entry.keys_within(("from_m", "to_m", "radius_m"))
            out.append(Capsule(link, _vector(entry, "from_m"), _vector(entry, "to_m"), _positive(entry, "radius_m")))
        else:
            entry.keys_within(("center_m", "size_m", "rpy_deg"))
            size = _vector(entry, "size_m")
            if min(size) <= 0:
                raise ConfigError(f"{entry.where}.size_m: every dimension must be positive")
            out.append(Box(link, _vector(entry, "center_m"), size, _vector(entry, "rpy_deg", (0.0, 0.0, 0.0))))
    return out


def additions_to_dict(
    frames: tuple[FrameConfig, ...], velocity_limits: dict[str, float], collision: CollisionConfig
) -> dict[str, Any]:
    """Plain-data form of the additions (only those present), re-readable by the ``read_*`` functions."""
    out: dict[str, Any] = {}
    if frames:
        out["frames"] = {
            f.name: {"parent": f.parent, "xyz_m": list(f.xyz_m), "rpy_deg": list(f.rpy_deg)} for f in frames
        }
    if velocity_limits:
        out["velocity_limits_rad_s"] = dict(velocity_limits)
    section: dict[str, Any] = {}
    if collision.disabled_pairs:
        section["disabled_pairs"] = [[p.link_a, p.link_b, p.reason.value] for p in collision.disabled_pairs]
    if collision.shapes:
        shapes: dict[str, list[dict[str, Any]]] = {}
        for shape in collision.shapes:
            if isinstance(shape, Capsule):
                entry: dict[str, Any] = {
                    "capsule": {"from_m": list(shape.from_m), "to_m": list(shape.to_m), "radius_m": shape.radius_m}
                }
            elif isinstance(shape, VisualHull):
                entry = {"visual_hull": {}}
            else:
                box = {"center_m": list(shape.center_m), "size_m": list(shape.size_m), "rpy_deg": list(shape.rpy_deg)}
                entry = {"box": box}
            shapes.setdefault(shape.link, []).append(entry)
        section["shapes"] = shapes
    if section:
        out["collision"] = section
    return out


def _vector(reader: Reader, key: str, default: Any = ...) -> Vector3:
    x, y, z = reader.numbers(key, 3, list(default) if isinstance(default, tuple) else default)
    return (x, y, z)


def _positive(reader: Reader, key: str) -> float:
    value = reader.number(key)
    if value <= 0:
        raise ConfigError(f"{reader.where}.{key}: must be > 0, got {value}")
    return value
