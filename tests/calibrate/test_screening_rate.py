"""Screening at its stated rate: noise-only simulations of every shipped robot lose at most 2 % of their rows.

Each shipped robot's standing postures (``tests/data/standing/``) are recorded by a robot with
the default errors of ``posegen simulate`` (2 mm, 0.5 deg) and encoder noise, with no row
corrupted. Screened as ``calibrate`` screens them before any model is chosen (the feet, then
the robust fit of the config's first candidate at the middle prior scale), at most 2 % of the
rows may be left out. The whole ``calibrate`` (screened again with the model cross-validation
chooses) on more seeds is ``benchmarks/screening_bench.py``.
"""

import numpy as np
import pytest

from posegen.calibrate import Noise, Perturbation, simulate
from posegen.calibrate.calibration import unusable_rows
from posegen.calibrate.estimation import held_at_urdf
from posegen.calibrate.screening import Screening
from posegen.model import (
    DEFAULT_FLOOR_NOISE,
    DEFAULT_NOISE,
    CalibrationModel,
    candidate_spec,
    spec_for_rows,
    start_point,
)
from tests.calibrate.standing_postures import ROBOTS, load_standing

NOISE_ONLY = Perturbation(encoder_noise_rad=float(np.deg2rad(0.005)))  # posegen simulate's defaults
SEEDS = (0, 1)
MAX_SHARE = 0.02


def rows_left_out(robot: str, seed: int) -> tuple[int, int]:
    """Rows a noise-only simulation of ``robot`` loses to calibrate's first screening, and rows recorded."""
    scene, planned = load_standing(robot)
    recorded, _, _ = simulate(scene, planned, NOISE_ONLY, seed)
    config = scene.calibration
    model = CalibrationModel(scene, sorted(set(recorded.chains)), ["sim"], config.compliance, recorded.kinds_by_chain())
    observations = model.observations(recorded)
    left_out = {f.row for f in unusable_rows(model, observations, config)}
    usable = [i for i in range(len(recorded)) if i not in left_out]
    middle = sorted(config.prior_scales)[len(config.prior_scales) // 2]
    spec = spec_for_rows(model, candidate_spec(model, config.candidates[0], config.prior, middle), {"sim"})
    start = held_at_urdf(model, spec, start_point(model, observations.subset(usable)))
    screen = Screening(model, observations, recorded.labels, usable, config, drop=True)
    screen.run(spec, Noise(DEFAULT_NOISE, DEFAULT_FLOOR_NOISE), start)
    return len(left_out | {f.row for f in screen.flags}), len(recorded)


@pytest.mark.parametrize("robot", ROBOTS)
def test_noise_only_simulations_lose_at_most_two_percent_of_their_rows(robot):
    counts = [rows_left_out(robot, seed) for seed in SEEDS]
    left_out, rows = (sum(c) for c in zip(*counts, strict=True))
    assert rows >= 0.98 * len(SEEDS) * 60  # the rehearsal kept its postures
    assert left_out <= MAX_SHARE * rows, f"{robot}: {left_out} of {rows} rows left out"
