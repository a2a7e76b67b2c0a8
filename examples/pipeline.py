"""The whole pipeline in one script, on small sizes: pool -> select -> route -> check -> robot -> calibrate.

The robot is simulated: a TALOS with perturbed kinematics "records" the session. With
``posegen[ros]`` installed it runs the route as a rosbag2 (export, simulate the recording,
measure the contacts back); without it, it touches the table at the selected postures
directly. Everything goes to the folder given (default ``plans/example``).

    python examples/pipeline.py [OUTPUT_FOLDER] [--workers N]
"""

from __future__ import annotations

import argparse
import importlib.util
import time
from pathlib import Path

from posegen.calibrate import (
    Settings,
    calibrate_files,
    format_table,
    load_line,
    measure_bag,
    simulate_postures_file,
    simulate_route_bag,
)
from posegen.pool import generate_pool_file
from posegen.resources import DEFAULT_CONFIG, shipped_path
from posegen.route import check_route_file, export_route_bag, route_postures_file
from posegen.select import SelectionSettings, select_pool_file

SIMULATED_ROBOT = {"seed": 7, "error_mm": 2.0, "error_deg": 0.5, "noise_deg": 0.005}  # its errors (sigmas)


def main(output: Path, workers: int) -> None:
    """Run every stage into ``output``; print what each produced."""
    output.mkdir(parents=True, exist_ok=True)
    config = str(shipped_path(DEFAULT_CONFIG))  # TALOS at its table (the packaged copy outside the checkout)
    start = time.perf_counter()

    def lap() -> str:
        return f"{time.perf_counter() - start:.0f} s"

    pool = generate_pool_file(config, str(output / "pool.yaml"), n=100, seed=1, workers=workers)
    print(f"pool: {len(pool.postures)} feasible postures ({lap()})")

    selected = select_pool_file(str(output / "pool.yaml"), str(output / "selected.yaml"), SelectionSettings(k=38))
    print(f"select: {len(selected.postures)} postures ({lap()})")

    route_postures_file(str(output / "selected.yaml"), str(output / "route.yaml"), seed=0, workers=workers)
    checked = check_route_file(str(output / "route.yaml"), None)
    print(f"route: {checked.checked} points re-checked, {'no violation' if checked.ok else 'VIOLATIONS'} ({lap()})")

    measured = output / "measured.yaml"
    if importlib.util.find_spec("rosbags") is not None:  # posegen[ros]: the route as the robot would run it
        export_route_bag(str(output / "route.yaml"), str(output / "route_bag"), "/trajectory", "/segments")
        simulate_route_bag(
            str(output / "route.yaml"), str(output / "session"), config_path=None, session="sim",
            rate_hz=100.0, joint_topic="/joint_states", **SIMULATED_ROBOT,
        )  # fmt: skip
        measure_bag(
            str(output / "session"), str(measured), config_path=config, route_path=str(output / "route.yaml"),
            session="sim", joint_topic="/joint_states", use_wrench=True,
        )  # fmt: skip
        print(f"robot: route exported as a rosbag2, recorded by a simulated TALOS, contacts measured ({lap()})")
    else:
        selected_path = str(output / "selected.yaml")
        simulate_postures_file(selected_path, str(measured), config_path=None, session="sim", **SIMULATED_ROBOT)
        print("robot: contacts of a simulated TALOS at the selected postures (pip install 'posegen[ros]' for bags)")

    held_out = output / "held_out.yaml"  # the same robot at the pool's other postures judges the result
    pool_file = str(output / "pool.yaml")
    simulate_postures_file(pool_file, str(held_out), config_path=None, session="check", **SIMULATED_ROBOT)
    settings = Settings(candidates=("offsets",), prior_scale=5.0, fold_seeds=1)
    calibrated = calibrate_files([str(measured)], [str(held_out)], str(output / "calibration"), settings, None)
    print(format_table(calibrated.summary))
    print(load_line(calibrated.summary))
    print(f"pipeline: {lap()} -> {output}/")


if __name__ == "__main__":  # worker processes import this script again: keep the work under the guard
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", nargs="?", type=Path, default=Path("plans/example"))
    parser.add_argument("--workers", type=int, default=1)
    arguments = parser.parse_args()
    main(arguments.output, arguments.workers)
