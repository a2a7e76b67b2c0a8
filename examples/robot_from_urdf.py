"""A new robot: draft its config from its URDF (and SRDF), load it, compare it with a tuned one.

``posegen robot init`` in Python. The robot here is example-robot-data's TALOS (its URDF
and SRDF ship with that package): the draft finds its legs, soles, arms, contact frames,
joints to lock, a table within reach and the collision pairs to disable, and is re-read
as a scene before it is written. A draft is a start: edit the lines marked EDIT (the
shipped ``configs/talos_table.yaml`` is TALOS's tuned one), then ``posegen pool --config``.

    python examples/robot_from_urdf.py [OUTPUT_FOLDER] [--robot NAME]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from posegen.draft import write_draft
from posegen.resources import DEFAULT_CONFIG, shipped_path
from posegen.robot import Scene, load_config


def main(output: Path, robot: str) -> None:
    """Draft ``robot``'s config into ``output``, load it as a scene, compare it with the shipped TALOS config."""
    output.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    config_path = output / f"{robot}_table.yaml"
    draft = write_draft(robot, str(config_path), samples=400)  # random postures to find the collision pairs to disable
    for note in draft.notes:
        print(f"note: {note}")

    scene = Scene(load_config(config_path))
    print(f"URDF: {scene.files.urdf}")
    print(f"SRDF: {scene.files.srdf}")
    left, right = draft.chains
    soles = ", ".join(sole.frame for sole in draft.soles)
    print(f"draft: soles {soles}; hands {left.hand}, {right.hand}; table at {draft.table_center_m} m")

    # What a person tunes next: compare with the shipped, hand-tuned config of the same robot.
    shipped = load_config(shipped_path(DEFAULT_CONFIG))
    print(f"shipped config: table at {shipped.table.top_center_m} m; drafted: {scene.config.table.top_center_m} m")
    for drafted, tuned in zip(scene.config.chains, shipped.chains, strict=False):
        print(f"  chain {drafted.name}: drafted gripper {drafted.gripper_frame}, shipped {tuned.gripper_frame}")
    print(f"robot_from_urdf: {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", nargs="?", type=Path, default=Path("plans/example_robot"))
    parser.add_argument("--robot", default="talos", help="example-robot-data name (default talos)")
    arguments = parser.parse_args()
    main(arguments.output, arguments.robot)
