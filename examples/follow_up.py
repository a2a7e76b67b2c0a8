"""A follow-up session: after a first session is recorded, which postures to record next.

``select --given`` in Python: the example pool, a first session of 40 postures (simulated
here: a perturbed TALOS touching the table), its calibration, then the 10 postures of
the pool that best improve the chain that calibration predicts worst.

    python examples/follow_up.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from posegen.calibrate import Settings, calibrate_files, simulate_postures_file
from posegen.resources import shipped_path
from posegen.select import SelectionSettings, follow_up_pool_file, select_pool_file

EXAMPLE_POOL = "plans/talos/pool.yaml"  # shipped with posegen (its copy is read outside the checkout)


def main(output: Path) -> None:
    """Record (simulate) a first session, calibrate it, choose the follow-up postures."""
    output.mkdir(parents=True, exist_ok=True)
    pool = str(shipped_path(EXAMPLE_POOL))  # 200 feasible postures of TALOS at its table
    start = time.perf_counter()

    first = output / "first.yaml"
    select_pool_file(pool, str(first), SelectionSettings(k=40))
    measured = output / "day1.yaml"
    robot = {"seed": 3, "error_mm": 2.0, "error_deg": 0.5, "noise_deg": 0.005}
    simulate_postures_file(str(first), str(measured), config_path=None, session="day1", **robot)
    settings = Settings(candidates=("offsets",), prior_scale=5.0, fold_seeds=1)
    calibrate_files([str(measured)], [], str(output / "calibration"), settings, None)

    following = follow_up_pool_file(
        pool, str(output / "next.yaml"), [str(measured)], str(output / "calibration" / "calibration.yaml"), k=10
    ).figures
    chain = following.weakest_chain
    before, after = following.predicted_height_sigma_mm[chain]
    print(
        f"follow-up: {following.selected} postures for the {chain} chain, the weakest "
        f"(predicted height sigma {before:.2f} -> {after:.2f} mm) -> {output / 'next.yaml'}"
    )
    print(f"follow_up: {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", nargs="?", type=Path, default=Path("plans/example_follow_up"))
    main(parser.parse_args().output)
