"""Calibrate a real TALOS from its recorded contacts (CSV), then load the result in pinocchio.

The recordings (``left_train.csv``, ``right_train.csv``, ``left_validation.csv``) are read
from the folder given, else ``$POSEGEN_REAL_DATA``, else ``shared/data/talos_real`` beside
the working folder or this script (in a parent folder); without them the script says so
and stops (exit 0).

What a controller loads (see the docs, "Deploying a calibration"):

* ``calibrated.urdf``: the URDF alone, for any stack;
* ``with_compliance/``: when a compliant model predicts best, its URDF plus
  ``compliance.yaml``, by which the encoder angles are corrected before the URDF is used
  (:func:`posegen.calibrate.compensate`);
* ``offsets.yaml``: the same URDF as per-joint offsets of the nominal one.

    python examples/calibrate_recorded.py [DATA_FOLDER] [-o OUTPUT] [--candidates NAME ...]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

from posegen.calibrate import (
    Settings,
    calibrate_files,
    compensate,
    file_lines,
    format_table,
    load_line,
    read_compliance,
)
from posegen.resources import DEFAULT_CONFIG, shipped_path
from posegen.robot import Scene, load_config

FILES = ("left_train.csv", "right_train.csv", "left_validation.csv")


def find_data(given: Path | None) -> Path | None:
    """The folder holding the recordings, or None."""
    if given or os.environ.get("POSEGEN_REAL_DATA"):
        places = [given or Path(os.environ["POSEGEN_REAL_DATA"])]
    else:
        starts = (Path.cwd(), Path(__file__).resolve().parent)
        places = [p / "shared" / "data" / "talos_real" for start in starts for p in (start, *start.parents)]
    return next((p for p in places if all((p / f).is_file() for f in FILES)), None)


def hand_offsets_mm(nominal: pin.Model, calibrated: pin.Model, frames: list[str], q: np.ndarray) -> list[float]:
    """How far each frame moved (mm) between the two models, at the same joint angles ``q``."""
    out = []
    for model in (nominal, calibrated):
        data = model.createData()
        pin.framesForwardKinematics(model, data, q)
        out.append([data.oMf[model.getFrameId(f)].translation.copy() for f in frames])
    return [1e3 * float(np.linalg.norm(a - b)) for a, b in zip(*out, strict=True)]


def main(data: Path, output: Path, candidates: tuple[str, ...]) -> None:
    """Calibrate from the CSVs into ``output``; load what it wrote."""
    config = str(shipped_path(DEFAULT_CONFIG))
    start = time.perf_counter()
    settings = Settings(candidates=candidates, fold_seeds=1)
    train = [str(data / "left_train.csv"), str(data / "right_train.csv")]
    calibrated = calibrate_files(train, [str(data / "left_validation.csv")], str(output), settings, config)
    print("\n".join(file_lines(calibrated.summary)))  # each file written: predicted and held-out error
    print(format_table(calibrated.summary))
    print(load_line(calibrated.summary))
    print(f"calibrate: {time.perf_counter() - start:.0f} s -> {output}/")

    # 1. The URDF alone: any stack loads it. Here pinocchio, beside the nominal URDF.
    scene = Scene(load_config(config))
    nominal = pin.buildModelFromUrdf(str(scene.files.urdf))
    urdf = pin.buildModelFromUrdf(str(output / "calibrated.urdf"))
    q = pin.neutral(urdf)
    hands = [chain.gripper_frame for chain in scene.config.chains]
    moved = hand_offsets_mm(nominal, urdf, hands, q)
    print("calibrated.urdf: " + ", ".join(f"{f} moved {d:.1f} mm" for f, d in zip(hands, moved, strict=True)))

    # 2. With compliance (only when a compliant model predicted best): correct the encoders first.
    compliant = output / "with_compliance"
    if (compliant / "compliance.yaml").is_file():
        compliance = read_compliance(compliant / "compliance.yaml")
        encoders = scene.reference.copy()  # (nj,) rad, in scene.joint_names order: a standing posture
        joints = compensate(scene, encoders, compliance)[0]  # the angles the joints really have
        print(f"with_compliance/: encoders corrected by up to {np.degrees(np.abs(joints - encoders).max()):.3f} deg")
        pin.buildModelFromUrdf(str(compliant / "calibrated.urdf"))
    else:
        print("with_compliance/: not written (no compliant model beat the URDF alone)")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", type=Path, default=None, help="folder of the recorded CSV files")
    parser.add_argument("-o", "--output", type=Path, default=Path("plans/example_real"))
    parser.add_argument("--candidates", nargs="+", default=[], help="candidate models (default: the config's all)")
    arguments = parser.parse_args()
    found = find_data(arguments.data)
    if found is None:
        print(f"no recorded TALOS data ({', '.join(FILES)}) found: set POSEGEN_REAL_DATA to its folder; skipping")
    else:
        main(found, arguments.output, tuple(arguments.candidates))
