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
from pathlib import Path

import numpy as np

from posegen.calibrate import Calibration, Perturbation, Settings, calibrate, held_out_x
from posegen.calibrate.simulation import perturbed_robot, settle_true
from posegen.io import write_yaml
from posegen.model import Contacts, build_design, planned_kinds, read_measurements
from posegen.parallel import open_backend
from posegen.robot import Scene, load_pool, scene_for
from posegen.select import iroc
from posegen.session import Robot, SessionSettings, read_index, rehearse_session, start_session

TABLE = "table_1"  # the table session of every rehearsal


def robot_contacts(
    scene: Scene, joints: np.ndarray, chains: Sequence[str], spots: Sequence[str], robot: Robot
) -> Contacts:
    """Contacts of the rehearsal's robot (every chain of the config, one table) at planned postures, as simulate."""
    perturbation = Perturbation(
        length_m=robot.error_mm * 1e-3,
        angle_rad=float(np.deg2rad(robot.error_deg)),
        encoder_noise_rad=float(np.deg2rad(robot.noise_deg)),
        compliance_rad_per_nm=robot.compliance_rad_per_knm * 1e-3,
    )
    every = tuple(c.name for c in scene.config.chains)
    kinds = {c: (scene.chain(c).contact_kind,) for c in every}
    model, x = perturbed_robot(scene, every, [TABLE], perturbation, robot.seed, kinds)
    planned = Contacts(joints, tuple(chains), (TABLE,) * len(chains), tuple(spots), planned_kinds(scene, chains))
    settled, converged = settle_true(model, x, planned)
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


def bench_session(
    pool_path: Path,
    workdir: Path,
    machine: str,
    seeds: Sequence[int] = (1, 2, 3),
    held_out: int = 40,
    compliance: float = 0.3,
    max_batches: int = 6,
    settings: SessionSettings | None = None,
) -> None:
    """Print the table: true held-out error at the session's contact counts, three orders, over robot seeds."""
    settings = settings or SessionSettings(target_mm=1.0, candidates=("offsets", "offsets_hip_pitch"), fold_seeds=1)
    lean = Settings(candidates=settings.candidates, fold_seeds=settings.fold_seeds, seed=settings.seed)
    pool = load_pool(pool_path)
    scene = scene_for(pool.provenance, None)
    rng = np.random.default_rng(0)
    held_rows = set(rng.choice(len(pool.postures), size=held_out, replace=False).tolist())
    data = pool.to_dict()
    design_rows = [i for i in range(len(pool.postures)) if i not in held_rows]
    data["postures"] = [data["postures"][i] for i in design_rows]
    design_pool = workdir / "session_pool.yaml"
    write_yaml(design_pool, data)
    joints = pool.joints()
    chains = [p.chain for p in pool.postures]
    spots = [p.spot for p in pool.postures]
    sub_joints, sub_chains, sub_spots = (
        joints[design_rows],
        [chains[i] for i in design_rows],
        [spots[i] for i in design_rows],
    )
    design, _ = build_design(scene, sub_joints, sub_chains)
    ranking = list(iroc(design).ranking)
    rows: dict[str, list[list[float]]] = {
        "session (its recordings)": [],
        "session postures": [],
        "IROC": [],
        "random": [],
    }
    counts: list[list[int]] = []
    stops: list[tuple[float, float, int]] = []
    start = time.perf_counter()
    for seed in seeds:
        robot = Robot(seed=seed, compliance_rad_per_knm=compliance)
        folder = workdir / f"session_{seed}"
        with open_backend(2) as backend:
            start_session(str(design_pool), str(folder), settings, backend)
            rehearse_session(str(folder), robot, backend, max_batches)
        index = read_index(folder)
        kept = sorted(held_rows)
        held = robot_contacts(scene, joints[kept], [chains[i] for i in kept], [spots[i] for i in kept], robot)
        order = np.random.default_rng(seed).permutation(len(design_rows)).tolist()
        recorded: Contacts | None = None
        planned: list[int] = []
        mine: dict[str, list[float]] = {k: [] for k in rows}
        at: list[int] = []
        for batch in index.batches:
            if batch.assessment is None or batch.assessment.error:
                continue
            part = read_measurements(folder / batch.folder / "measurements.yaml", scene).contacts
            recorded = part if recorded is None else recorded.concat(part)
            planned.extend(batch.pool_rows)
            n = len(recorded)
            at.append(n)
            mine["session (its recordings)"].append(true_error_mm(calibrate(scene, recorded, [TABLE], lean), held))
            for name, picked in (("session postures", planned), ("IROC", ranking[:n]), ("random", order[:n])):
                picked_chains, picked_spots = [sub_chains[i] for i in picked], [sub_spots[i] for i in picked]
                contacts = robot_contacts(scene, sub_joints[picked], picked_chains, picked_spots, robot)
                mine[name].append(true_error_mm(calibrate(scene, contacts, [TABLE], lean), held))
            last = batch
        for name in rows:
            rows[name].append(mine[name])
        counts.append(at)
        predicted = max(last.assessment.predicted_z_mm.values())
        stops.append((predicted, mine["session (its recordings)"][-1], at[-1]))
    took = time.perf_counter() - start
    print(f"\n### session: true held-out height error at fixed contact counts ({machine})\n")
    print(
        f"{len(seeds)} robot seeds (hips {compliance:g} rad/kN m), {held_out} held-out postures, pool "
        f"{len(design_rows)}; URDF deliverable, candidates {', '.join(settings.candidates)}; {took:.0f} s\n"
    )
    print("| contacts | " + " | ".join(f"{name}: median (min-max) mm" for name in rows) + " |")
    print("|---" * (len(rows) + 1) + "|")
    for b in range(min(len(c) for c in counts)):
        cells = []
        for name in rows:
            values = [r[b] for r in rows[name]]
            cells.append(f"{statistics.median(values):.2f} ({min(values):.2f}-{max(values):.2f})")
        shown = sorted({c[b] for c in counts})
        print(f"| {'/'.join(str(c) for c in shown)} | " + " | ".join(cells) + " |")
    ratios = [p / t for p, t, _ in stops]
    print(
        f"\nat the last batch: predicted (CV, worst chain) / true held-out error = "
        f"{', '.join(f'{r:.2f}' for r in ratios)} (median {statistics.median(ratios):.2f}); "
        f"contacts {', '.join(str(n) for _, _, n in stops)}"
    )
