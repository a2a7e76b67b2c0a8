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

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from posegen.calibrate.calibration import Calibration
from posegen.calibrate.compliance import (
    COMPLIANCE_FILE,
    Compliance,
    ComplianceGroup,
    read_compliance,
    write_compliance,
)
from posegen.calibrate.deliverables import Deliverable, DeliverableKind
from posegen.calibrate.file_judge import JUDGED_AS, Judged, errors_by_chain, judge
from posegen.calibrate.offsets import OFFSETS_FILE, joint_offsets, write_offsets
from posegen.calibrate.scoring import DELIVERABLE_RULE, CvResult
from posegen.calibrate.summary import NOMINAL_KEY
from posegen.calibrate.urdf_export import calibrated_robot
from posegen.io import dump_yaml, write_atomic
from posegen.model import Contacts, Kind
from posegen.robot import FloatArray, Scene, load_config, parse_config

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


@dataclass(frozen=True)
class Written:
    """A deliverable's files, written and read back: the robot a stack loading them has."""

    deliverable: Deliverable
    scene: Scene  # the robot its URDF (and config's frames) describe
    compliance: Compliance | None  # its compliance.yaml, read back; None for the URDF alone


def write_deliverable(calibration: Calibration, deliverable: Deliverable, out_dir: Path, seed: int | None) -> Written:
    """Write a deliverable's files into the calibration folder ``out_dir``, and read them back.

    The URDF is the nominal one as it is, or the URDF of the deliverable's fit (built once,
    with its config). The URDF alone ships its config (``calibrated.yaml``); the
    compensated deliverable's robot is read with the same config's frames at its own
    placements (not written: a posegen command does not compensate).
    """
    model = calibration.model
    scene = model.scene
    folder = out_dir / folder_of(deliverable)
    folder.mkdir(parents=True, exist_ok=True)
    nominal = scene.files.urdf.read_text()
    theta = model.contact.nominal() if deliverable.nominal else model.theta(deliverable.estimate.x)
    exported, config = calibrated_robot(nominal, model.contact, theta, folder / URDF_FILE)
    urdf = nominal if deliverable.nominal else exported  # nominal: the config's frames as they are
    write_atomic(folder / URDF_FILE, urdf)
    provenance = scene.provenance(seed)
    write_offsets(folder / OFFSETS_FILE, joint_offsets(nominal, urdf), URDF_FILE, str(scene.files.urdf), provenance)
    if deliverable.kind == DeliverableKind.COMPENSATED:
        write_compliance(folder / COMPLIANCE_FILE, compliance_of(calibration, deliverable), URDF_FILE, provenance)
        robot = Scene(parse_config(config, str(folder / CONFIG_FILE)))  # the URDF as written, beside this config
        return Written(deliverable, robot, read_compliance(folder / COMPLIANCE_FILE))
    write_atomic(folder / CONFIG_FILE, dump_yaml(config))
    return Written(deliverable, Scene(load_config(folder / CONFIG_FILE)), None)


@dataclass(frozen=True)
class Judgements:
    """Every file, and the interpretable model, judged as a stack loading it sees it (:mod:`file_judge`)."""

    nominal: Judged  # the nominal URDF as it is
    files: dict[DeliverableKind, Judged]  # each deliverable, from its files as written
    model: Judged  # the interpretable model (one-SE rule), not written


def judge_all(calibration: Calibration, written: Sequence[Written], held_out: Contacts | None) -> Judgements:
    """Judge the nominal URDF, every deliverable from its written files, and the interpretable model alike."""
    scene, train, kept = calibration.model.scene, calibration.train, calibration.kept
    model = calibration.model
    x = calibration.after.x
    groups = tuple(
        ComplianceGroup(g, tuple(scene.joint_names[j] for j in model.compliance[g]), model.compliances(x)[g])
        for g in calibration.candidate.compliance
    )
    own = Compliance(groups, tuple(scene.stance.sole_frames)) if groups else None
    parameters = {p.name: float(x[i]) for i, p in enumerate(model.contact.parameters)}
    return Judgements(
        nominal=judge(scene, train, kept, held_out),
        files={w.deliverable.kind: judge(w.scene, train, kept, held_out, w.compliance) for w in written},
        model=judge(scene, train, kept, held_out, own, parameters),
    )


def _errors(values: Sequence[float] | FloatArray, digits: int) -> dict[str, float | None]:
    shown = np.asarray(values, dtype=float) * SHOWN
    return {f: round(float(v), digits) if np.isfinite(v) else None for f, v in zip(FIELDS, shown, strict=True)}


def predicted_figures(result: CvResult) -> dict[str, Any]:
    """CV-predicted held-out error per chain (mean abs, RMS; mm, deg), as calibration.yaml writes it."""
    return {chain: {"mean_abs": _errors(e.mean_abs, 3), "rms": _errors(e.rms, 3)} for chain, e in result.chains.items()}


def judged_figures(residuals: FloatArray, contacts: Contacts) -> dict[str, Any]:
    """Mean abs and RMS (mm, deg; six decimals) of judged residuals, over all rows and per chain."""
    return {
        chain: {"contacts": e.contacts, "mean_abs": _errors(e.mean_abs, 6), "rms": _errors(e.rms, 6)}
        for chain, e in errors_by_chain(residuals, contacts).items()
    }


def file_entry(calibration: Calibration, judged: Judged, held_out: Contacts | None) -> dict[str, Any]:
    """A file's figures as a stack loading it sees them: its kept training rows and the held-out ones."""
    kept = list(calibration.kept)
    entry = {"training": judged_figures(judged.training[kept], calibration.train.subset(kept))}
    if held_out is not None and judged.held_out is not None:
        entry["held_out"] = judged_figures(judged.held_out, held_out)
    return entry


def deliverables_report(calibration: Calibration, judged: Judgements, held_out: Contacts | None) -> dict[str, Any]:
    """The ``deliverables`` section of ``calibration.yaml``: each file, its model, predicted and judged errors."""
    section: dict[str, Any] = {"rule": DELIVERABLE_RULE, "judged": JUDGED_AS}
    for deliverable in calibration.deliverables.all():
        section[deliverable.kind.value] = {
            "files": files_of(deliverable),
            "load_with": LOADED_BY[deliverable.kind],
            "candidate": deliverable.candidate.name,
            "prior_scale": deliverable.result.prior_scale,
            "free_parameters": deliverable.result.free,
            "score": round(deliverable.result.score, 2),
            "se": round(deliverable.result.se, 2),
            "predicted_error": predicted_figures(deliverable.result),
            **file_entry(calibration, judged.files[deliverable.kind], held_out),
        }
    nominal = calibration.selection.nominal
    section[NOMINAL_KEY] = {
        "files": [],
        "load_with": "for comparison: the URDF as it is (not written)",
        "score": round(nominal.score, 2),
        "se": round(nominal.se, 2),
        "predicted_error": predicted_figures(nominal),
        **file_entry(calibration, judged.nominal, held_out),
    }
    return section
