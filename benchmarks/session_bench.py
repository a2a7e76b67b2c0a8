"""The session benchmark: a rehearsal's true held-out error at fixed contact counts, against fixed orders.

Imported by ``benchmarks/run.py`` (stage ``session``). Per robot seed: a session is started
on the pool minus held-out postures and rehearsed on the simulated robot (hips compliant)
until done or ``max_batches``; after each batch, the URDF deliverable (what the session's
stopping figure is about) is judged on the held-out postures of the same robot (true
error, mean absolute height), and so are calibrations on the same number of contacts
taken in the IROC ranking order and in a random order. The three use the same calibration
settings. The session's own contacts come from its recordings (``simulate --bag``); the
fixed orders' from ``posegen simulate`` at their postures (same robot, same table plane),
and so, for a like-for-like comparison of the choice alone, do the session's postures.
So does the fixed exact-k IROC design (``posegen select --k K`` on the design pool, K = 60 by
default), the session's yardstick. Both deliverables are judged: the URDF alone, and the URDF
with its compliance compensation (NaN when no compliant candidate wins). The figures are
summarised by ``benchmarks/session_compare.py``.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
from session_compare import (  # benchmarks/session_compare.py, beside this module
    DELIVERABLES,
    ORDERS,
    SeedResult,
    report,
    write_json,
)

from posegen.calibrate import Calibration, Perturbation, Settings, calibrate, held_out_x
from posegen.calibrate.simulation import contact_offsets, perturbed_robot, settle_true
from posegen.io import load_pool, write_yaml
from posegen.model import Contacts, Design, build_design, planned_kinds, read_measurements
from posegen.parallel import open_backend
from posegen.robot import Scene, scene_for
from posegen.select import iroc, select_k
from posegen.session import Robot, SessionIndex, SessionSettings, read_index, rehearse_session, start_session

TABLE = "table_1"  # the table session of every rehearsal
JSON = "session_bench.json"  # the raw per-seed figures, in the work folder


def robot_contacts(
    scene: Scene, joints: np.ndarray, chains: Sequence[str], spots: Sequence[str], robot: Robot
) -> Contacts:
    """Contacts of the rehearsal's robot (every chain of the config, one table) at planned postures, as simulate.

    Each posture on its local plane (the rehearsal's contact noise, drawn as ``simulate`` draws it: the same
    posture gets the same offset in every order). The session's recordings hold the route's contact
    posture instead (a few mrad off, the go-to-contact's overshoot), whose draw is another, independent one;
    and ``simulate --bag`` keeps the legs as routed where this closes the second leg on the true floor.
    """
    perturbation = Perturbation(
        length_m=robot.error_mm * 1e-3,
        angle_rad=float(np.deg2rad(robot.error_deg)),
        encoder_noise_rad=float(np.deg2rad(robot.noise_deg)),
        compliance_rad_per_nm=robot.compliance_rad_per_knm * 1e-3,
        contact_noise_m=robot.contact_noise_mm * 1e-3,
        contact_noise_rad=float(np.deg2rad(robot.contact_noise_deg)),
    )
    every = tuple(c.name for c in scene.config.chains)
    kinds = {c: (scene.chain(c).contact_kind,) for c in every}
    model, x = perturbed_robot(scene, every, [TABLE], perturbation, robot.seed, kinds)
    planned = Contacts(joints, tuple(chains), (TABLE,) * len(chains), tuple(spots), planned_kinds(scene, chains))
    settled, converged, _ = settle_true(model, x, planned, offsets=contact_offsets(planned, perturbation, robot.seed))
    settled = settled.subset(np.flatnonzero(converged))
    rng = np.random.default_rng([robot.seed, 1])
    return settled.at(settled.joints + rng.normal(0.0, perturbation.encoder_noise_rad, settled.joints.shape))


def true_error_mm(calibration: Calibration, held: Contacts, deliverable: str = "urdf") -> float:
    """Mean absolute held-out height error (mm) of a deliverable, of its worst chain (the stopping chain).

    ``deliverable``: ``urdf`` (the URDF alone) or ``compensated`` (the URDF with its compliance
    compensation); NaN when the calibration ships no compensated deliverable.
    """
    chosen = getattr(calibration.deliverables, deliverable)
    if chosen is None:
        return float("nan")
    model = calibration.model
    mine = held.subset([i for i, c in enumerate(held.chains) if c in model.contact.chains])
    x = held_out_x(calibration, chosen.estimate.x, mine)
    residuals = model.evaluate(x, model.observations(mine), floor=False).contact
    by_chain = np.array(mine.chains)
    return max(float(np.mean(np.abs(residuals[by_chain == c, 0])) * 1e3) for c in sorted(set(mine.chains)))


def both_errors(calibration: Calibration, held: Contacts) -> dict[str, float]:
    """Each deliverable's true error (mm)."""
    return {d: true_error_mm(calibration, held, d) for d in DELIVERABLES}


@dataclass(frozen=True)
class Split:
    """The pool split into the postures a session may choose (the design pool) and held-out ones."""

    scene: Scene
    joints: np.ndarray  # (n, nj) the whole pool
    chains: list[str]
    spots: list[str]
    design_rows: list[int]  # pool rows of the design pool, in its order
    held_rows: list[int]
    ranking: list[int]  # IROC ranking of the design pool (its rows)
    fixed: list[int]  # the exact-k IROC design (select --k) of the design pool (its rows)
    design: Design  # of the design pool (its base regressors)

    def contacts(self, rows: Sequence[int], robot: Robot) -> Contacts:
        """The robot's contacts at some pool rows."""
        chains, spots = [self.chains[i] for i in rows], [self.spots[i] for i in rows]
        return robot_contacts(self.scene, self.joints[list(rows)], chains, spots, robot)


def split_pool(pool_path: Path, workdir: Path, held_out: int, fixed_k: int = 60) -> tuple[Split, Path]:
    """Hold postures out of the pool (seed 0); write the design pool; rank it by IROC; its exact-k design.

    The exact design is what ``posegen select --k fixed_k`` writes for the design pool (no DETMAX runs).
    """
    pool = load_pool(pool_path)
    scene = scene_for(pool.provenance, None)
    held = sorted(np.random.default_rng(0).choice(len(pool.postures), size=held_out, replace=False).tolist())
    design_rows = [i for i in range(len(pool.postures)) if i not in set(held)]
    data = pool.to_dict()
    data["postures"] = [data["postures"][i] for i in design_rows]
    design_pool = workdir / "session_pool.yaml"
    write_yaml(design_pool, data)
    joints, chains = pool.joints(), [p.chain for p in pool.postures]
    design, _ = build_design(scene, joints[design_rows], [chains[i] for i in design_rows])
    ranking = iroc(design).ranking
    fixed = list(select_k(design, fixed_k, ranking).rows)
    spots = [p.spot for p in pool.postures]
    return Split(scene, joints, chains, spots, design_rows, held, list(ranking), fixed, design), design_pool


def predicted_mm(calibration: Calibration, deliverable: str) -> float:
    """A deliverable's CV-predicted held-out height error (mm, mean abs, worst chain); NaN when it is not shipped."""
    chosen = getattr(calibration.deliverables, deliverable)
    if chosen is None:
        return float("nan")
    return max(e.mean_abs[0] for e in chosen.result.chains.values()) * 1e3


def robot_time(index: SessionIndex) -> tuple[float, int]:
    """Robot time the session's bags recorded (s, their joint states) and the contacts measured in them."""
    recorded = [b.recording for b in index.batches if b.recording is not None]
    return sum(r.duration_s for r in recorded), sum(r.contacts for r in recorded)


def judge_seed(
    split: Split,
    design_pool: Path,
    folder: Path,
    robot: Robot,
    settings: SessionSettings,
    max_batches: int,
    workers: int,
) -> SeedResult:
    """Rehearse one robot; judge every order after each batch, and the fixed design, on its held-out postures.

    True errors are on the held-out postures without contact noise (the model's error alone);
    the stopping rule's is on held-out contacts with the rehearsal's contact noise (what a
    validation set would show, as the CV predicts), at the last batch.
    """
    with open_backend(workers) as backend:
        start_session(str(design_pool), str(folder), settings, backend)
        rehearse_session(str(folder), robot, backend, max_batches)
    lean = Settings(candidates=settings.candidates, fold_seeds=settings.fold_seeds, seed=settings.seed)
    held = split.contacts(split.held_rows, replace(robot, contact_noise_mm=0.0, contact_noise_deg=0.0))
    noisy_held = split.contacts(split.held_rows, robot)
    shuffled = np.random.default_rng(robot.seed).permutation(len(split.design_rows)).tolist()
    recorded: Contacts | None = None
    planned: list[int] = []  # design pool rows
    errors: dict[str, dict[str, list[float]]] = {d: {k: [] for k in ORDERS} for d in DELIVERABLES}
    counts: list[int] = []
    predicted: dict[str, float] = {}
    noisy: dict[str, float] = {}
    index = read_index(folder)
    for batch in index.batches:
        if batch.assessment is None or batch.assessment.error:
            continue
        part = read_measurements(folder / batch.folder / "measurements.yaml", split.scene).contacts
        recorded = part if recorded is None else recorded.concat(part)
        planned.extend(batch.pool_rows)
        counts.append(len(recorded))
        calibration = calibrate(split.scene, recorded, [TABLE], lean)
        judged = [both_errors(calibration, held)]
        noisy = {d: true_error_mm(calibration, noisy_held, d) for d in DELIVERABLES}
        predicted = {d: predicted_mm(calibration, d) for d in DELIVERABLES}
        for picked in (planned, split.ranking, shuffled):
            contacts = split.contacts([split.design_rows[i] for i in picked[: len(recorded)]], robot)
            judged.append(both_errors(calibrate(split.scene, contacts, [TABLE], lean), held))
        for name, figures in zip(ORDERS, judged, strict=True):
            for d in DELIVERABLES:
                errors[d][name].append(figures[d])
    fixed = split.contacts([split.design_rows[i] for i in split.fixed], robot)
    fixed_error = both_errors(calibrate(split.scene, fixed, [TABLE], lean), held)
    spent, measured = robot_time(index)
    return SeedResult(robot.seed, counts, errors, len(fixed), fixed_error, predicted, noisy, spent, measured)


def bench_session(
    pool_path: Path,
    workdir: Path,
    machine: str,
    seeds: Sequence[int] = (1, 2, 3),
    held_out: int = 40,
    compliance: float = 0.3,
    max_batches: int = 6,
    settings: SessionSettings | None = None,
    workers: int = 2,
    robot: Robot | None = None,
    fixed_k: int = 60,
    plot: Path | None = None,
) -> list[SeedResult]:
    """Print the tables: true held-out error at the session's contact counts, four orders and the fixed design.

    ``robot``: the simulated robot's sizes (its seed is each of ``seeds``); None: ``Robot``'s defaults
    (contact noise as the real recordings') with the hips' ``compliance``. The raw per-seed figures
    go to ``workdir/session_bench.json``; the curves to ``plot`` (PNG) if given.
    """
    robot = robot or Robot(compliance_rad_per_knm=compliance)
    settings = settings or SessionSettings(  # no stop before max_batches: every curve reaches the same counts
        target_mm=1.0, candidates=("offsets", "offsets_hip_pitch"), fold_seeds=1, patience=0
    )
    split, design_pool = split_pool(pool_path, workdir, held_out, fixed_k)
    start = time.perf_counter()
    trials = []
    for seed in seeds:
        folder = workdir / f"session_{seed}"
        trials.append(judge_seed(split, design_pool, folder, replace(robot, seed=seed), settings, max_batches, workers))
        write_json(trials, {"partial": True}, workdir / JSON)  # a long run keeps what it has
    took = time.perf_counter() - start
    about = describe(robot, settings, len(seeds), held_out, len(split.design_rows), took)
    facts = {"machine": machine, "about": about, "robot": asdict(robot), "session": str(settings), "wall_s": took}
    write_json(trials, facts | {"held_out": held_out, "fixed_k": fixed_k, "max_batches": max_batches}, workdir / JSON)
    report(trials, machine, about, plot, fixed_k)
    return trials


def describe(robot: Robot, settings: SessionSettings, seeds: int, held_out: int, pool: int, took_s: float) -> str:
    """The settings of a run, in one line."""
    return (
        f"{seeds} robot seeds (hips {robot.compliance_rad_per_knm:g} rad/kN m, contact noise "
        f"{robot.contact_noise_mm:g} mm / {robot.contact_noise_deg:g} deg), {held_out} held-out postures, pool "
        f"{pool}, margin {settings.margin:g}, {settings.batch_postures}-posture batches, "
        f"candidates {', '.join(settings.candidates)}, fold seeds {settings.fold_seeds}; {took_s:.0f} s"
    )
