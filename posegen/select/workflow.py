"""The select stage's command, from files to files: ``posegen select``."""

from __future__ import annotations

import hashlib
import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from posegen.arguments import check_count, check_seed
from posegen.errors import InfeasibleError, InputError
from posegen.io import (
    DesignFigures,
    FollowUpFigures,
    Pool,
    Selection,
    SelectionMethod,
    check_apart,
    check_named,
    check_writable,
    chosen_from_pool,
    claim_output,
    load_pool,
    write_selection,
)
from posegen.model import DEFAULT_NOISE, Contacts, build_design, measurement_item, read_measurements
from posegen.progress import ProgressCallback, Steps, ignore_progress
from posegen.robot import CandidateConfig, Scene, scene_for_postures
from posegen.select.figures import design_selection, plot_detmax, plot_o1
from posegen.select.followup import follow_up, read_calibration_model
from posegen.select.selection import detmax_runs, iroc, select_k
from posegen.select.subset_selection import Subset, subset_of

LOG = logging.getLogger(__name__)
MAX_RUNS = 10_000  # DETMAX restarts: each one a whole exchange search


@dataclass(frozen=True)
class SelectionSettings:
    """How postures are chosen.

    Example:
        >>> settings = posegen.SelectionSettings(k=40, runs=4, seed=1)  # exactly 40, DETMAX from 4 starts

    """

    k: int | None = None  # exactly k postures (greedy, IROC top-k, DETMAX, exchange); None: where O1 peaks
    runs: int = 0  # DETMAX runs from seeded random starts (run r draws from seed * 1000 + r)
    seed: int = 0  # seed of the DETMAX starts
    fractions: tuple[float, ...] = (0.9, 0.95)  # report the smallest k reaching these fractions of O1*


def select_pool_file(
    pool_path: str,
    output: str,
    settings: SelectionSettings | None = None,
    config_path: str | None = None,
    progress: ProgressCallback = ignore_progress,
) -> Selection[DesignFigures]:
    """Select postures from a pool file; write the selection file and its plots.

    Args:
        pool_path: Pool file.
        output: Selection file; ``<stem>_o1.png`` (and with DETMAX runs, ``<stem>_detmax.png``)
            go beside it.
        settings: How to choose; defaults if None.
        config_path: Scene config; None: the one saved in the pool.
        progress: Told when each step starts.

    Returns:
        The selection, as written.

    The arguments, the pool (its robot model included) and the output's place are
    checked before any work; the output is locked while it is made. Wall times of the
    steps are logged (``-v``), never written into the file: the same pool and settings
    give the same bytes.

    Raises:
        PosegenError: Bad arguments, not a pool, a pool of another robot model, an empty
            or rank-deficient pool, k out of range, or an output that cannot be written.

    """
    settings = settings or SelectionSettings()
    k, runs, seed = settings.k, settings.runs, settings.seed
    if k is not None:
        check_count(k, "k")
    check_count(runs, "runs", minimum=0, maximum=MAX_RUNS)
    check_seed(seed, "seed")
    check_named(output)
    path = Path(output)
    plots = [path.with_name(path.stem + "_o1.png"), path.with_name(path.stem + "_detmax.png")]
    check_writable(path)
    for plot in plots:
        check_writable(plot)
    check_apart([path, *plots], [pool_path, config_path])
    pool = load_pool(pool_path)
    scene = scene_for_postures(pool, pool_path, config_path)
    if not pool.postures:
        raise InfeasibleError(f"{pool_path}: the pool is empty")
    if k is not None and k > len(pool.postures):
        raise InfeasibleError(f"k={k}: the pool has only {len(pool.postures)} postures", parameter="k")
    with claim_output(path, beside=plots):
        timings: dict[str, float] = {}
        say = Steps(4 + runs, progress)
        start = time.perf_counter()
        say("information matrices")
        design, _ = build_design(scene, pool.joints(), [p.chain for p in pool.postures])
        timings["design"] = time.perf_counter() - start
        start = time.perf_counter()
        say("IROC weights")
        result = iroc(design, fractions=settings.fractions)
        timings["iroc"] = time.perf_counter() - start
        size = k if k else len(result.selected.rows)
        start = time.perf_counter()
        detmax: list[Subset] = []
        for r in range(runs):
            say(f"DETMAX run {r + 1}")
            detmax.extend(detmax_runs(design, size, 1, seed * 1000 + r))
        timings["detmax"] = time.perf_counter() - start
        start = time.perf_counter()
        say("exact design" if k else "write")
        chosen = select_k(design, size, result.ranking, tuple(detmax)) if k else result.selected
        timings["k_selection"] = time.perf_counter() - start
        LOG.info("timings (s): %s", ", ".join(f"{step} {t:.3f}" for step, t in timings.items()))
        method = SelectionMethod.K if k else SelectionMethod.IROC
        selection = design_selection(pool, pool_path, design, result, chosen, method, tuple(detmax), seed)
        write_selection(path, selection)
        plot_o1(result, plots[0])
        if detmax:
            top_k = subset_of(design, result.ranking[:size]) if k else result.selected
            plot_detmax(top_k, chosen, tuple(detmax), plots[1])
    return selection


def _given_contacts(given: Sequence[str], scene: Scene) -> Contacts:
    """The contacts of every measurement file given (``FILE[@SESSION]``), concatenated."""
    contacts: Contacts | None = None
    for item in given:
        measured, session = measurement_item(item)
        part = read_measurements(measured, scene, session or None).contacts
        contacts = part if contacts is None else contacts.concat(part)
    assert contacts is not None  # given is not empty
    return contacts


def _follow_up_model(
    scene: Scene, pool: Pool, pool_path: str, calibration_path: str | None, weakest: str | None
) -> tuple[CandidateConfig, float, tuple[float, ...], str | None, str]:
    """The model a follow-up plans for: candidate, prior scale, noise, weakest chain and where it came from.

    Raises:
        InfeasibleError: The pool has no posture of the calibration's weakest chain.

    """
    scales = scene.calibration.prior_scales
    candidate, scale = scene.calibration.candidates[0], scales[len(scales) // 2]
    noise: tuple[float, ...] = DEFAULT_NOISE
    chosen = weakest
    source = "posterior variance of the config's first candidate" if weakest is None else "given"
    if calibration_path is not None:
        candidate, scale, noise, weakest = read_calibration_model(calibration_path, scene)
        source = f"cross-validation of {calibration_path}" if chosen is None else "given"
        weakest = chosen or weakest
        chains = {p.chain for p in pool.postures}
        if weakest not in chains:
            raise InfeasibleError(
                f"{pool_path}: no posture of chain '{weakest}', the weakest of {calibration_path}; "
                f"the pool's chains: {', '.join(sorted(chains))}"
            )
    return candidate, scale, noise, weakest, source


def follow_up_pool_file(
    pool_path: str,
    output: str,
    given: Sequence[str],
    calibration_path: str | None = None,
    k: int = 10,
    config_path: str | None = None,
    weakest: str | None = None,
    exclude: Sequence[int] = (),
) -> Selection[FollowUpFigures]:
    """Choose the next ``k`` postures of a pool for the weakest chain of a calibration; write a selection file.

    Args:
        pool_path: Pool file.
        output: Selection file (route and simulate take it like any other).
        given: Measurement files already recorded, ``FILE[@SESSION]``.
        calibration_path: Their ``calibration.yaml``: its model, prior scale, noise and the
            chain its cross-validation predicts worst. None: the config's first candidate at
            the middle prior scale, noise (1 mm, 0.1 deg), and the chain this model predicts worst.
        k: Postures to choose.
        config_path: Scene config; None: the one saved in the pool.
        weakest: The chain to improve; None: the calibration's weakest (or, without
            one, the chain the model predicts worst).
        exclude: Pool rows never to choose (a session's postures already measured).

    Raises:
        PosegenError: Bad pool, measurements or calibration file; k out of range (or
            more than the postures left).

    """
    check_count(k, "k")
    path = Path(output)
    check_writable(path)
    if not given:
        raise InputError("given: at least one measurement file", parameter="given")
    check_apart([path], [pool_path, calibration_path, config_path, *(measurement_item(g)[0] for g in given)])
    pool = load_pool(pool_path)
    scene = scene_for_postures(pool, pool_path, config_path)
    if k > len(pool.postures):
        raise InfeasibleError(f"k={k}: the pool has only {len(pool.postures)} postures", parameter="k")
    contacts = _given_contacts(given, scene)
    candidate, scale, noise, weakest, source = _follow_up_model(scene, pool, pool_path, calibration_path, weakest)
    with claim_output(path):
        result = follow_up(
            scene,
            pool.joints(),
            [p.chain for p in pool.postures],
            contacts,
            candidate,
            scale,
            noise,
            k,
            weakest,
            exclude,
        )
        provenance = dict(pool.provenance)
        provenance["pool"] = pool_path
        provenance["pool_sha256"] = hashlib.sha256(Path(pool_path).read_bytes()).hexdigest()
        provenance["given"] = list(given)
        provenance["calibration"] = calibration_path
        figures = FollowUpFigures(
            selected=len(result.rows),
            pool_postures=len(pool.postures),
            given_contacts=len(contacts),
            excluded_postures=len(set(exclude)) if exclude else None,
            candidate=candidate.name,
            prior_scale=scale,
            weakest_chain=result.chain,
            weakest_from=source,
            predicted_height_sigma_mm={c: (round(b, 4), round(a, 4)) for c, (b, a) in result.height_std_mm.items()},
        )
        postures = tuple(
            chosen_from_pool(pool, row, rank, round(gain, 6))
            for rank, (row, gain) in enumerate(zip(result.rows, result.gains, strict=True), start=1)
        )
        selection = Selection(provenance, SelectionMethod.FOLLOWUP, pool.joint_names, figures, postures)
        write_selection(path, selection)
    return selection
