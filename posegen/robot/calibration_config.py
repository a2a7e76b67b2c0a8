"""Typed ``calibration`` section of a scene config: priors, compliance, candidate models.

What is robot-specific in a calibration lives here, read from ``configs/*.yaml``: the
prior size of each parameter kind (from manufacturing tolerances), which joints give
way under gravity (compliance groups), the candidate models that cross-validation
chooses among, the prior scales it tries, its folds, and the error the user aims at.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from posegen.arguments import is_finite_number
from posegen.errors import ConfigError
from posegen.robot.config_reader import Reader

PARTS = ("leg", "torso", "arm", "*")
KINDS = ("joint_offset", "axis_tilt", "link_translation", "frame_rotation", "*")


@dataclass(frozen=True)
class PriorConfig:
    """Prior sigma of each parameter kind's deviation from the URDF, at prior scale 1."""

    joint_offset_deg: float = 0.1  # encoder zero
    axis_tilt_deg: float = 0.1  # joint axis vs its housing
    link_translation_mm: float = 1.0  # a placement's origin
    frame_rotation_deg: float = 0.1  # a fixed frame (sole, gripper mount)
    contact_height_mm: float = 1.0  # contact frame along the gripper normal
    contact_tilt_deg: float = 0.1  # contact frame roll and pitch
    contact_point_mm: float = 1.0  # a point contact's tip centre in its point frame
    compliance_rad_per_knm: float = 0.1  # joint deflection per kN m of gravity torque


@dataclass(frozen=True)
class CandidateConfig:
    """A candidate model: which parameter kinds are fitted, and which effects are modelled.

    Contact offsets and table planes are always fitted. ``fit`` holds ``part.kind``
    patterns, part one of leg, torso, arm or ``*``, kind one of joint_offset, axis_tilt,
    link_translation, frame_rotation or ``*``; every other kind is held at the URDF.
    """

    name: str
    fit: tuple[str, ...]
    floor: bool = False  # use the floor equations (both soles flat on one floor)
    compliance: tuple[str, ...] = ()  # compliance groups fitted (the others stay rigid)

    def fits(self, part: str, kind: str) -> bool:
        """Whether this candidate fits parameters of this part and kind."""
        return any(p in (part, "*") and k in (kind, "*") for p, k in (s.split(".") for s in self.fit))


DEFAULT_CANDIDATES = (
    CandidateConfig("full", ("*.*",)),
    CandidateConfig(
        "arm_translations_held", ("leg.*", "torso.*", "arm.joint_offset", "arm.axis_tilt", "arm.frame_rotation")
    ),
    CandidateConfig("offsets_legs", ("*.joint_offset", "leg.*")),
    CandidateConfig("offsets", ("*.joint_offset",)),
)


MAX_FOLD_SEEDS = 1000  # repetitions of the cross-validation: its estimate settles long before
MIN_PRIOR_SIGMA = 1e-6  # a prior sigma below it (in its kind's unit) is a weight LAPACK cannot factor
PRIOR_SCALE_RANGE = (1e-3, 1e4)  # a prior scale's bounds: beyond them the prior is all or nothing, and LAPACK fails


@dataclass(frozen=True)
class CalibrationConfig:
    """How ``posegen calibrate`` models the robot and chooses among models."""

    prior: PriorConfig = PriorConfig()
    prior_scales: tuple[float, ...] = (0.3, 1.0, 3.0, 10.0, 30.0, 100.0, 300.0)  # tried, x the prior sigmas
    compliance: dict[str, tuple[str, ...]] = field(default_factory=dict)  # group -> joints sharing one compliance
    candidates: tuple[CandidateConfig, ...] = DEFAULT_CANDIDATES
    folds: int = 5  # regions of the table per chain (or sessions, when a chain has several)
    fold_seeds: int = 5  # repetitions of the grouped cross-validation
    fold_iterations: int = 3  # Levenberg-Marquardt iterations of a fold's fit, started from the full fit
    target_error_mm: float = 4.0  # warn when a chain's predicted held-out height error is above
    outlier_false_alarm: float = 0.01  # chance of flagging any row of a clean data set (Bonferroni)
    max_left_out: float = 0.2  # screening stops (and warns) before leaving out more than this share of the rows
    feet_tolerance_mm: float = 5.0  # a second sole further than this from its place (URDF) did not stand
    feet_tolerance_deg: float = 1.0  # ... or tilted more than this
    plausible_mm: float = 25.0  # a fit moving a length further from the URDF is not this robot (degenerate)
    plausible_deg: float = 5.0  # ... or an angle


def parse_candidate(name: str, data: Any, where: str, groups: dict[str, Any]) -> CandidateConfig:
    """One entry of ``calibration.candidates``; ``compliance`` is true (every group), false, or group names.

    Raises:
        ConfigError: Unknown keys, parts or kinds.

    """
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: expected a mapping with fit, floor, compliance")
    Reader(data, where).keys_within(("fit", "floor", "compliance"))
    patterns = data.get("fit")
    if not isinstance(patterns, list) or not all(isinstance(p, str) for p in patterns):
        raise ConfigError(f"{where}.fit: expected a list of part.kind patterns")
    for pattern in patterns:
        part, _, kind = pattern.partition(".")
        if part not in PARTS or kind not in KINDS:
            raise ConfigError(
                f"{where}.fit: '{pattern}' is not part.kind; parts: {', '.join(PARTS)}; kinds: {', '.join(KINDS)}"
            )
    floor = data.get("floor", False)
    if not isinstance(floor, bool):
        raise ConfigError(f"{where}.floor: expected true or false, got {floor!r}")
    compliance = data.get("compliance", False)
    if compliance is True:
        compliance = list(groups)
    elif compliance is False:
        compliance = []
    if not isinstance(compliance, list) or not all(isinstance(g, str) for g in compliance):
        raise ConfigError(f"{where}.compliance: expected true, false or a list of compliance groups")
    missing = [g for g in compliance if g not in groups]
    if missing or (data.get("compliance") is True and not groups):
        raise ConfigError(
            f"{where}.compliance: unknown groups {missing or 'all'}; calibration.compliance defines: "
            f"{', '.join(groups) or 'none'}"
        )
    return CandidateConfig(name, tuple(patterns), floor, tuple(compliance))


def _number(data: dict[str, Any], key: str, default: float, where: str) -> float:
    """A finite number > 0 (NaN and infinity refused: no threshold or sigma means them)."""
    value = data.get(key, default)
    if not is_finite_number(value) or value <= 0:
        raise ConfigError(f"{where}.{key}: expected a positive finite number, got {value!r}")
    return float(value)


def _probability(data: dict[str, Any], key: str, default: float, where: str) -> float:
    value = _number(data, key, default, where)
    if not value < 1.0:
        raise ConfigError(f"{where}.{key}: expected a probability between 0 and 1 (exclusive), got {value!r}")
    return value


def parse_calibration(data: Any, where: str = "calibration") -> CalibrationConfig:
    """The ``calibration`` section (every key optional; defaults in :class:`CalibrationConfig`).

    Raises:
        ConfigError: A key is unknown, of the wrong type or out of range.

    """
    if data is None:
        return CalibrationConfig()
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: expected a mapping")
    defaults = CalibrationConfig()
    section = Reader(data, where)
    section.keys_within(tuple(f.name for f in dataclasses.fields(CalibrationConfig)))
    prior = _prior(data.get("prior", {}), defaults.prior, f"{where}.prior")
    scales = data.get("prior_scales", list(defaults.prior_scales))
    low, high = PRIOR_SCALE_RANGE
    if (
        not isinstance(scales, list)
        or len(scales) < 1
        or not all(isinstance(s, (int, float)) and not isinstance(s, bool) and low <= s <= high for s in scales)
    ):
        raise ConfigError(f"{where}.prior_scales: expected a list of numbers from {low:g} to {high:g}, got {scales!r}")
    groups = data.get("compliance", {})
    if not isinstance(groups, dict) or not all(
        isinstance(v, list) and v and all(isinstance(j, str) for j in v) for v in groups.values()
    ):
        raise ConfigError(f"{where}.compliance: expected a mapping group -> list of joint names")
    return CalibrationConfig(
        prior=prior,
        prior_scales=tuple(float(s) for s in sorted(scales)),
        compliance={str(g): tuple(v) for g, v in groups.items()},
        candidates=_candidates(data.get("candidates"), defaults.candidates, groups, f"{where}.candidates"),
        folds=section.integer("folds", defaults.folds, minimum=2),
        fold_seeds=section.integer("fold_seeds", defaults.fold_seeds, maximum=MAX_FOLD_SEEDS),
        fold_iterations=section.integer("fold_iterations", defaults.fold_iterations),
        target_error_mm=_number(data, "target_error_mm", defaults.target_error_mm, where),
        outlier_false_alarm=_probability(data, "outlier_false_alarm", defaults.outlier_false_alarm, where),
        max_left_out=_probability(data, "max_left_out", defaults.max_left_out, where),
        feet_tolerance_mm=_number(data, "feet_tolerance_mm", defaults.feet_tolerance_mm, where),
        feet_tolerance_deg=_number(data, "feet_tolerance_deg", defaults.feet_tolerance_deg, where),
        plausible_mm=_number(data, "plausible_mm", defaults.plausible_mm, where),
        plausible_deg=_number(data, "plausible_deg", defaults.plausible_deg, where),
    )


def _prior(data: Any, defaults: PriorConfig, where: str) -> PriorConfig:
    """The ``prior`` mapping kind -> sigma; absent kinds keep ``defaults``."""
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: expected a mapping kind -> sigma")
    fields = tuple(f.name for f in dataclasses.fields(PriorConfig))
    Reader(data, where).keys_within(fields)
    prior = {k: _number(data, k, getattr(defaults, k), where) for k in fields}
    small = [k for k, v in prior.items() if v < MIN_PRIOR_SIGMA]
    if small:
        raise ConfigError(f"{where}.{small[0]}: expected a number >= {MIN_PRIOR_SIGMA:g}, got {prior[small[0]]!r}")
    return PriorConfig(**prior)


def _candidates(
    data: Any, defaults: tuple[CandidateConfig, ...], groups: dict[str, list[str]], where: str
) -> tuple[CandidateConfig, ...]:
    """The ``candidates`` mapping name -> {fit, floor, compliance}; ``defaults`` when absent."""
    if data is None:
        return defaults
    if not isinstance(data, dict) or not data:
        raise ConfigError(f"{where}: expected a mapping name -> {{fit, floor, compliance}}")
    return tuple(parse_candidate(str(n), c, f"{where}.{n}", groups) for n, c in data.items())


def calibration_to_dict(config: CalibrationConfig) -> dict[str, Any]:
    """Plain-data form, as in the YAML file (re-loadable by :func:`parse_calibration`)."""
    out = dataclasses.asdict(config)
    out["prior_scales"] = list(config.prior_scales)
    out["compliance"] = {g: list(j) for g, j in config.compliance.items()}
    out["candidates"] = {
        c.name: {"fit": list(c.fit), "floor": c.floor, "compliance": list(c.compliance)} for c in config.candidates
    }
    return out
