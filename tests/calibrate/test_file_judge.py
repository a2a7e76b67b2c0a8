"""One number for one thing: each file's held-out error, printed, written and reported, is the written files' own.

``posegen calibrate`` judges every file it writes as a stack loading it sees it
(:mod:`posegen.calibrate.file_judge`). Here an independent re-evaluation reads the files
back (pinocchio's forward kinematics of the written URDF; ``compensate`` with the written
``compliance.yaml``), fits the table planes and contact tilts by scipy's least squares,
and must find, per deliverable and chain, the figure the command printed, wrote in
``calibration.yaml`` and showed in ``report.html``, to 1e-6 (mm, deg).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import scipy.optimize
import yaml

from posegen.calibrate import Perturbation, compensate, read_compliance, read_summary, simulate
from posegen.cli.main import main
from posegen.model import Contacts, read_measurements, write_measurements
from posegen.robot import Scene, load_config

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "talos_table.yaml"
SHOWN = np.array([1e3, 180.0 / np.pi, 180.0 / np.pi])  # m, rad -> mm, deg
UNITS = np.array([1e-3, np.deg2rad(0.1), np.deg2rad(0.1)])  # how the protocol weighs a contact's residual


@pytest.fixture(scope="module")
def calibrated(scene, example_pool, tmp_path_factory):
    """A compliant TALOS: 60 training contacts (one table session), 20 held out (another), calibrated from the CLI."""
    folder = tmp_path_factory.mktemp("judged")
    rows = list(range(80))
    plan = Contacts(
        example_pool.joints()[rows],
        tuple(example_pool.postures[i].chain for i in rows),
        ("train",) * 60 + ("held",) * 20,
        tuple(example_pool.postures[i].spot for i in rows),
    )
    perturbation = Perturbation(encoder_noise_rad=np.deg2rad(0.01), compliance_rad_per_nm=3e-4)
    recorded, _, _ = simulate(scene, plan, perturbation, seed=11)
    train = recorded.subset([i for i, s in enumerate(recorded.sessions) if s == "train"])
    held = recorded.subset([i for i, s in enumerate(recorded.sessions) if s == "held"])
    write_measurements(folder / "train.yaml", scene, train, scene.provenance(11))
    write_measurements(folder / "held.yaml", scene, held, scene.provenance(11))
    return folder


@pytest.fixture(scope="module")
def printed(calibrated, scene):
    """What ``posegen calibrate`` printed, and the folder it wrote."""
    import contextlib
    import io

    out = calibrated / "calibration"
    argv = ["calibrate", str(calibrated / "train.yaml"), "--validate", str(calibrated / "held.yaml")]
    options = ["--candidates", "offsets", "offsets_hip_pitch", "--prior-scale", "10", "--fold-seeds", "1"]
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        assert main([*argv, *options, "--workers", "1", "-q", "-o", str(out)]) == 0
    return stdout.getvalue(), out


def independent(folder: Path, kind: str, train: Contacts, kept: list[int], held: Contacts) -> dict[str, np.ndarray]:
    """Each chain's held-out mean absolute error (mm, deg) of a deliverable, from its written files alone."""
    config = folder / "calibrated.yaml"
    if kind == "compensated":  # the same frames, its own URDF
        own = folder / "with_compliance" / "calibrated.urdf"
        text = config.read_text().replace("urdf: calibrated.urdf", f"urdf: {own}")
        config = folder / "compensated.yaml"
        config.write_text(text)
    robot = Scene(load_config(config))
    joints = np.vstack([train.joints, held.joints])
    if kind == "compensated":
        joints = compensate(robot, joints, read_compliance(folder / "with_compliance" / "compliance.yaml"))
    data = robot.model.createData()
    chains = [*train.chains, *held.chains]
    frames = []
    for q, chain in zip(joints, chains, strict=True):
        pin.framesForwardKinematics(robot.model, data, robot.configuration(q))
        config_chain = robot.config.chain(chain)
        sole, contact = (data.oMf[robot.frame_id(f)] for f in (config_chain.sole_frame, config_chain.contact_frame))
        frames.append(sole.actInv(contact).homogeneous)
    frames = np.array(frames)
    names = sorted(set(chains))

    def offset(z: float, roll: float, pitch: float) -> np.ndarray:
        out = np.eye(4)
        out[:3, :3] = pin.rpy.rpyToMatrix(roll, pitch, 0.0)
        out[2, 3] = z
        return out

    def residuals(unknowns: np.ndarray, rows: list[int]) -> np.ndarray:
        plane = offset(*unknowns[:3])
        tilts = {c: offset(0.0, *unknowns[3 + 2 * k : 5 + 2 * k]) for k, c in enumerate(names)}
        out = []
        for i in rows:
            f = np.linalg.inv(plane) @ frames[i] @ tilts[chains[i]]
            out.append([f[2, 3], np.arctan2(f[2, 1], f[2, 2]), np.arcsin(-f[2, 0])])
        return np.array(out)

    start = np.zeros(3 + 2 * len(names))
    start[0] = frames[kept, 2, 3].mean()
    solved = scipy.optimize.least_squares(
        lambda u: (residuals(u, kept) / UNITS).ravel(), start, xtol=1e-15, ftol=1e-15, gtol=1e-15
    )
    held_rows = list(range(len(train), len(chains)))
    judged = np.abs(residuals(solved.x, held_rows)) * SHOWN  # the held-out session takes the training plane
    return {c: judged[[k for k, i in enumerate(held_rows) if chains[i] == c]].mean(axis=0) for c in set(held.chains)}


@pytest.mark.parametrize("kind", ["urdf", "compensated"])
def test_each_file_s_held_out_error_is_its_written_files_own(printed, calibrated, scene, kind):
    stdout, out = printed
    summary = read_summary(out / "calibration.yaml")
    assert {k.value for k in summary.deliverables} == {"urdf", "compensated"}  # both files written
    train = read_measurements(calibrated / "train.yaml", scene).contacts
    held = read_measurements(calibrated / "held.yaml", scene).contacts
    left_out = {f"{row.file}:{row.line}" for row in summary.left_out if not row.kept}
    kept = [i for i, label in enumerate(train.labels) if label.rsplit(":", 1)[0] not in left_out]
    truth = independent(out, kind, train, kept, held)
    written = yaml.safe_load((out / "calibration.yaml").read_text())["deliverables"][kind]["held_out"]
    block = stdout.split("with_compliance/ (" if kind == "compensated" else "calibrated.urdf (", 1)[1]
    line = next(ln for ln in block.splitlines() if ln.strip().startswith("held-out"))
    report = (out / "report.html").read_text()
    name = "with_compliance/calibrated.urdf" if kind == "compensated" else "calibrated.urdf, calibrated.yaml"
    for chain, expected in truth.items():
        figures = written[chain]["mean_abs"]
        assert [figures["z_mm"], figures["roll_deg"], figures["pitch_deg"]] == pytest.approx(expected, abs=1e-6)
        shown = " / ".join(f"{v:.2f}" for v in expected)
        assert f"{chain} {shown} ({written[chain]['contacts']} contacts)" in line  # printed
        rows = [r for r in re.findall(r"<tr>(.*?)</tr>", report) if name in r and f"{chain}: held-out" in r]
        assert len(rows) == 1 and f"{shown} (mm / deg / deg)" in rows[0]  # reported
