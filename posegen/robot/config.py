"""Typed configuration of a robot-and-table scene, loaded and validated once.

Every robot-specific name (frames, joints, chains, table) comes from a YAML file in
``configs/``; this module turns it into frozen dataclasses. Structural errors (missing
keys, wrong types, bad numbers) are reported here; names are checked against the
robot model by :class:`posegen.robot.scene.Scene`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from posegen.arguments import is_finite_number
from posegen.errors import ConfigError
from posegen.io import load_yaml_file
from posegen.resources import shipped_path
from posegen.robot.additions import (
    CollisionConfig,
    FrameConfig,
    additions_to_dict,
    read_collision,
    read_frames,
    read_velocity_limits,
)
from posegen.robot.calibration_config import CalibrationConfig, calibration_to_dict, parse_calibration
from posegen.robot.chain_config import CHAIN_DEFAULTS, ChainConfig, read_chain, require_distinct
from posegen.robot.config_reader import Reader
from posegen.robot.config_sections import (
    FIELD_MAXIMA,
    POSITIVE_FIELDS,
    MarginConfig,
    SamplingConfig,
    TableConfig,
    read_margins,
    read_sampling,
    read_table,
)

PACKAGE_URI = "package://"


@dataclass(frozen=True)
class RobotSource:
    """Where the robot model comes from: an example-robot-data name or URDF/SRDF paths.

    With ``example_robot_data``, ``srdf`` may name another SRDF than the loader's: a
    path, or a ``package://`` URI resolved in the package dirs. No SRDF is needed: without
    one, the reference posture and the disabled collision pairs come from the config.
    """

    example_robot_data: str | None = None
    urdf: str | None = None
    srdf: str | None = None
    package_dirs: tuple[str, ...] = ()


@dataclass(frozen=True)
class StanceConfig:
    """Both feet flat on the floor at the poses of a reference posture."""

    reference_posture: str  # an SRDF group state; "" for every joint at 0
    sole_frames: tuple[str, str]  # the first is the anchor the floating base is solved from
    foot_x_m: tuple[float, float]  # sole rectangle along the sole frame's x
    foot_y_m: tuple[float, float]  # sole rectangle along the sole frame's y
    floor_contact_frames: tuple[str, ...]  # links allowed to touch the floor
    reference_joints: dict[str, float] = dataclasses.field(default_factory=dict)  # rad, overriding the state
    root_rpy_deg: tuple[float, float, float] | None = None  # root orientation at the reference (a y-up model)

    @property
    def foot_centre_m(self) -> tuple[float, float]:
        """The sole rectangle's centre (x, y), m, in the sole frame."""
        (x0, x1), (y0, y1) = self.foot_x_m, self.foot_y_m
        return (x0 + x1) / 2, (y0 + y1) / 2

    @property
    def foot_half_m(self) -> tuple[float, float]:
        """The sole rectangle's half sizes (x, y), m."""
        (x0, x1), (y0, y1) = self.foot_x_m, self.foot_y_m
        return (x1 - x0) / 2, (y1 - y0) / 2


@dataclass(frozen=True)
class RouteConfig:
    """How the contact postures are visited."""

    acceleration_limit_rad_s2: float = 1.5  # every joint
    velocity_scale_free: float = 0.5  # fraction of the URDF velocity limits away from the table
    velocity_scale_near: float = 0.15  # approach and release
    velocity_scale_contact: float = 0.05  # go-to-contact, where force control takes over
    overshoot_m: float = 0.003  # go-to-contact ends this far below the nominal plane
    pre_contact_m: float = 0.01  # approach ends, and go-to-contact starts, this far above it
    hold_s: float = 1.0  # time held in contact
    waypoint_step_rad: float = 0.02  # largest joint change between checked waypoints
    planning_checks: float = 4000  # OMPL budget per free motion, in state checks (repeatable, unlike seconds)
    return_to_start: bool = True  # end the route at the start posture
    contact_force_n: float = 30.0  # normal force the force-controlled contact holds (torques, physics)


@dataclass(frozen=True)
class RecordingConfig:
    """How contacts are found in a recorded session (``posegen measure``)."""

    force_threshold_n: float = 15.0  # wrist force (sensor offset removed) above this: in contact
    speed_threshold_rad_s: float = 0.02  # every joint slower than this: still
    speed_span_s: float = 0.04  # joint speed from position differences over this span
    min_duration_s: float = 0.5  # shorter contact windows are rejected
    trim_s: float = 0.1  # dropped at both ends of a window before averaging (the controller settles)
    max_std_rad: float = 0.001  # a joint varying more than this (std) within a window: too noisy
    max_gap_s: float = 0.02  # shorter interruptions of a window are bridged
    match_tolerance_rad: float = 0.1  # largest joint deviation of a window from the route's planned posture
    match_ratio: float = 0.5  # beyond it, with wrist force: the nearest contact at most this fraction of the next's


@dataclass(frozen=True)
class Config:
    """A whole scene: robot, stance, chains, table, margins, sampling."""

    robot: RobotSource
    locked_joints: dict[str, float]  # rad, held fixed during sampling
    stance: StanceConfig
    chains: tuple[ChainConfig, ...]
    table: TableConfig
    margins: MarginConfig
    sampling: SamplingConfig
    route: RouteConfig = RouteConfig()
    recording: RecordingConfig = RecordingConfig()
    calibration: CalibrationConfig = dataclasses.field(default_factory=CalibrationConfig)
    source_path: str = ""
    frames: tuple[FrameConfig, ...] = ()  # declared frames, added to the description at load
    velocity_limits: dict[str, float] = dataclasses.field(default_factory=dict)  # rad/s, overriding the URDF's
    collision: CollisionConfig = dataclasses.field(default_factory=CollisionConfig)

    def chain(self, name: str) -> ChainConfig:
        """Return the chain called ``name``.

        Raises:
            ConfigError: No chain has that name.

        """
        for chain in self.chains:
            if chain.name == name:
                return chain
        valid = ", ".join(c.name for c in self.chains)
        raise ConfigError(f"unknown chain '{name}'; valid chains: {valid}")

    @property
    def contact_collision_margin_m(self) -> float:
        """Collision margin during contact segments: the margin less the commanded overshoot."""
        return max(self.margins.collision_m - self.route.overshoot_m, 0.0)

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form, as saved in every artefact (re-loadable by :func:`parse_config`)."""
        source = {k: v for k, v in dataclasses.asdict(self.robot).items() if v not in (None, ())}
        chains = {}
        for chain in self.chains:
            fields = dataclasses.asdict(chain)
            fields["contact_kind"] = chain.contact_kind.value
            for key in ("contact_kind", "point_frame", "point_radius_m", "point_cone_deg"):
                if fields[key] == CHAIN_DEFAULTS[key] or (key != "contact_kind" and not chain.point_frame):
                    del fields[key]  # a flush-only chain saves as before
            if not chain.touching_links:
                del fields["touching_links"]
            if not chain.wrench_frame:
                del fields["wrench_frame"]
            for key in ("tool_mass_kg", "tool_com_m"):
                if fields[key] is None:
                    del fields[key]
            chains[fields.pop("name")] = fields
        stance = dataclasses.asdict(self.stance)
        if not stance["reference_joints"]:
            del stance["reference_joints"]  # only what a config says: older artefacts stay identical
        if stance["root_rpy_deg"] is None:
            del stance["root_rpy_deg"]
        margins = dataclasses.asdict(self.margins)
        for key, unset in (("joint_limit_rad_by_joint", {}), ("com_uncertainty_m", 0.0), ("table_clearance_m", 0.0)):
            if margins[key] == unset:
                del margins[key]  # only what a config says: older artefacts stay identical
        robot = {"source": source, "locked_joints": dict(self.locked_joints)}
        robot.update(additions_to_dict(self.frames, self.velocity_limits, self.collision))
        data = {
            "robot": robot,
            "stance": stance,
            "chains": chains,
            "table": dataclasses.asdict(self.table),
            "margins": margins,
            "sampling": dataclasses.asdict(self.sampling),
            "route": dataclasses.asdict(self.route),
            "recording": dataclasses.asdict(self.recording),
            "calibration": calibration_to_dict(self.calibration),
        }
        return dict(_plain(data))


def _plain(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def parse_config(data: Any, source_path: str = "") -> Config:
    """Build a :class:`Config` from plain data (a parsed YAML document).

    Each section is read by its own step (:func:`read_source`, :func:`read_stance`,
    :func:`read_chains`, :func:`read_table`, :func:`read_margins`, :func:`read_sampling`, ...).

    Raises:
        ConfigError: A field is missing, of the wrong type or out of range.

    """
    top = Reader(data, "")
    top.keys_within(TOP_KEYS)
    robot = top.sub("robot")
    source = read_source(robot.sub("source"), source_path)
    robot.keys_within(("source", "locked_joints", "frames", "velocity_limits_rad_s", "collision"))
    locked = robot.raw("locked_joints", {})
    if not isinstance(locked, dict) or not all(is_finite_number(v) for v in locked.values()):
        raise ConfigError("robot.locked_joints: expected a mapping joint name -> angle (rad)")
    stance = read_stance(top.sub("stance"))
    chains = read_chains(top)
    table, margins = read_table(top.sub("table"), chains), read_margins(top.sub("margins"))
    if margins.table_clearance_m >= table.approach_standoff_m:
        raise ConfigError(
            f"margins.table_clearance_m: must be below table.approach_standoff_m ({table.approach_standoff_m} m), "
            f"where free motions start, got {margins.table_clearance_m}"
        )
    return Config(
        robot=source,
        locked_joints={str(k): float(v) for k, v in locked.items()},
        stance=stance,
        chains=chains,
        table=table,
        margins=margins,
        sampling=read_sampling(top.sub("sampling")),
        route=_route(top),
        recording=_recording(top),
        calibration=parse_calibration(top.raw("calibration", None)),
        source_path=source_path,
        frames=read_frames(robot),
        velocity_limits=read_velocity_limits(robot),
        collision=read_collision(robot),
    )


def read_source(src: Reader, source_path: str = "") -> RobotSource:
    """``robot.source``; relative paths are made absolute from the config file's folder (else the working one).

    Raises:
        ConfigError: Neither or both of example_robot_data and urdf, or a path with a NUL.

    """
    base = Path(source_path).parent if source_path else Path.cwd()

    def absolute(value: str | None) -> str | None:
        if value is not None and "\0" in value:
            raise ConfigError(f"robot.source: {value!r} is not a valid path")
        if value is None or value.startswith(PACKAGE_URI):  # package:// is resolved with the package dirs
            return value
        return str((base / value).resolve())

    source = RobotSource(
        example_robot_data=src.optional_text("example_robot_data"),
        urdf=absolute(src.optional_text("urdf")),
        srdf=absolute(src.optional_text("srdf")),
        package_dirs=tuple(str(absolute(d)) for d in src.texts("package_dirs", [])),
    )
    if (source.example_robot_data is None) == (source.urdf is None):
        raise ConfigError("robot.source: give either example_robot_data or urdf")
    return source


def read_stance(st: Reader) -> StanceConfig:
    """The ``stance`` section.

    Raises:
        ConfigError: Not two different sole frames, an unknown key, a malformed field or a sole
            rectangle beyond ``MAX_FOOT_M`` of its frame.

    """
    st.keys_within(tuple(f.name for f in dataclasses.fields(StanceConfig)))
    soles = st.texts("sole_frames")
    if len(soles) != 2 or soles[0] == soles[1]:
        raise ConfigError(f"stance.sole_frames: expected two different sole frames, got {list(soles)}")
    return StanceConfig(
        reference_posture=str(st.raw("reference_posture", "") or ""),
        sole_frames=(soles[0], soles[1]),
        foot_x_m=st.interval("foot_x_m", MAX_FOOT_M),
        foot_y_m=st.interval("foot_y_m", MAX_FOOT_M),
        floor_contact_frames=st.texts("floor_contact_frames"),
        reference_joints=st.angles("reference_joints"),
        root_rpy_deg=_root_rpy(st),
    )


def read_chains(top: Reader) -> tuple[ChainConfig, ...]:
    """The ``chains`` section, in the file's order.

    Raises:
        ConfigError: No chains, a malformed chain, or two sharing a contact frame, recording name or wrench topic.

    """
    chains_raw = top.raw("chains")
    if not isinstance(chains_raw, dict) or not chains_raw:
        raise ConfigError("chains: expected a mapping chain name -> chain settings")
    chains = tuple(read_chain(top.sub("chains").sub(str(name)), str(name)) for name in chains_raw)
    require_distinct(chains)
    return chains


def _root_rpy(stance: Reader) -> tuple[float, float, float] | None:
    """``stance.root_rpy_deg``: the root's roll, pitch, yaw (deg) at the reference, or None."""
    if stance.raw("root_rpy_deg", None) is None:
        return None
    roll, pitch, yaw = stance.numbers("root_rpy_deg", 3)
    return (roll, pitch, yaw)


MAX_FOOT_M = 0.5  # m: a sole rectangle reaches at most this far from its sole frame (a humanoid's foot: ~0.1-0.15)

TOP_KEYS = ("robot", "stance", "chains", "table", "margins", "sampling", "route", "recording", "calibration")
"""The sections of a config file (a misspelt one would otherwise be ignored)."""

_Section = TypeVar("_Section", RouteConfig, RecordingConfig)


def _route(top: Reader) -> RouteConfig:
    """The ``route`` section; the velocity scales are fractions of the URDF's limits, at most 1."""
    route = _section(top, "route", RouteConfig())
    for name in ("velocity_scale_free", "velocity_scale_near", "velocity_scale_contact"):
        scale = getattr(route, name)
        if scale > 1.0:
            raise ConfigError(f"route.{name}: a fraction of the URDF velocity limits, at most 1, got {scale:g}")
    return route


def _recording(top: Reader) -> RecordingConfig:
    """The ``recording`` section; ``match_ratio`` is a fraction below 1 (0: the tolerance alone)."""
    recording = _section(top, "recording", RecordingConfig())
    if recording.match_ratio >= 1.0:
        raise ConfigError(f"recording.match_ratio: expected a fraction below 1, got {recording.match_ratio:g}")
    return recording


def _section(top: Reader, key: str, defaults: _Section) -> _Section:
    """An optional section of numbers and flags; absent keys keep their defaults.

    Every number is finite and >= 0; those a zero would divide by (``POSITIVE_FIELDS``) are > 0.
    """
    if key not in top.data:
        return defaults
    reader = top.sub(key)
    fields = dataclasses.asdict(defaults)
    values: dict[str, Any] = {}
    for name, default in fields.items():
        if isinstance(default, bool):
            flag = reader.raw(name, default)
            if not isinstance(flag, bool):
                raise ConfigError(f"{key}.{name}: expected true or false, got {flag!r}")
            values[name] = flag
        else:
            values[name] = reader.number(name, default, minimum=0.0, maximum=FIELD_MAXIMA.get(name))
            if name in POSITIVE_FIELDS and values[name] == 0.0:
                raise ConfigError(f"{key}.{name}: must be > 0, got 0")
    reader.keys_within(tuple(fields))
    return dataclasses.replace(defaults, **values)


def load_config(path: str | Path) -> Config:
    """Load and validate a scene configuration file.

    A relative path into ``configs/`` that does not exist from here is read from
    posegen's copy of that folder (:func:`posegen.resources.shipped_path`).

    Raises:
        ConfigError: The file is missing, not YAML, or not a valid configuration.

    """
    path = shipped_path(path)  # a shipped config (configs/...) is found outside the checkout too
    data = load_yaml_file(path, ConfigError)
    kind = data.get("format") if isinstance(data, dict) else None
    if isinstance(kind, str) and "robot" not in data:  # an artefact (a pool, a route...) given for its config
        raise ConfigError(f"{path}: a {kind} file, not a scene config (a config has 'robot', 'stance', 'chains'...)")
    try:
        return parse_config(data, str(path))
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from exc
