"""The loop closed in physics (issue 31, item 5): calibrate on a physics session, judge on physics held-out contacts.

Both routes are rehearsed free-standing by the same perturbed robot (one ``--seed``), each bag
measured; ``posegen calibrate SESSION --validate HELD_OUT`` fits and judges (its own figures:
each table plane fitted from the training contacts). Then each held-out contact frame's height
above the **true** table, from the recorded angles through the true robot, the nominal URDF
and the shipped ``calibrated.urdf``: the plane as ``truth.yaml`` has it (in the anchor sole's
frame, where the robot stood when the route started), carried into the other sole's frame
through the true legs at the recorded angles for the other chain. Also the contact frames'
true roll and pitch against the table (a flush contact pins them at zero).

    python benchmarks/physics_loop.py SESSION_ROUTE HELD_OUT_ROUTE --seed 8 [--workdir DIR]

Run from the repository root with the venv's ``posegen`` (2 cores: ``OPENBLAS_NUM_THREADS=1``).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import yaml

from posegen.model import ContactModel, Contacts, FloorModel, measurement_provenance, read_measurements
from posegen.physics.true_robot import plane_offsets
from posegen.robot import FloatArray, Scene, load_config, offset_matrix, scene_for

ROOT = Path(__file__).resolve().parents[1]
POSEGEN = [sys.executable, "-m", "posegen.cli"]


def run(*args: str) -> str:
    done = subprocess.run([*POSEGEN, *args], cwd=ROOT, capture_output=True, text=True, check=True)
    return done.stdout.splitlines()[0] if done.stdout else ""


def true_vector(model: ContactModel, truth: dict[str, dict[str, float]]) -> FloatArray:
    """The true contact-model parameters (p,), the measurement's session read as the truth's one."""
    session = next(k.split("@")[1].split(".")[0] for k in truth if k.startswith("plane@"))
    x = model.nominal()
    for i, p in enumerate(model.parameters):
        name = f"plane@{session}.{p.name.split('.')[-1]}" if p.name.startswith("plane@") else p.name
        x[i] = truth[name]["true"]
    return x


def planes(scene: Scene, model: ContactModel, x_true: FloatArray, contacts: Contacts) -> FloatArray:
    """(n, 3) the true plane (z m, roll, pitch rad) in each contact's own sole frame."""
    session = contacts.sessions[0]
    anchor_plane = offset_matrix(*x_true[model.plane_columns(session)])
    seconds = FloorModel(model).second_sole_frames(x_true[None], contacts.joints)[0]  # (n, 4, 4) in the anchor's
    out = np.zeros((len(contacts), 3))
    for k, chain in enumerate(contacts.chains):
        plane = anchor_plane
        if scene.chain(chain).sole_frame != scene.stance.sole_frames[0]:
            plane = np.linalg.inv(seconds[k]) @ plane  # into the second sole's frame
        out[k] = plane_offsets(plane)
    return out


def residuals(scene: Scene, chains: list[str], theta: FloatArray, contacts: Contacts, true: FloatArray) -> FloatArray:
    """(n, 3) each contact's height (m), roll and pitch (rad) above its true plane, through ``theta``."""
    model = ContactModel(scene, chains, sorted(set(contacts.sessions)))
    out = np.zeros((len(contacts), 3))
    for k in range(len(contacts)):
        values = theta.copy()
        values[model.plane_columns(contacts.sessions[k])] = true[k]
        out[k] = model.residuals(values, contacts.subset([k]))[0]
    return out


def judge(held_out: Path, truth_file: Path, calibration: Path) -> None:
    scene = scene_for(measurement_provenance(held_out), None)
    contacts = read_measurements(held_out, scene).contacts
    chains = sorted(set(contacts.chains))
    model = ContactModel(scene, chains, sorted(set(contacts.sessions)))
    truth = yaml.safe_load(truth_file.read_text())["parameters"]
    x_true = true_vector(model, truth)
    true = planes(scene, model, x_true, contacts)
    shipped = Scene(load_config(calibration / "calibrated.yaml"))
    rows = {
        "true robot": residuals(scene, chains, x_true, contacts, true),
        "nominal URDF": residuals(scene, chains, model.nominal(), contacts, true),
        "calibrated.urdf": residuals(shipped, chains, ContactModel(shipped, chains, ["x"]).nominal(), contacts, true),
    }
    names = np.array(contacts.chains)
    print("| model | chain | contacts | z RMS (mm) | z mean abs (mm) | roll, pitch mean abs (deg) |")
    print("|---|---|---|---|---|---|")
    for label, values in rows.items():
        for chain in chains:
            own = values[names == chain]
            z = 1000 * own[:, 0]
            tilt = np.degrees(np.abs(own[:, 1:]).mean(axis=0))
            print(
                f"| {label} | {chain} | {len(own)} | {np.sqrt(np.mean(z**2)):.2f} | {np.mean(np.abs(z)):.2f} "
                f"| {tilt[0]:.2f}, {tilt[1]:.2f} |"
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("session", help="the session's route")
    parser.add_argument("held_out", help="the held-out contacts' route")
    parser.add_argument("--seed", type=int, default=8)
    parser.add_argument("--workdir", default=None)
    args = parser.parse_args()
    work = Path(args.workdir or tempfile.mkdtemp(prefix="physics_loop_"))
    work.mkdir(parents=True, exist_ok=True)
    files = {}
    for name, route in (("session", args.session), ("held_out", args.held_out)):
        bag = work / f"{name}_bag"
        if not bag.exists():
            print(run("simulate", route, "--physics", "--bag", str(bag), "--seed", str(args.seed), "-q"))
        files[name] = work / f"{name}.yaml"
        print(run("measure", str(bag), "-o", str(files[name]), "-q"))
    out = work / "calibration"
    done = subprocess.run(
        [*POSEGEN, "calibrate", str(files["session"]), "--validate", str(files["held_out"]), "-o", str(out), "-q"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    print("\n".join(done.stdout.splitlines()[:8]))
    judge(files["held_out"], work / "held_out_bag" / "truth.yaml", out)


if __name__ == "__main__":
    main()
