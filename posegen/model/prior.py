"""The prior of a candidate model: which directions are free, and their sigmas.

A candidate (``calibration.candidates`` of the config) names the parameter kinds it
fits per body part, and whether it models joint compliance and uses the floor
equations. At a prior scale kappa, each free direction's prior sigma is kappa times
its kind's sigma in ``calibration.prior``; contact offsets and planes are always
free, planes and floor constants without a prior.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from posegen.model.calibration_model import CalibrationModel
from posegen.model.kinds import Kind
from posegen.robot import CandidateConfig, FloatArray, PriorConfig

ROBOT_KINDS = (Kind.JOINT_OFFSET, Kind.AXIS_TILT, Kind.LINK_TRANSLATION, Kind.FRAME_ROTATION)


@dataclass(frozen=True)
class Spec:
    """What a fit estimates: free directions, their prior, and whether the floor equations count."""

    free: tuple[int, ...]  # indices of the model's directions that are estimated
    prior_sd: FloatArray  # (nx,) prior sigma of each direction; inf: no prior
    floor: bool


def kind_sigmas(prior: PriorConfig) -> dict[Kind, float]:
    """Prior sigma of each kind at scale 1, in m, rad and rad/N m (inf: no prior)."""
    return {
        Kind.JOINT_OFFSET: float(np.deg2rad(prior.joint_offset_deg)),
        Kind.AXIS_TILT: float(np.deg2rad(prior.axis_tilt_deg)),
        Kind.LINK_TRANSLATION: prior.link_translation_mm * 1e-3,
        Kind.FRAME_ROTATION: float(np.deg2rad(prior.frame_rotation_deg)),
        Kind.CONTACT_HEIGHT: prior.contact_height_mm * 1e-3,
        Kind.CONTACT_TILT: float(np.deg2rad(prior.contact_tilt_deg)),
        Kind.CONTACT_POINT: prior.contact_point_mm * 1e-3,
        Kind.COMPLIANCE: prior.compliance_rad_per_knm * 1e-3,
        Kind.PLANE: np.inf,
        Kind.FLOOR: np.inf,
    }


def prior_sigmas(model: CalibrationModel, prior: PriorConfig, scale: float) -> FloatArray:
    """Prior sigma of every direction at prior scale ``scale``. Shape (nx,)."""
    sigma = kind_sigmas(prior)
    return np.array([sigma[d.kind] * scale for d in model.directions])


def free_directions(model: CalibrationModel, candidate: CandidateConfig) -> tuple[int, ...]:
    """Indices of the directions a candidate estimates."""
    out = []
    for i, d in enumerate(model.directions):
        if d.kind in ROBOT_KINDS:
            keep = candidate.fits(d.part.value, d.kind.value)
        elif d.kind == Kind.COMPLIANCE:
            keep = d.owner in candidate.compliance
        elif d.kind == Kind.FLOOR:
            keep = candidate.floor and model.floor is not None
        else:  # contact offsets, planes
            keep = True
        if keep:
            out.append(i)
    return tuple(out)


def candidate_spec(model: CalibrationModel, candidate: CandidateConfig, prior: PriorConfig, scale: float) -> Spec:
    """The estimation spec of a candidate at one prior scale."""
    return Spec(
        free=free_directions(model, candidate),
        prior_sd=prior_sigmas(model, prior, scale),
        floor=candidate.floor and model.floor is not None,
    )


def spec_for_rows(model: CalibrationModel, spec: Spec, sessions: set[str]) -> Spec:
    """``spec`` without the planes and floor constants of sessions that have no row."""
    keep = tuple(
        i
        for i in spec.free
        if model.directions[i].kind not in (Kind.PLANE, Kind.FLOOR)
        or model.directions[i].owner.removeprefix("floor@") in sessions
    )
    return Spec(keep, spec.prior_sd, spec.floor)
