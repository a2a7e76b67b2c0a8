"""The scene config's plain sections: the table, the margins, the sampling settings.

Read and validated by :func:`posegen.robot.config.parse_config` (which re-exports them).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np
import numpy.typing as npt

from posegen.errors import ConfigError
from posegen.robot.chain_config import ChainConfig
from posegen.robot.config_reader import Reader

# Route and recording fields a zero would divide by or make meaningless (a route of infinite seconds, a hold at 0 N).
POSITIVE_FIELDS = frozenset(
    [
        "acceleration_limit_rad_s2",
        "velocity_scale_free",
        "velocity_scale_near",
        "velocity_scale_contact",
        "waypoint_step_rad",
        "planning_checks",
        "contact_force_n",
        "force_threshold_n",
        "speed_threshold_rad_s",
        "speed_span_s",
        "max_std_rad",
        "match_tolerance_rad",
    ]
)
FIELD_MAXIMA = {
    "hold_s": 600.0,  # s: a contact held longer is no calibration step (a route must end within 1e6 s)
    "waypoint_step_rad": 0.2,  # rad: beyond it, a hand 0.6 m from its shoulder moves 12 cm between collision checks
}


@dataclass(frozen=True)
class TableConfig:
    """A flat table: box whose top face holds the contact spots."""

    top_center_m: tuple[float, float, float]  # world position of the top face's centre
    yaw_deg: float
    size_m: tuple[float, float, float]  # length (x), width (y), thickness (z)
    spots_x_m: tuple[float, ...]  # grid of target spots, table frame
    spots_y_m: tuple[float, ...]
    approach_standoff_m: float


@dataclass(frozen=True)
class MarginConfig:
    """Safety margins of feasibility."""

    com_m: float  # CoM ground projection inside the support polygon by at least this
    collision_m: float  # minimum distance between bodies that must not touch
    joint_limit_rad: float  # distance kept from every joint limit
    effort_ratio: float = 0.9  # planned static torques within this fraction of the URDF effort limits
    zmp_m: float = 0.01  # the ZMP at the planned timing inside the support polygon by at least this
    com_uncertainty_m: float = 0.0  # the true CoM may lie this far from the model's (x and y): torques hold either way
    joint_limit_rad_by_joint: dict[str, float] = field(default_factory=dict)  # joint -> a larger margin, rad
    table_clearance_m: float = 0.0  # in free motions every body stays this far above the table (0: collision_m)


def leaves_no_room(lower: npt.ArrayLike, upper: npt.ArrayLike, margin: npt.ArrayLike) -> npt.NDArray[np.bool_]:
    """Whether keeping ``margin`` (rad) from both limits leaves a joint no room: a range of at most twice it.

    Element-wise over arrays of joints (the scene's margins) or for one joint (a draft's arm end).

    Example:
        >>> bool(leaves_no_room(0.0, 0.02, 0.01))
        True

    """
    return np.asarray(np.subtract(upper, lower) <= 2.0 * np.asarray(margin))


@dataclass(frozen=True)
class SamplingConfig:
    """Settings of the Gauss-Newton projection of random samples."""

    soft_iterations: int  # iterations with every task soft
    hard_iterations: int  # iterations with feet and contact hard
    spot_tolerance_m: float  # accepted distance of the contact point from its target spot
    chunk_size: int  # samples per unit of work (checkpointing and parallelism)


def read_table(tb: Reader, chains: tuple[ChainConfig, ...]) -> TableConfig:
    """The ``table`` section: every spot on the table and served by a chain.

    Raises:
        ConfigError: A size not positive, a spot off the table or one no chain's ``spot_y_range_m`` covers.

    """
    tb.keys_within(tuple(f.name for f in fields(TableConfig)))
    size = tb.numbers("size_m", 3)
    if min(size) <= 0:
        raise ConfigError("table.size_m: every dimension must be positive")
    top_center = tb.numbers("top_center_m", 3)
    table = TableConfig(
        top_center_m=(top_center[0], top_center[1], top_center[2]),
        yaw_deg=tb.number("yaw_deg", 0.0, minimum=-360.0, maximum=360.0),
        size_m=(size[0], size[1], size[2]),
        spots_x_m=tb.numbers("spots_x_m"),
        spots_y_m=tb.numbers("spots_y_m"),
        approach_standoff_m=tb.number("approach_standoff_m", minimum=0.0),
    )
    for value, half, axis in ((table.spots_x_m, size[0] / 2, "x"), (table.spots_y_m, size[1] / 2, "y")):
        if any(abs(v) > half for v in value):
            raise ConfigError(f"table.spots_{axis}_m: spots must lie on the table (|{axis}| <= {half} m)")
    for spot_y in table.spots_y_m:
        if not any(c.spot_y_range_m[0] <= spot_y <= c.spot_y_range_m[1] for c in chains):
            raise ConfigError(f"table.spots_y_m: no chain's spot_y_range_m covers y = {spot_y} m")
    return table


MARGIN_KEYS = (
    "com_m",
    "collision_m",
    "joint_limit_rad",
    "joint_limit_rad_by_joint",
    "effort_ratio",
    "zmp_m",
    "com_uncertainty_m",
    "table_clearance_m",
)  # the ``margins`` section's keys


def read_margins(mg: Reader) -> MarginConfig:
    """The ``margins`` section (every margin >= 0)."""
    mg.keys_within(MARGIN_KEYS)
    return MarginConfig(
        com_m=mg.number("com_m", minimum=0.0),
        collision_m=mg.number("collision_m", minimum=0.0),
        joint_limit_rad=mg.number("joint_limit_rad", minimum=0.0),
        effort_ratio=_fraction(mg, "effort_ratio", 0.9),
        zmp_m=mg.number("zmp_m", 0.01, minimum=0.0),
        com_uncertainty_m=mg.number("com_uncertainty_m", 0.0, minimum=0.0),
        joint_limit_rad_by_joint=_larger_margins(mg, mg.number("joint_limit_rad", minimum=0.0)),
        table_clearance_m=mg.number("table_clearance_m", 0.0, minimum=0.0),
    )


def _larger_margins(mg: Reader, margin_rad: float) -> dict[str, float]:
    """``margins.joint_limit_rad_by_joint``: joint -> rad, each at least ``joint_limit_rad``."""
    larger = mg.angles("joint_limit_rad_by_joint")
    for joint, value in larger.items():
        if value < margin_rad:
            raise ConfigError(
                f"margins.joint_limit_rad_by_joint.{joint}: {value} rad is below margins.joint_limit_rad "
                f"({margin_rad} rad); a joint's own margin can only be larger"
            )
    return larger


def _fraction(reader: Reader, key: str, default: float) -> float:
    """A number in (0, 1]."""
    value = reader.number(key, default, minimum=0.0)
    if not 0.0 < value <= 1.0:
        raise ConfigError(f"margins.{key}: expected a fraction in (0, 1], got {value}")
    return value


def read_sampling(sp: Reader) -> SamplingConfig:
    """The ``sampling`` section."""
    sp.keys_within(tuple(f.name for f in fields(SamplingConfig)))
    return SamplingConfig(
        soft_iterations=sp.integer("soft_iterations"),
        hard_iterations=sp.integer("hard_iterations"),
        spot_tolerance_m=sp.number("spot_tolerance_m", minimum=0.0),
        chunk_size=sp.integer("chunk_size", maximum=10_000),
    )
