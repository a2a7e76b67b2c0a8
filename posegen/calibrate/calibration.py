"""The whole calibration: screening, model selection, the final fit, before/after, held-out protocols.

1. Rows that cannot be used are left out and reported: a table session with a single
   row (its plane would be fitted to it alone), a row whose feet were not on the floor.
2. Bad rows are screened with a robust fit (:mod:`posegen.calibrate.screening`), the
   model (candidate and prior scale) is chosen by repeated, grouped cross-validation
   without them (:mod:`posegen.calibrate.model_selection`), and the rows are screened
   again with the chosen model; if it flags more, the model is chosen once more without
   them. Screening is monotone and bounded: a flagged row stays out and shapes nothing
   (not the noise, the model choice or the base parameters), at most
   ``calibration.max_left_out`` of the rows are left out, and it never fails.
   The deliverables (the URDF alone, and the URDF with its compliance compensation)
   are chosen from the same cross-validation (:mod:`posegen.calibrate.deliverables`).
3. "After" is the chosen candidate fitted on every kept row; "before" is the URDF with
   only the contact offsets and planes fitted. Base parameters (QR) are computed for
   identifiability and reporting only: the fit itself regularises every parameter by
   its physical prior.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from posegen.arguments import check_count, check_seed, check_within
from posegen.calibrate.deliverables import Deliverables, choose_deliverables
from posegen.calibrate.estimation import Estimate, Noise, estimate, fit, held_at_urdf, plane_spec
from posegen.calibrate.file_judge import with_training_planes
from posegen.calibrate.folds import repeated_folds, spot_of
from posegen.calibrate.model_selection import ModelSelection, ScaleSearch, select_model
from posegen.calibrate.screening import Flag, Screening, feet_off_the_floor, feet_unexplained
from posegen.calibrate.urdf_export import check_exportable
from posegen.errors import ArgumentError, InputError
from posegen.model import (
    DEFAULT_FLOOR_NOISE,
    DEFAULT_NOISE,
    STRUCTURAL_POSTURES,
    BaseParameters,
    CalibrationModel,
    Contacts,
    Kind,
    Observations,
    Spec,
    base_at,
    candidate_spec,
    kind_sigmas,
    level_postures,
    row_counts,
    spec_for_rows,
    start_point,
)
from posegen.parallel import Backend
from posegen.progress import ProgressCallback, ignore_progress
from posegen.robot import MAX_FOLD_SEEDS, PRIOR_SCALE_RANGE, CalibrationConfig, CandidateConfig, FloatArray, Scene

LOG = logging.getLogger(__name__)
SAME_POSTURE_RAD = 1e-3  # rows no joint of which differs by more (rad): one posture (a contact window's own spread)
SELECTIONS = 2  # model selections at most: on the screened rows, then again if the chosen model flags more


@dataclass(frozen=True)
class Settings:
    """How a calibration is run; what is robot-specific comes from the config's ``calibration``.

    Example:
        >>> settings = posegen.CalibrationSettings(candidates=("offsets",), fold_seeds=3)

    """

    prior_scale: float | None = None  # fix the prior scale (candidates are still compared by CV)
    candidates: tuple[str, ...] = ()  # only these of the config's candidates; empty: all
    fold_seeds: int | None = None  # repetitions of the CV; None: the config's
    drop_outliers: bool = True
    seed: int = 0  # the first fold seed
    structural_postures: int = STRUCTURAL_POSTURES  # per (chain, session) pair, for the base parameters
    search: ScaleSearch = ScaleSearch.VALLEY  # which prior scales each candidate is cross-validated at


@dataclass(frozen=True)
class Calibration:
    """Result of a calibration."""

    model: CalibrationModel
    config: CalibrationConfig  # as used (overrides applied)
    train: Contacts  # every row read
    kept: tuple[int, ...]  # rows of ``train`` that the final fit used
    flags: tuple[Flag, ...]  # rows left out (or, with drop_outliers off, flagged and kept)
    selection: ModelSelection
    candidate: CandidateConfig
    spec: Spec
    before: Estimate
    after: Estimate
    base: BaseParameters
    base_with_floor: int | None  # base parameters of contacts and floor equations (None: one leg only)
    deliverables: Deliverables  # the files a robot loads, each with its predicted error
    warnings: tuple[str, ...] = ()  # what the user must know (screening at its limit, a URDF kept)


def check_settings(settings: Settings) -> None:
    """Check the numbers of ``settings`` (before any file is read).

    Raises:
        ArgumentError: A prior scale out of ``PRIOR_SCALE_RANGE``, a fold seed count
            below 1, or a seed out of range.

    """
    if settings.prior_scale is not None:
        check_within(settings.prior_scale, "prior_scale", *PRIOR_SCALE_RANGE)
    if settings.fold_seeds is not None:
        check_count(settings.fold_seeds, "fold_seeds", maximum=MAX_FOLD_SEEDS)
    check_seed(settings.seed, "seed")


def check_candidates(scene: Scene, settings: Settings) -> None:
    """Check that the candidate models ``settings`` names are the config's.

    Raises:
        InputError: One is not.

    """
    _settings(scene, settings)


def _settings(scene: Scene, settings: Settings) -> tuple[CalibrationConfig, list[CandidateConfig]]:
    config = scene.calibration
    if settings.prior_scale is not None:
        config = replace(config, prior_scales=(settings.prior_scale,))
    if settings.fold_seeds is not None:
        config = replace(config, fold_seeds=settings.fold_seeds)
    names = [c.name for c in config.candidates]
    if isinstance(settings.candidates, str):  # its letters would be read as names
        raise ArgumentError(
            f"candidates must be a list of model names, got the string {settings.candidates!r}", parameter="candidates"
        )
    unknown = [n for n in settings.candidates if n not in names]
    if unknown:
        raise InputError(f"unknown candidate models {unknown}; the config has: {', '.join(names)}")
    chosen = [c for c in config.candidates if not settings.candidates or c.name in settings.candidates]
    return replace(config, candidates=tuple(chosen)), chosen


def unusable_rows(model: CalibrationModel, observations: Observations, config: CalibrationConfig) -> list[Flag]:
    """Rows of a session that has no other row, and rows whose feet were not on the floor."""
    contacts = observations.contacts
    flags = []
    for session in set(contacts.sessions):
        rows = [i for i, s in enumerate(contacts.sessions) if s == session]
        if len(rows) == 1:
            flags.append(Flag(rows[0], contacts.labels[rows[0]], "alone in its session", 1.0, 0))
    if model.floor is not None:
        tolerance = (config.feet_tolerance_mm * 1e-3, float(np.deg2rad(config.feet_tolerance_deg)))
        offsets = feet_unexplained(model, observations, np.repeat(tolerance, 3), _leg_prior(config))
        for i in np.flatnonzero(feet_off_the_floor(offsets, *tolerance) > 1.0):
            size = max(np.abs(offsets[i, :3]).max() * 1e3, np.degrees(np.abs(offsets[i, 3:]).max()))
            flags.append(Flag(int(i), contacts.labels[i], "feet off the floor (mm or deg)", float(size), 0))
    for flag in flags:  # the command prints them with the result (or names them in its error)
        LOG.info("row left out: %s: %s", flag.label, flag.reason)
    return sorted(flags, key=lambda f: f.row)


def _leg_prior(config: CalibrationConfig) -> tuple[float, float]:
    """Prior sigma of a placement's lengths (m) and angles (rad) at the middle prior scale."""
    sigma = kind_sigmas(config.prior)
    scale = sorted(config.prior_scales)[len(config.prior_scales) // 2]
    angles = (Kind.JOINT_OFFSET, Kind.AXIS_TILT, Kind.FRAME_ROTATION)
    return sigma[Kind.LINK_TRANSLATION] * scale, max(sigma[k] for k in angles) * scale


def check_enough(
    model: CalibrationModel, contacts: Contacts, config: CalibrationConfig, left_out: Sequence[Flag] = ()
) -> None:
    """Enough rows to fit the planes and to hold out regions of every chain.

    Args:
        model: The model to fit.
        contacts: The usable rows.
        config: The calibration section of the config.
        left_out: The rows left out (named in the message, by file and line).

    Raises:
        InputError: Fewer contact equations than parameters without a prior, or a chain
            with fewer than two spots (nothing to hold out) or whose rows hold one posture.

    """
    planes = 3 * len(set(contacts.sessions))
    equations = int(row_counts(contacts.kinds).sum())  # 3 per flush contact, 1 per point contact
    if equations <= planes:
        raise InputError(
            f"{len(contacts)} usable rows{_files_of(contacts.labels)} give {equations} equations for the "
            f"{planes} plane parameters that have no prior{_left_out(left_out)}: record more contacts"
        )
    for chain in model.contact.chains:
        rows = zip(contacts.chains, contacts.sessions, contacts.labels, strict=True)
        mine = [(s, label) for c, s, label in rows if c == chain]
        spots = {(s, spot_of(label)) for s, label in mine}
        if len(spots) < 2:
            raise InputError(
                f"chain '{chain}' has {len(spots)} usable spot(s){_files_of([label for _, label in mine])}"
                f"{_left_out(left_out)}: cross-validation needs at least 2"
            )
        joints = contacts.joints[[i for i, c in enumerate(contacts.chains) if c == chain]]  # (n, nj) rad
        if np.abs(joints - joints[0]).max() <= SAME_POSTURE_RAD:
            raise InputError(
                f"chain '{chain}': its {len(joints)} usable rows{_files_of([label for _, label in mine])} hold one "
                f"posture (no joint differs by more than {SAME_POSTURE_RAD:g} rad): they identify nothing of its "
                "kinematics; record contacts at different postures"
            )


def _left_out(flags: Sequence[Flag]) -> str:
    """``; N rows left out: FILE:LINE (why), ...`` (a few of them), or nothing."""
    if not flags:
        return ""
    shown = ", ".join(f"{f.label.rsplit(':', 1)[0]} ({f.reason})" for f in flags[:3])
    return f"; {len(flags)} row(s) left out: {shown}" + (f" and {len(flags) - 3} more" if len(flags) > 3 else "")


def _files_of(labels: Sequence[str]) -> str:
    """`` (FILE:LINE, ...)`` of the rows a message is about (a few of them), or nothing without labels."""
    named = [label.rsplit(":", 1)[0] for label in labels if label.count(":") >= 2]
    if not named:
        return ""
    shown = ", ".join(named[:3]) + (f" and {len(named) - 3} more" if len(named) > 3 else "")
    return f" ({shown})"


def _select_screened(
    model: CalibrationModel,
    everything: Observations,
    screen: Screening,
    setup: tuple[CalibrationConfig, list[CandidateConfig]],
    settings: Settings,
    progress: ProgressCallback,
    backend: Backend | None,
) -> ModelSelection:
    """Select the model on the rows ``screen`` keeps; screen again with it and, if it flags more, select once more."""
    config, candidates = setup
    seeds = range(settings.seed, settings.seed + config.fold_seeds)
    sessions = set(everything.contacts.subset(screen.kept).sessions)
    noise = Noise(DEFAULT_NOISE, DEFAULT_FLOOR_NOISE)
    warm: dict[tuple[str, float], tuple[FloatArray, ...]] = {}
    for selection_round in range(1, SELECTIONS + 1):
        check_enough(model, everything.contacts.subset(screen.kept), config, screen.dropped)
        observations = everything.subset(screen.kept)
        folds = repeated_folds(model.contact, observations.contacts, config.folds, seeds)
        selection = select_model(
            model, observations, config, folds, noise, candidates, progress, backend, settings.search, warm
        )
        # the next selection's rows lack only the rows flagged now: its fits start from these ones (the
        # plausible ones: a weak prior's implausible fit ends where its flat valley stops the steps)
        plausible = {(r.candidate, r.prior_scale) for r in selection.results if r.plausible}
        warm = {pair: selection.estimates[pair].rounds for pair in plausible if selection.estimates[pair].rounds}
        chosen = next(c for c in candidates if c.name == selection.chosen.candidate)
        spec = spec_for_rows(model, candidate_spec(model, chosen, config.prior, selection.chosen.prior_scale), sessions)
        best = selection.estimates[chosen.name, selection.chosen.prior_scale]
        if selection_round == SELECTIONS or not screen.run(spec, best.noise, best.x):
            break  # the chosen model flags no new row (or the last selection is made): done
    return selection


def calibrate(
    scene: Scene,
    train: Contacts,
    sessions: Sequence[str],
    settings: Settings | None = None,
    progress: ProgressCallback = ignore_progress,
    backend: Backend | None = None,
) -> Calibration:
    """Calibrate the chains seen in ``train``.

    Args:
        scene: Scene (robot model and config, with its calibration section).
        train: Training rows.
        sessions: Every session the model must know (training and held-out).
        settings: How to run; defaults if None.
        progress: Told when each cross-validation step starts.
        backend: Where the candidates' cross-validations run; None: this process.

    Returns:
        The calibration, with its warnings (rows left out at the screening's limit,
        a URDF kept as it was): bad rows never stop it.

    Raises:
        InputError: Unknown candidate names, or too few usable rows.

    Example:
        >>> calibration = calibrate(scene, contacts, ["left_train", "right_train"])
        >>> calibration.deliverables.urdf.result.chains["left"].mean_abs  # predicted held-out error

    """
    settings = settings or Settings()
    config, candidates = _settings(scene, settings)
    model = CalibrationModel(scene, sorted(set(train.chains)), sessions, config.compliance, train.kinds_by_chain())
    check_exportable(model.contact)  # a layout the URDF cannot carry costs milliseconds, not a calibration
    everything = model.observations(train)
    flags = unusable_rows(model, everything, config)
    usable = [i for i in range(len(train)) if i not in {f.row for f in flags}]
    check_enough(model, train.subset(usable), config, flags)
    sessions_in = set(train.subset(usable).sessions)
    middle = sorted(config.prior_scales)[len(config.prior_scales) // 2]
    spec = spec_for_rows(model, candidate_spec(model, candidates[0], config.prior, middle), sessions_in)
    start = held_at_urdf(model, spec, start_point(model, everything.subset(usable)))
    screen = Screening(model, everything, train.labels, usable, config, settings.drop_outliers)
    screen.run(spec, Noise(DEFAULT_NOISE, DEFAULT_FLOOR_NOISE), start)
    selection = _select_screened(model, everything, screen, (config, candidates), settings, progress, backend)
    flags.extend(screen.flags)
    for flag in screen.flags:
        LOG.warning("bad row %s: studentised residual %.1f", flag.label, flag.value)
    kept = screen.kept
    chosen = next(c for c in candidates if c.name == selection.chosen.candidate)
    spec = spec_for_rows(model, candidate_spec(model, chosen, config.prior, selection.chosen.prior_scale), sessions_in)
    observations = everything.subset(kept)
    after = selection.estimates[chosen.name, selection.chosen.prior_scale]
    sides = tuple(model.columns([Kind.CONTACT_HEIGHT, Kind.CONTACT_TILT, Kind.CONTACT_POINT, Kind.PLANE]))
    before_spec = spec_for_rows(model, Spec(sides, np.full(model.size, np.inf), floor=False), sessions_in)
    before = estimate(model, observations, before_spec, after.noise, start_point(model, observations), rounds=1)
    postures = level_postures(model.contact, observations.contacts, settings.structural_postures, settings.seed)
    base = base_at(model.contact, postures, DEFAULT_NOISE)
    base_with_floor = base_at(model.contact, postures, DEFAULT_NOISE, DEFAULT_FLOOR_NOISE).size if model.floor else None
    deliverables = choose_deliverables(selection, candidates)
    return Calibration(
        model=model,
        config=config,
        train=train,
        kept=tuple(kept),
        flags=tuple(flags),
        selection=selection,
        candidate=chosen,
        spec=spec,
        before=before,
        after=after,
        base=base,
        base_with_floor=base_with_floor,
        deliverables=deliverables,
        warnings=(*screen.warnings, *deliverables.warnings),
    )


def held_out_x(calibration: Calibration, x: FloatArray, contacts: Contacts) -> FloatArray:
    """Protocol 1: a held-out session takes the plane fitted with the same chain in training.

    A session also present in training keeps its own plane. Another session takes the
    plane of the training session with the most kept rows of the held-out chain: the
    plane's height is only known relative to the chain it was fitted with
    (:func:`posegen.calibrate.file_judge.with_training_planes`).
    """
    return with_training_planes(calibration.model, x, calibration.train.subset(list(calibration.kept)), contacts)


def held_out_residuals(calibration: Calibration, contacts: Contacts) -> dict[str, dict[str, FloatArray]]:
    """Held-out residuals (n, 3) per protocol ("training_plane", "refitted_plane") and model."""
    model = calibration.model
    observations = model.observations(contacts)
    out: dict[str, dict[str, FloatArray]] = {"training_plane": {}, "refitted_plane": {}}
    for name, fitted in (("before", calibration.before), ("after", calibration.after)):
        x = held_out_x(calibration, fitted.x, contacts)
        out["training_plane"][name] = model.evaluate(x, observations, floor=False).contact
        planes = plane_spec(model, set(contacts.sessions))
        refit = model.x_of(fit(model, observations, planes, fitted.noise, x)[0])
        out["refitted_plane"][name] = model.evaluate(refit, observations, floor=False).contact
    return out
