"""The whole pipeline in one script, on small sizes: pool -> select -> route -> check -> robot -> calibrate.

Only the public API (``import posegen``). The robot is simulated: a TALOS with perturbed
kinematics "records" the session. With ``posegen[ros]`` installed it runs the route as a
rosbag2 (export, simulate the recording, measure the contacts back); without it, it touches
the table at the selected postures directly. Everything goes to the folder given (default
``plans/example``).

    python examples/pipeline.py [OUTPUT_FOLDER] [--workers N]
"""

from __future__ import annotations

import argparse
import importlib.util
import time
from pathlib import Path

import posegen
from posegen.resources import DEFAULT_CONFIG, shipped_path

ROBOT = posegen.SimulatedRobot(seed=7, error_mm=2.0, error_deg=0.5, noise_deg=0.005)  # its errors (sigmas)


def main(output: Path, workers: int) -> None:
    """Run every stage into ``output``; print what each produced."""
    output.mkdir(parents=True, exist_ok=True)
    config = shipped_path(DEFAULT_CONFIG)  # TALOS at its table (the packaged copy outside the checkout)
    start = time.perf_counter()

    def lap() -> str:
        return f"{time.perf_counter() - start:.0f} s"

    pool = posegen.generate_pool(config, output / "pool.yaml", n=100, seed=1, workers=workers)
    print(f"pool: {len(pool.postures)} feasible postures ({lap()})")

    settings = posegen.SelectionSettings(k=38)
    selected = posegen.select_postures(output / "pool.yaml", output / "selected.yaml", settings=settings)
    print(f"select: {len(selected.postures)} postures ({lap()})")

    posegen.plan_route(output / "selected.yaml", output / "route.yaml", seed=0, workers=workers)
    checked = posegen.check_route(output / "route.yaml")
    print(f"route: {checked.checked} points re-checked, {'no violation' if checked.ok else 'VIOLATIONS'} ({lap()})")

    measured = output / "measured.yaml"
    if importlib.util.find_spec("rosbags") is not None:  # posegen[ros]: the route as the robot would run it
        posegen.export_route(
            output / "route.yaml", output / "route_bag", topic="/trajectory", segments_topic="/segments"
        )
        posegen.simulate_recording(output / "route.yaml", output / "session", robot=ROBOT, rate_hz=100.0)
        posegen.measure(output / "session", measured, route=output / "route.yaml", config=config, session="sim")
        print(f"robot: route exported as a rosbag2, recorded by a simulated TALOS, contacts measured ({lap()})")
    else:
        posegen.simulate(output / "selected.yaml", measured, robot=ROBOT)
        print("robot: contacts of a simulated TALOS at the selected postures (pip install 'posegen[ros]' for bags)")

    held_out = output / "held_out.yaml"  # the same robot at the pool's other postures judges the result
    posegen.simulate(output / "pool.yaml", held_out, robot=ROBOT, session="check")
    settings = posegen.CalibrationSettings(candidates=("offsets",), prior_scale=5.0, fold_seeds=1)
    summary = posegen.calibrate_robot([measured], output / "calibration", held_out=[held_out], settings=settings)
    print(posegen.describe_calibration(summary))
    print(f"pipeline: {lap()} -> {output}/")


if __name__ == "__main__":  # worker processes import this script again: keep the work under the guard
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", nargs="?", type=Path, default=Path("plans/example"))
    parser.add_argument("--workers", type=int, default=1)
    arguments = parser.parse_args()
    main(arguments.output, arguments.workers)
