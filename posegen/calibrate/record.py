"""A calibration folder read back: the report, every contact's residuals and the posterior.

Besides ``calibration.yaml`` (:mod:`posegen.calibrate.calibration_file`), a calibration writes::

    residuals.csv    one row per contact: set (training | outlier | held_out), label,
                     chain, session, kind (flush | point), height/roll/pitch residuals
                     before (the nominal URDF) and after (calibrated.urdf), each as a stack
                     loading it sees them (mm, deg; a point contact's roll and pitch are
                     empty: not measured), then the joint angles (rad, one per joint)
    posterior.npz    the fitted directions' names (parameter kinds, :mod:`posegen.model.kinds`),
                     their posterior covariance (f, f), the singular values of the
                     noise-whitened regressor (f,) and the condition numbers of the
                     regressor alone and with the prior

Residuals are judged as :mod:`posegen.calibrate.file_judge` says: the file's kinematics
frozen, the planes and contact tilts fitted on the kept training rows, held-out rows
judged with the training plane. Viewers and the HTML report read a folder through
:func:`read_calibration` only.
"""

from __future__ import annotations

import csv
import enum
import io
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from posegen.calibrate.calibration import Calibration
from posegen.calibrate.estimation import frozen_jacobian
from posegen.calibrate.file_judge import Judged
from posegen.calibrate.summary import CALIBRATION_FORMAT, COMPONENTS, summary_from_dict
from posegen.errors import InputError, reason
from posegen.io import load_yaml_file, write_atomic
from posegen.model import Contacts
from posegen.robot import DEFAULT_KIND, ContactKind, FloatArray, kind_named

CALIBRATION_FILE = "calibration.yaml"
RESIDUALS_FILE = "residuals.csv"
POSTERIOR_FILE = "posterior.npz"
CALIBRATED_CONFIG_FILE = "calibrated.yaml"
DISPLAY = np.array([1e3, 180.0 / np.pi, 180.0 / np.pi])  # m, rad, rad -> mm, deg, deg


class ContactSet(str, enum.Enum):
    """Which part of the data a contact belongs to."""

    TRAINING = "training"  # fitted
    OUTLIER = "outlier"  # training row left out of the final fit
    HELD_OUT = "held_out"  # judged, never fitted


@dataclass(frozen=True)
class ContactResidual:
    """One contact and its residuals under the nominal and the calibrated model."""

    set: ContactSet
    label: str
    chain: str
    session: str
    joints: FloatArray  # (nj,) rad, in ``joint_names`` order
    before: FloatArray  # (3,) height (m), roll, pitch (rad): the nominal URDF as a stack sees it; NaN: not measured
    after: FloatArray  # (3,) the same, calibrated.urdf
    kind: ContactKind = DEFAULT_KIND


@dataclass(frozen=True)
class Posterior:
    """Uncertainty and conditioning of the fitted directions."""

    names: tuple[str, ...]  # (f,) fitted directions, as in the report's parameter table
    covariance: FloatArray  # (f, f) posterior covariance (prior included), m, rad and rad/N m
    singular_values: FloatArray  # (f,) of the noise-whitened regressor (data only), descending
    condition: float  # of that regressor: largest / smallest singular value
    condition_with_prior: float  # of the regressor stacked on the prior's rows

    @property
    def correlation(self) -> FloatArray:
        """Posterior correlation of the fitted directions. Shape (f, f)."""
        std = np.sqrt(np.clip(np.diag(self.covariance), 1e-300, None))
        return self.covariance / np.outer(std, std)


@dataclass(frozen=True)
class CalibrationRecord:
    """Everything a calibration folder holds, read back."""

    directory: Path
    report: dict[str, Any]  # the content of calibration.yaml
    joint_names: tuple[str, ...]
    contacts: tuple[ContactResidual, ...]
    posterior: Posterior
    calibrated_config: Path  # scene config of the calibrated robot

    @property
    def provenance(self) -> dict[str, Any]:
        """The calibration's provenance (config, model hash, seed, version)."""
        return dict(self.report.get("provenance") or {})


def contact_residuals(
    calibration: Calibration, held_out: Contacts | None, judged: tuple[Judged, Judged]
) -> list[ContactResidual]:
    """Every training contact (fitted or left out) and every held-out one, with its residuals.

    ``judged``: the nominal URDF and calibrated.urdf, each judged as a stack loading it sees it.
    """
    train = calibration.train
    before, after = judged
    kept = set(calibration.kept)
    rows = [
        ContactResidual(
            set=ContactSet.TRAINING if i in kept else ContactSet.OUTLIER,
            label=train.labels[i],
            chain=train.chains[i],
            session=train.sessions[i],
            joints=train.joints[i].copy(),
            before=before.training[i],
            after=after.training[i],
            kind=train.kinds[i],
        )
        for i in range(len(train))
    ]
    if held_out is not None and before.held_out is not None and after.held_out is not None:
        rows.extend(
            ContactResidual(
                set=ContactSet.HELD_OUT,
                label=held_out.labels[i],
                chain=held_out.chains[i],
                session=held_out.sessions[i],
                joints=held_out.joints[i].copy(),
                before=before.held_out[i],
                after=after.held_out[i],
                kind=held_out.kinds[i],
            )
            for i in range(len(held_out))
        )
    return rows


def posterior_of(calibration: Calibration) -> Posterior:
    """Posterior correlation of the fitted directions and conditioning of their regressor (m, rad, rad/N m)."""
    model, fit, spec = calibration.model, calibration.after, calibration.spec
    observations = model.observations(calibration.train.subset(list(calibration.kept)))
    per_posture, prior_rows = frozen_jacobian(model, observations, spec, fit.noise, fit.x)
    regressor = per_posture.reshape(-1, per_posture.shape[2])  # whitened data rows (contacts, and floors if used)
    stacked = np.vstack([regressor, prior_rows])
    covariance = np.linalg.pinv(stacked.T @ stacked)
    singular = np.linalg.svd(regressor, compute_uv=False)
    with_prior = np.linalg.svd(stacked, compute_uv=False)
    return Posterior(
        names=tuple(model.directions[i].name for i in spec.free),
        covariance=covariance,
        singular_values=singular,
        condition=float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf"),
        condition_with_prior=float(with_prior[0] / with_prior[-1]) if with_prior[-1] > 0 else float("inf"),
    )


def write_record(
    calibration: Calibration, held_out: Contacts | None, out_dir: Path, judged: tuple[Judged, Judged]
) -> None:
    """Write ``residuals.csv`` (``judged``: the nominal URDF and calibrated.urdf) and ``posterior.npz``."""
    names = calibration.model.scene.joint_names
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(
        ["set", "label", "chain", "session", "kind"]
        + [f"{c}_before" for c in COMPONENTS]
        + [f"{c}_after" for c in COMPONENTS]
        + list(names)
    )
    for row in contact_residuals(calibration, held_out, judged):
        writer.writerow(
            [row.set.value, row.label, row.chain, row.session, row.kind.value]
            + [_cell(v) for v in np.concatenate([row.before, row.after]) * np.tile(DISPLAY, 2)]
            + [repr(float(v)) for v in row.joints]
        )
    write_atomic(out_dir / RESIDUALS_FILE, buffer.getvalue())
    posterior = posterior_of(calibration)
    packed = io.BytesIO()
    np.savez(
        packed,
        names=np.array(posterior.names),
        covariance=posterior.covariance,
        singular_values=posterior.singular_values,
        condition=np.array([posterior.condition, posterior.condition_with_prior]),
    )
    write_atomic(out_dir / POSTERIOR_FILE, packed.getvalue())


def _cell(value: float) -> str:
    """A residual as written (full precision); empty when not measured."""
    return repr(float(value)) if np.isfinite(value) else ""


def _read_residuals(path: Path) -> tuple[tuple[str, ...], tuple[ContactResidual, ...]]:
    try:
        with path.open(newline="") as handle:
            rows = list(csv.reader(handle))
        header, body = rows[0], rows[1:]
        named = 5 if header[4] == "kind" else 4  # tables before point contacts have no kind column
        first = named + 2 * len(COMPONENTS)
        joint_names = tuple(header[first:])
        contacts = []
        for line, row in enumerate(body, start=2):
            if len(row) != len(header):
                raise ValueError(f"line {line}: {len(row)} fields, expected {len(header)}")
            values = np.array([float(v) if v else np.nan for v in row[named:]])
            shown = values[: first - named] / np.tile(DISPLAY, 2)
            contacts.append(
                ContactResidual(
                    set=ContactSet(row[0]),
                    label=row[1],
                    chain=row[2],
                    session=row[3],
                    joints=values[first - named :],
                    before=shown[:3],
                    after=shown[3:],
                    kind=kind_named(row[4]) if named == 5 else DEFAULT_KIND,
                )
            )
    except (OSError, IndexError, ValueError, csv.Error) as exc:
        raise InputError(f"{path}: not a posegen residual table ({exc})") from exc
    if not all(np.all(np.isfinite(c.joints)) for c in contacts):
        raise InputError(f"{path}: not a posegen residual table (joint angles that are not finite)")
    return joint_names, tuple(contacts)


def _read_posterior(path: Path) -> Posterior:
    try:
        with np.load(path, allow_pickle=False) as data:
            names = tuple(str(n) for n in np.atleast_1d(data["names"]))
            condition = np.array(data["condition"], dtype=float).reshape(2)
            posterior = Posterior(
                names=names,
                covariance=np.array(data["covariance"], dtype=float),
                singular_values=np.array(data["singular_values"], dtype=float).reshape(-1),
                condition=float(condition[0]),
                condition_with_prior=float(condition[1]),
            )
    except Exception as exc:  # numpy's readers raise many kinds on damaged bytes (SyntaxError, MemoryError...)
        raise InputError(f"{path}: not a posegen posterior file ({reason(exc)})") from exc
    nb = len(posterior.names)
    if posterior.covariance.shape != (nb, nb) or len(posterior.singular_values) > nb:
        raise InputError(f"{path}: not a posegen posterior file (shapes do not match {nb} parameters)")
    return posterior


def read_calibration(path: str | Path) -> CalibrationRecord:
    """Read a calibration folder (or its ``calibration.yaml``).

    Raises:
        InputError: A file is missing or malformed (the folder predates this format, or
            is not a calibration folder).

    """
    path = Path(path)
    directory = path.parent if path.is_file() else path
    report = load_yaml_file(directory / CALIBRATION_FILE, InputError)
    if not isinstance(report, dict) or report.get("format") != CALIBRATION_FORMAT:
        raise InputError(f"{directory / CALIBRATION_FILE}: not a {CALIBRATION_FORMAT} file")
    summary_from_dict(report, str(directory / CALIBRATION_FILE))  # every section a reader needs, of this version
    for name in (RESIDUALS_FILE, POSTERIOR_FILE, CALIBRATED_CONFIG_FILE):
        if not (directory / name).is_file():
            raise InputError(f"{directory}: no {name} (calibrate again with this posegen version)")
    joint_names, contacts = _read_residuals(directory / RESIDUALS_FILE)
    return CalibrationRecord(
        directory=directory,
        report=report,
        joint_names=joint_names,
        contacts=contacts,
        posterior=_read_posterior(directory / POSTERIOR_FILE),
        calibrated_config=directory / CALIBRATED_CONFIG_FILE,
    )
