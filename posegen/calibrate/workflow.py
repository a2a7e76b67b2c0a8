"""The calibrate stage's commands, from files to files: ``posegen simulate`` and ``posegen calibrate``."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from posegen.arguments import check_seed, check_within
from posegen.calibrate.calibration import Settings, calibrate, check_candidates, check_settings
from posegen.calibrate.calibration_file import write_calibration_files
from posegen.calibrate.plots import drawing
from posegen.calibrate.record import CALIBRATION_FILE
from posegen.calibrate.simulation import Perturbation, simulate
from posegen.calibrate.summary import CalibrationSummary
from posegen.errors import ArgumentError, InputError
from posegen.io import (
    OutputKind,
    atomic_folder,
    check_apart,
    check_replaceable,
    check_writable,
    claim_output,
    companion_of,
    companions_of,
    dump_yaml,
    load_postures,
    write_with_companions,
)
from posegen.model import (
    CalibrationModel,
    Contacts,
    existing_measurement_file,
    measurement_item,
    measurement_provenance,
    measurements_to_dict,
    planned_kinds,
    read_measurements,
)
from posegen.parallel import Backend
from posegen.progress import ProgressCallback, ignore_progress
from posegen.robot import FloatArray, Scene, load_config, scene_for

TRUTH_FORMAT = "posegen-truth"
TRUTH_SUFFIX = ".truth.yaml"  # beside a simulation's measurements: ``<name>.<sha256 prefix of it>.truth.yaml``


@dataclass(frozen=True)
class Simulated:
    """What ``posegen simulate`` wrote."""

    contacts: int  # number of simulated contacts
    measurements: Path
    truth: Path  # the true parameters, beside the measurements


@dataclass(frozen=True)
class Calibrated:
    """What ``posegen calibrate`` found and wrote."""

    summary: CalibrationSummary  # calibration.yaml
    training_contacts: int  # read from the training files (outliers included)


def simulate_postures_file(
    postures_path: str,
    output: str,
    *,
    config_path: str | None,
    seed: int,
    error_mm: float,
    error_deg: float,
    noise_deg: float,
    session: str,
    compliance_rad_per_knm: float = 0.0,
    contact_noise_mm: float = 0.0,
    contact_noise_deg: float = 0.0,
) -> Simulated:
    """Contacts of a perturbed robot at the postures of a pool or selection file.

    Args:
        postures_path: Pool or selection file.
        output: Measurement file to write; the truth goes beside it, named by the
            measurements' bytes (``<name>.<sha256 prefix>.truth.yaml``, :func:`truth_of`),
            and the two are replaced as one.
        config_path: Scene config; None: the one saved in the postures file.
        seed: Seed of the robot's errors and of the encoder noise.
        error_mm: Sigma of placement length errors (mm).
        error_deg: Sigma of placement angle errors (deg, clipped at 1.5 deg).
        noise_deg: Sigma of the encoder noise (deg).
        session: Table session of every contact.
        compliance_rad_per_knm: True compliance of the config's first compliance group.
        contact_noise_mm: Sigma of each contact's local table height (mm).
        contact_noise_deg: Sigma of each contact's local table roll and pitch (deg).

    The arguments, the postures file (its robot model included) and the outputs' place are
    checked before any work; the output is locked while it is made.

    Raises:
        PosegenError: Bad arguments, config or postures file, one of another robot model, an
            output that cannot be written, or a contact that does not settle.

    """
    check_seed(seed, "seed")
    perturbation = perturbation_of(
        error_mm, error_deg, noise_deg, compliance_rad_per_knm, contact_noise_mm, contact_noise_deg
    )
    if not session:
        raise ArgumentError("session: give a session name", parameter="session")
    measurements = Path(output)
    check_writable(measurements)
    check_apart([measurements, *companions_of(measurements, TRUTH_SUFFIX)], [postures_path, config_path])
    chosen, _ = load_postures(postures_path)
    scene = scene_for(chosen.provenance, config_path)  # None: the config saved in the postures file
    check_compliance(scene, compliance_rad_per_knm)
    scene.check_made_for(chosen.provenance, postures_path)
    chosen.check_joints(scene.joint_names, postures_path)
    chosen.check_names([c.name for c in scene.config.chains], [s.name for s in scene.spots], postures_path)
    chosen.check_limits(scene.joint_names, scene.lower, scene.upper, postures_path)
    chains = tuple(p.chain for p in chosen.postures)
    spots = tuple(p.spot for p in chosen.postures)
    planned = Contacts(chosen.joints(), chains, (session,) * len(chains), spots, planned_kinds(scene, chains))
    with claim_output(measurements):
        recorded, model, x = simulate(scene, planned, perturbation, seed)
        prov = scene.provenance(seed)
        prov["simulation"] = {
            "postures": postures_path,
            "error_mm": error_mm,
            "error_deg": error_deg,
            "encoder_noise_deg": noise_deg,
            "compliance_rad_per_knm": compliance_rad_per_knm,
            **contact_noise_record(contact_noise_mm, contact_noise_deg),
        }
        header = dump_yaml(measurements_to_dict(scene, recorded, prov)).encode()
        true = dump_yaml(truth_record(model, x, prov)).encode()
        (truth,) = write_with_companions(measurements, header, {TRUTH_SUFFIX: true})
    return Simulated(contacts=len(recorded), measurements=measurements, truth=truth)


PERTURBATION_MAXIMA = {  # the largest errors a simulated robot is drawn with: beyond them no robot, no table
    "error_mm": 1000.0,
    "error_deg": 180.0,
    "noise_deg": 180.0,
    "compliance_rad_per_knm": 100.0,
    "contact_noise_mm": 1000.0,
    "contact_noise_deg": 90.0,
}


def perturbation_of(
    error_mm: float,
    error_deg: float,
    noise_deg: float,
    compliance_rad_per_knm: float = 0.0,
    contact_noise_mm: float = 0.0,
    contact_noise_deg: float = 0.0,
) -> Perturbation:
    """The perturbation in the command line's units: mm and deg of errors and noise, rad/kN m.

    Raises:
        ArgumentError: A size that is negative, not a finite number or beyond any robot
            (``PERTURBATION_MAXIMA``).

    """
    for value, name in (
        (error_mm, "error_mm"),
        (error_deg, "error_deg"),
        (noise_deg, "noise_deg"),
        (compliance_rad_per_knm, "compliance_rad_per_knm"),
        (contact_noise_mm, "contact_noise_mm"),
        (contact_noise_deg, "contact_noise_deg"),
    ):
        check_within(value, name, 0.0, PERTURBATION_MAXIMA[name])
    return Perturbation(
        length_m=error_mm * 1e-3,
        angle_rad=float(np.deg2rad(error_deg)),
        encoder_noise_rad=float(np.deg2rad(noise_deg)),
        compliance_rad_per_nm=compliance_rad_per_knm * 1e-3,
        contact_noise_m=contact_noise_mm * 1e-3,
        contact_noise_rad=float(np.deg2rad(contact_noise_deg)),
    )


def contact_noise_record(contact_noise_mm: float, contact_noise_deg: float) -> dict[str, float]:
    """The contact noise as a simulation's provenance records it: nothing without any (older files' bytes)."""
    if not contact_noise_mm and not contact_noise_deg:
        return {}
    return {"contact_noise_mm": contact_noise_mm, "contact_noise_deg": contact_noise_deg}


def check_compliance(scene: Scene, compliance_rad_per_knm: float) -> None:
    """Check that a simulated compliance has a group of the config to act on.

    Raises:
        ArgumentError: A compliance but no ``calibration.compliance`` group in the config.

    """
    if compliance_rad_per_knm and not scene.calibration.compliance:
        raise ArgumentError(
            f"compliance_rad_per_knm={compliance_rad_per_knm:g}: "
            "the config defines no calibration.compliance group to act on",
            parameter="compliance_rad_per_knm",
        )


def truth_of(measurements: str | Path) -> Path:
    """The true parameters ``posegen simulate`` wrote with a measurement file (named by its bytes).

    Raises:
        InputError: The file has none: not simulated, or edited since (its bytes changed).

    """
    found = companion_of(measurements, TRUTH_SUFFIX)
    if found is None:
        raise InputError(f"{measurements}: no true parameters written with this file (not simulated, or changed since)")
    return found


def truth_record(model: CalibrationModel, x: FloatArray, provenance: dict[str, Any]) -> dict[str, Any]:
    """The true parameters of a simulated robot, as a ``posegen-truth`` document."""
    nominal = model.nominal()
    parameters = {
        p.name: {"true": float(x[i]), "nominal": float(nominal[i])} for i, p in enumerate(model.contact.parameters)
    }
    for group, value in model.compliances(x).items():
        parameters[f"compliance@{group}"] = {"true": value, "nominal": 0.0}
    return {"format": TRUTH_FORMAT, "format_version": 1, "provenance": provenance, "parameters": parameters}


def read_contacts(items: Sequence[str], scene: Scene, rejected: list[str]) -> Contacts:
    """Read ``FILE[@SESSION]`` items into one set of contacts; unusable rows go to ``rejected``.

    Raises:
        InputError: A file is missing or malformed, or no item is given.

    """
    contacts: Contacts | None = None
    for item in items:
        path, session = measurement_item(item)
        part = read_measurements(path, scene, session)
        rejected.extend(part.rejected)
        contacts = part.contacts if contacts is None else contacts.concat(part.contacts)
    assert contacts is not None, "at least one measurement file"
    return contacts


def calibrate_files(
    measurements: Sequence[str],
    held_out: Sequence[str],
    output: str,
    settings: Settings,
    config_path: str | None,
    progress: ProgressCallback = ignore_progress,
    backend: Backend | None = None,
    finish: Callable[[Path], object] | None = None,
) -> Calibrated:
    """Calibrate from measurement files and write the calibration folder, swapped in whole.

    Args:
        measurements: Training files (posegen YAML or recorded CSV), ``FILE[@SESSION]``.
        held_out: Held-out files, judged but not fitted; may be empty.
        output: Output folder.
        settings: How to calibrate (its seed is recorded in the provenance).
        config_path: Scene config; None: the one saved in the first measurement file
            that has one (posegen's format; recorded CSV files have none).
        progress: Told when each step starts.
        backend: Where the candidates' cross-validations run; None: this process.
        finish: Writes more files into the folder (given its staging path) before it
            is swapped in: ``posegen calibrate``'s ``report.html``.

    Raises:
        PosegenError: Bad config or input, too few contacts, or an output folder that
            is not a calibration folder.

    """
    check_settings(settings)
    if not measurements:
        raise ArgumentError("give at least one training measurement file")
    out_dir = Path(output)
    check_writable(out_dir, OutputKind.FOLDER)
    files = [measurement_item(item)[0] for item in [*measurements, *held_out]]
    check_apart([out_dir], [config_path, *files])
    _check_given_once(files[: len(measurements)], "measurements")
    _check_given_once(files[len(measurements) :], "held_out")
    _check_held_out_apart(files[: len(measurements)], files[len(measurements) :])
    check_replaceable(out_dir, CALIBRATION_FILE)
    scene = Scene(load_config(config_path)) if config_path else _saved_scene([*measurements, *held_out])
    check_candidates(scene, settings)
    rejected: list[str] = []
    train = read_contacts(measurements, scene, rejected)
    validation = read_contacts(held_out, scene, rejected) if held_out else None
    if validation is not None:
        _check_trained(train, validation)
    sessions = list(dict.fromkeys(train.sessions + (validation.sessions if validation else ())))
    with claim_output(out_dir, OutputKind.FOLDER), atomic_folder(out_dir) as staging:
        calibration = calibrate(scene, train, sessions, settings, progress, backend)
        summary, plots = write_calibration_files(calibration, validation, staging, settings.seed, rejected)
        with drawing(plots, backend):  # on the idle workers, while this process writes the report
            if finish is not None:
                finish(staging)
    return Calibrated(summary=summary, training_contacts=len(train))


def _same_file(first: str, second: str) -> bool:
    """Whether two paths name one file (by path, symlink or hard link)."""
    if Path(first).resolve() == Path(second).resolve():
        return True
    return Path(first).exists() and Path(second).exists() and os.path.samefile(first, second)


def _check_given_once(files: Sequence[str], parameter: str) -> None:
    """No measurement file is given twice (its rows would count twice, under any session name).

    Raises:
        InputError: A file given twice (by path, link or name).

    """
    for i, later in enumerate(files):
        for earlier in files[:i]:
            if _same_file(earlier, later):
                raise InputError(
                    f"{later} is given twice ({parameter}): its contacts would count twice; give it once",
                    parameter=parameter,
                )


def _check_held_out_apart(training: Sequence[str], held_out: Sequence[str]) -> None:
    """No file is both fitted and held out (its contacts would judge the fit they made).

    Raises:
        InputError: A file given as training and held out (by path, link or name).

    """
    for kept in held_out:
        for fitted in training:
            if _same_file(kept, fitted):
                raise InputError(
                    f"{kept} is a training file and a held-out one (held_out): give it once", parameter="held_out"
                )


def _check_trained(train: Contacts, held_out: Contacts) -> None:
    """Every held-out chain and contact kind has training contacts (its contact parameters are fitted there).

    Raises:
        InputError: A held-out chain, or a chain's contact kind, that training lacks.

    """
    trained = train.kinds_by_chain()
    for chain, kinds in held_out.kinds_by_chain().items():
        missing = [k.value for k in kinds if k not in trained.get(chain, ())]
        if missing:
            raise InputError(
                f"held-out {' and '.join(missing)} contacts of chain '{chain}': the training files have none "
                "(the contact's parameters are fitted on training contacts of its kind)"
            )


def _saved_scene(items: Sequence[str]) -> Scene:
    """The scene saved in the first measurement file that has one.

    Raises:
        InputError: No file carries a config (recorded CSV files do not).

    """
    for item in items:
        path = existing_measurement_file(measurement_item(item)[0])  # a folder or nothing: said as such
        if path.suffix.lower() in (".yaml", ".yml"):
            return scene_for(measurement_provenance(path), None)
    raise InputError(
        "the measurement files carry no scene config (recorded CSV files do not): give config_path",
        parameter="config_path",
    )
