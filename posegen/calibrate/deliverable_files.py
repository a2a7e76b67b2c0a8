"""The files of each deliverable, and what ``calibration.yaml`` says of them.

In the calibration folder::

    calibrated.urdf                  the URDF alone: any stack loads it
    calibrated.yaml                  a scene config using it (posegen's own commands)
    offsets.yaml                     calibrated.urdf as offsets of the nominal URDF
    with_compliance/calibrated.urdf  the URDF of the compliant model (only when one predicts best)
    with_compliance/compliance.yaml  its compliance, to correct the encoder angles
    with_compliance/offsets.yaml     its URDF as offsets of the nominal URDF

A deliverable's URDF holds its own fit (never a compliant fit with its compliance
dropped): loaded alone, it predicts what cross-validation said it would.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from posegen.calibrate.calibration import Calibration, held_out_x
from posegen.calibrate.compliance import COMPLIANCE_FILE, Compliance, ComplianceGroup, write_compliance
from posegen.calibrate.deliverables import Deliverable, DeliverableKind
from posegen.calibrate.offsets import OFFSETS_FILE, joint_offsets, write_offsets
from posegen.calibrate.scoring import DELIVERABLE_RULE, CvResult, column_stats
from posegen.calibrate.summary import CalibrationSummary
from posegen.calibrate.urdf_export import calibrated_robot, calibrated_urdf
from posegen.io import dump_yaml, write_atomic
from posegen.model import Contacts, Kind, masked
from posegen.robot import FloatArray

URDF_FILE = "calibrated.urdf"
CONFIG_FILE = "calibrated.yaml"
COMPLIANT_DIR = "with_compliance"
LOADED_BY = {
    DeliverableKind.URDF: "any stack (controllers, MoveIt, RViz, pinocchio): the URDF alone",
    DeliverableKind.COMPENSATED: "stacks that correct the encoder angles by compliance.yaml "
    "(posegen.calibrate.compensate), with this URDF",
}
SHOWN = np.array([1e3, 180.0 / np.pi, 180.0 / np.pi])  # m, rad, rad -> mm, deg, deg
FIELDS = ("z_mm", "roll_deg", "pitch_deg")


def folder_of(deliverable: Deliverable) -> str:
    """The deliverable's place in the calibration folder ("" for the folder itself)."""
    return COMPLIANT_DIR if deliverable.kind == DeliverableKind.COMPENSATED else ""


def files_of(deliverable: Deliverable) -> list[str]:
    """The deliverable's files, relative to the calibration folder."""
    folder = folder_of(deliverable)
    names = [URDF_FILE, OFFSETS_FILE] + ([COMPLIANCE_FILE] if deliverable.kind == DeliverableKind.COMPENSATED else [])
    if deliverable.kind == DeliverableKind.URDF:
        names.insert(1, CONFIG_FILE)
    return [f"{folder}/{n}" if folder else n for n in names]


def compliance_of(calibration: Calibration, deliverable: Deliverable) -> Compliance:
    """The compliance groups a deliverable's candidate fits, with their values and posterior std."""
    model = calibration.model
    values = model.compliances(deliverable.estimate.x)
    std = {model.directions[i].owner: float(deliverable.estimate.std[i]) for i in model.columns([Kind.COMPLIANCE])}
    groups = tuple(
        ComplianceGroup(g, tuple(model.scene.joint_names[j] for j in model.compliance[g]), values[g], std[g])
        for g in deliverable.candidate.compliance
    )
    return Compliance(groups, tuple(model.scene.stance.sole_frames))


def write_deliverable(calibration: Calibration, deliverable: Deliverable, out_dir: Path, seed: int | None) -> str:
    """Write a deliverable's files into the calibration folder ``out_dir``; its URDF text.

    The URDF is the nominal one as it is, or the URDF of the deliverable's fit (built once,
    with its config for the URDF deliverable).
    """
    model = calibration.model
    scene = model.scene
    folder = out_dir / folder_of(deliverable)
    folder.mkdir(parents=True, exist_ok=True)
    nominal = scene.files.urdf.read_text()
    theta = model.contact.nominal() if deliverable.nominal else model.theta(deliverable.estimate.x)
    urdf, config = nominal, None
    if deliverable.kind == DeliverableKind.URDF:  # nominal: the config's frames as they are
        exported, config = calibrated_robot(nominal, model.contact, theta, folder / URDF_FILE)
        urdf = nominal if deliverable.nominal else exported
    elif not deliverable.nominal:
        urdf = calibrated_urdf(nominal, model.contact, theta)
    write_atomic(folder / URDF_FILE, urdf)
    provenance = scene.provenance(seed)
    write_offsets(folder / OFFSETS_FILE, joint_offsets(nominal, urdf), URDF_FILE, str(scene.files.urdf), provenance)
    if config is None:  # the compensated deliverable
        write_compliance(folder / COMPLIANCE_FILE, compliance_of(calibration, deliverable), URDF_FILE, provenance)
    else:
        write_atomic(folder / CONFIG_FILE, dump_yaml(config))
    return urdf


def _errors(values: FloatArray) -> dict[str, float | None]:
    return {f: round(float(v), 3) if np.isfinite(v) else None for f, v in zip(FIELDS, values * SHOWN, strict=True)}


def _predicted(result: CvResult) -> dict[str, Any]:
    return {
        chain: {"mean_abs": _errors(np.array(e.mean_abs)), "rms": _errors(np.array(e.rms))}
        for chain, e in result.chains.items()
    }


def held_out_errors(calibration: Calibration, x: FloatArray, held_out: Contacts) -> dict[str, Any]:
    """Held-out errors of parameters ``x`` with the planes from training, per chain and in all (mean abs, RMS)."""
    model = calibration.model
    observations = model.observations(held_out)
    residuals = masked(
        model.evaluate(held_out_x(calibration, x, held_out), observations, floor=False).contact, held_out.kinds
    )
    out: dict[str, Any] = {}
    chains = np.array(held_out.chains)
    for chain in ["all", *sorted(set(held_out.chains))]:
        rows = residuals if chain == "all" else residuals[chains == chain]
        mean_abs, rms = column_stats(rows)
        out[chain] = {"contacts": len(rows), "mean_abs": _errors(mean_abs), "rms": _errors(rms)}
    return out


def deliverables_report(calibration: Calibration, held_out: Contacts | None) -> dict[str, Any]:
    """The ``deliverables`` section of ``calibration.yaml``: each one's files, fit and predicted error."""
    section: dict[str, Any] = {"rule": DELIVERABLE_RULE}
    nominal = calibration.selection.nominal
    for deliverable in calibration.deliverables.all():
        entry: dict[str, Any] = {
            "files": files_of(deliverable),
            "load_with": LOADED_BY[deliverable.kind],
            "candidate": deliverable.candidate.name,
            "prior_scale": deliverable.result.prior_scale,
            "free_parameters": deliverable.result.free,
            "score": round(deliverable.result.score, 2),
            "se": round(deliverable.result.se, 2),
            "predicted_error": _predicted(deliverable.result),
        }
        if held_out is not None:
            entry["held_out_training_plane"] = held_out_errors(calibration, deliverable.estimate.x, held_out)
        section[deliverable.kind.value] = entry
    section["nominal_urdf"] = {
        "score": round(nominal.score, 2),
        "se": round(nominal.se, 2),
        "predicted_error": _predicted(nominal),
    }
    return section


def load_line(summary: CalibrationSummary) -> str:
    """One line: which file to load for which stack, with each one's predicted held-out height error."""
    parts = []
    for kind, deliverable in summary.deliverables.items():
        errors = ", ".join(
            f"{chain} {e.mean_abs.z_mm:.2f} mm" for chain, e in sorted(deliverable.predicted_error.items())
        )
        what = deliverable.files[0] if kind == DeliverableKind.URDF else f"{COMPLIANT_DIR}/ (URDF + {COMPLIANCE_FILE})"
        who = "any stack" if kind == DeliverableKind.URDF else "stacks that compensate compliance"
        parts.append(f"{what} for {who} (predicted held-out z {errors})")
    return "load: " + "; or ".join(parts)
