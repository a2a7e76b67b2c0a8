"""Screening at its stated rate: rows the whole ``calibrate`` leaves out of noise-only simulations (issue 32).

Per shipped robot: its standing postures (``tests/data/standing/``, 60) recorded by the perturbed
robot of ``simulate`` (default errors 2 mm / 0.5 deg, encoder noise 0.005 deg, no row corrupted)
at each seed, then calibrated with every candidate of its config (one fold seed): the rows left
out (feet and residual, both screenings: before the choice and with the chosen model) per robot,
against the target of 2 %. ``python benchmarks/screening_bench.py [SEEDS]``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.calibrate.standing_postures

from posegen.calibrate import Perturbation, Settings, calibrate, simulate
from tests.calibrate.standing_postures import ROBOTS, load_standing

NOISE_ONLY = Perturbation(encoder_noise_rad=float(np.deg2rad(0.005)))


def bench(seeds: tuple[int, ...]) -> None:
    """Print one table row per robot: rows recorded, rows left out (largest residual), chosen models."""
    print("| robot | rows recorded | rows left out | share | chosen models | seconds |\n|---|---|---|---|---|---|")
    for robot in ROBOTS:
        scene, planned = load_standing(robot)
        rows = left = 0
        chosen, values, start = [], [], time.perf_counter()
        for seed in seeds:
            recorded, _, _ = simulate(scene, planned, NOISE_ONLY, seed)
            calibration = calibrate(scene, recorded, ["sim"], Settings(fold_seeds=1))
            rows += len(recorded)
            left += len(calibration.flags)
            values += [f"{f.reason} {f.value:.1f}" for f in calibration.flags]
            chosen.append(calibration.selection.chosen.candidate)
        shown = f" ({', '.join(values)})" if values else ""
        print(
            f"| {robot} | {rows} | {left}{shown} | {left / rows:.1%} | {', '.join(chosen)} | "
            f"{time.perf_counter() - start:.0f} |",
            flush=True,
        )


if __name__ == "__main__":
    bench(tuple(int(s) for s in sys.argv[1].split(",")) if len(sys.argv) > 1 else (0, 1))
