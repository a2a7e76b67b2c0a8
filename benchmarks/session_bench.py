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
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from posegen.calibrate import Calibration, Perturbation, Settings, calibrate, held_out_x
from posegen.calibrate.simulation import contact_offsets, perturbed_robot, settle_true
from posegen.io import load_pool, write_yaml
from posegen.model import Contacts, build_design, planned_kinds, read_measurements
from posegen.parallel import open_backend
from posegen.robot import Scene, scene_for
from posegen.select import iroc
from posegen.session import Robot, SessionSettings, read_index, rehearse_session, start_session

TABLE = "table_1"  # the table session of every rehearsal


def robot_contacts(
    scene: Scene, joints: np.ndarray, chains: Sequence[str], spots: Sequence[str], robot: Robot
) -> Contacts:
    """Contacts of the rehearsal's robot (every chain of the config, one table) at planned postures, as simulate.

    Each posture on its local plane (the rehearsal's contact noise, drawn as ``simulate`` draws it: the same
    posture gets the same offset in the session's recordings and in the fixed orders).
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
    settled, converged = settle_true(model, x, planned, offsets=contact_offsets(planned, perturbation, robot.seed))
    settled = settled.subset(np.flatnonzero(converged))
    rng = np.random.default_rng([robot.seed, 1])
    return settled.at(settled.joints + rng.normal(0.0, perturbation.encoder_noise_rad, settled.joints.shape))


def true_error_mm(calibration: Calibration, held: Contacts) -> float:
    """Mean absolute held-out height error (mm) of the URDF deliverable, of its worst chain (the stopping chain)."""
    model = calibration.model
    mine = held.subset([i for i, c in enumerate(held.chains) if c in model.contact.chains])
    x = held_out_x(calibration, calibration.deliverables.urdf.estimate.x, mine)
    residuals = model.evaluate(x, model.observations(mine), floor=False).contact
    by_chain = np.array(mine.chains)
    return max(float(np.mean(np.abs(residuals[by_chain == c, 0])) * 1e3) for c in sorted(set(mine.chains)))


ORDERS = ("session (its recordings)", "session postures", "IROC", "random")


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

    def contacts(self, rows: Sequence[int], robot: Robot) -> Contacts:
        """The robot's contacts at some pool rows."""
        chains, spots = [self.chains[i] for i in rows], [self.spots[i] for i in rows]
        return robot_contacts(self.scene, self.joints[list(rows)], chains, spots, robot)


def split_pool(pool_path: Path, workdir: Path, held_out: int) -> tuple[Split, Path]:
    """Hold postures out of the pool (seed 0); write the design pool; rank it by IROC."""
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
    ranking = list(iroc(design).ranking)
    spots = [p.spot for p in pool.postures]
    return Split(scene, joints, chains, spots, design_rows, held, ranking), design_pool


def judge_seed(
    split: Split,
    design_pool: Path,
    folder: Path,
    robot: Robot,
    settings: SessionSettings,
    max_batches: int,
    workers: int = 2,
) -> tuple[list[int], dict[str, list[float]], float, float]:
    """Rehearse one robot.

    Returns:
        The contact counts after each batch; each order's true error there (on the held-out
        postures without contact noise: the model's error alone); at the last batch, the
        session's predicted error and its true error on held-out contacts with the
        rehearsal's contact noise (what a validation set would show, as the CV predicts).

    """
    with open_backend(workers) as backend:
        start_session(str(design_pool), str(folder), settings, backend)
        rehearse_session(str(folder), robot, backend, max_batches)
    lean = Settings(candidates=settings.candidates, fold_seeds=settings.fold_seeds, seed=settings.seed)
    held = split.contacts(split.held_rows, replace(robot, contact_noise_mm=0.0, contact_noise_deg=0.0))
    noisy_held = split.contacts(split.held_rows, robot)
    noisy = float("nan")
    shuffled = np.random.default_rng(robot.seed).permutation(len(split.design_rows)).tolist()
    recorded: Contacts | None = None
    planned: list[int] = []  # design pool rows
    errors: dict[str, list[float]] = {k: [] for k in ORDERS}
    counts: list[int] = []
    predicted = float("nan")
    for batch in read_index(folder).batches:
        if batch.assessment is None or batch.assessment.error:
            continue
        part = read_measurements(folder / batch.folder / "measurements.yaml", split.scene).contacts
        recorded = part if recorded is None else recorded.concat(part)
        planned.extend(batch.pool_rows)
        counts.append(len(recorded))
        calibration = calibrate(split.scene, recorded, [TABLE], lean)
        errors[ORDERS[0]].append(true_error_mm(calibration, held))
        noisy = true_error_mm(calibration, noisy_held)
        for name, picked in zip(ORDERS[1:], (planned, split.ranking, shuffled), strict=True):
            rows = [split.design_rows[i] for i in picked[: len(recorded)]]
            contacts = split.contacts(rows, robot)
            errors[name].append(true_error_mm(calibrate(split.scene, contacts, [TABLE], lean), held))
        predicted = max(batch.assessment.predicted_z_mm.values())
    return counts, errors, predicted, noisy


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
) -> None:
    """Print the table: true held-out error at the session's contact counts, four orders, over robot seeds.

    ``robot``: the simulated robot's sizes (its seed is each of ``seeds``); None: ``Robot``'s defaults
    (contact noise as the real recordings') with the hips' ``compliance``.
    """
    robot = robot or Robot(compliance_rad_per_knm=compliance)
    settings = settings or SessionSettings(target_mm=1.0, candidates=("offsets", "offsets_hip_pitch"), fold_seeds=1)
    split, design_pool = split_pool(pool_path, workdir, held_out)
    start = time.perf_counter()
    trials = [
        judge_seed(
            split, design_pool, workdir / f"session_{seed}", replace(robot, seed=seed), settings, max_batches, workers
        )
        for seed in seeds
    ]
    took = time.perf_counter() - start
    print(f"\n### session: true held-out height error at fixed contact counts ({machine})\n")
    print(
        f"{len(seeds)} robot seeds (hips {robot.compliance_rad_per_knm:g} rad/kN m, contact noise "
        f"{robot.contact_noise_mm:g} mm / {robot.contact_noise_deg:g} deg), {held_out} held-out postures, pool "
        f"{len(split.design_rows)}; URDF deliverable, candidates {', '.join(settings.candidates)}; {took:.0f} s\n"
    )
    print("true error: mean abs height, worst chain, on held-out contacts without contact noise (the model's)\n")
    print("| contacts | " + " | ".join(f"{name}: median (min-max) mm" for name in ORDERS) + " |")
    print("|---" * (len(ORDERS) + 1) + "|")
    for b in range(min(len(counts) for counts, _, _, _ in trials)):
        cells = []
        for name in ORDERS:
            values = [errors[name][b] for _, errors, _, _ in trials]
            cells.append(f"{statistics.median(values):.2f} ({min(values):.2f}-{max(values):.2f})")
        shown = sorted({counts[b] for counts, _, _, _ in trials})
        print(f"| {'/'.join(str(c) for c in shown)} | " + " | ".join(cells) + " |")
    ratios = [predicted / noisy for _, _, predicted, noisy in trials]
    predicted = ", ".join(f"{p:.2f}" for _, _, p, _ in trials)
    true = ", ".join(f"{n:.2f}" for *_, n in trials)
    contacts = ", ".join(str(counts[-1]) for counts, _, _, _ in trials)
    print(
        f"\nat the last batch: predicted (CV, worst chain) / true held-out error (worst chain, held-out contacts "
        f"with contact noise) = {', '.join(f'{r:.2f}' for r in ratios)} (median {statistics.median(ratios):.2f}); "
        f"predicted {predicted} mm, true {true} mm; contacts {contacts}"
    )
