"""End to end without a robot: select -> route -> export --bag -> simulate --bag -> measure -> calibrate.

One arm of the example pool (itself made by ``posegen pool``), 30 selected postures: the
fewest that identify every base parameter of one chain. The simulated robot must be
recovered: the held-out error on the pool's other postures of that arm at least 10x
smaller than the nominal model's, and consistent with the calibration's posterior: the
held-out residuals, over their predicted sigma, like draws of a unit Gaussian.
"""

import contextlib
import io
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

from posegen.calibrate import Noise, Settings, calibrate, held_out_residuals, posterior_of
from posegen.calibrate.estimation import frozen_jacobian
from posegen.cli import main
from posegen.io import JointStates, RecordedBag, Wrenches, read_route, write_recording, write_yaml
from posegen.model import read_measurements
from tests.cli.test_cli import assert_fails_cleanly

pytestmark = pytest.mark.slow  # one simulated session through rosbag2, 1.5 min: `make slow`, a step of .ci/run

CHAIN = "left"
K = 30
SEED = 7
ENCODER_NOISE_DEG = 0.005  # sigma of each encoder reading of the held-out contacts
SHORT = 3  # contacts of the short route


@pytest.fixture(scope="module")
def chain(example_pool, tmp_path_factory):
    """Every step's output, made once; and a short route (its first contacts) for the cheap tests."""
    folder = tmp_path_factory.mktemp("session")
    data = example_pool.to_dict()
    data["postures"] = [p for p in data["postures"] if p["chain"] == CHAIN]
    write_yaml(folder / "pool.yaml", data)
    route, bag = str(folder / "route.yaml"), str(folder / "bag")
    steps = {
        "select": ["select", str(folder / "pool.yaml"), "--k", str(K), "-q", "-o", str(folder / "selected.yaml")],
        "route": ["route", str(folder / "selected.yaml"), "-q", "-o", route],
        "simulate": ["simulate", route, "--bag", bag, "--seed", str(SEED)],
        "measure": ["measure", bag, "--route", route, "--session", "sim", "-o", str(folder / "measurements.yaml")],
    }
    printed = {}
    for name, argv in steps.items():
        code, out, err = run_plain(argv)
        assert code == 0, (name, err)
        printed[name] = out
    selected = {tuple(p["joints"]) for p in yaml.safe_load((folder / "selected.yaml").read_text())["postures"]}
    data["postures"] = [p for p in data["postures"] if tuple(p["joints"]) not in selected]
    write_yaml(folder / "others.yaml", data)
    code, _, err = run_plain(
        [
            "simulate",
            str(folder / "others.yaml"),
            "--seed",
            str(SEED),
            "--noise-deg",
            str(ENCODER_NOISE_DEG),
            "-o",
            str(folder / "held.yaml"),
        ]
    )
    assert code == 0, err
    short = first_contacts(route, SHORT)
    write_yaml(folder / "short.yaml", short)
    code, _, err = run_plain(
        ["simulate", str(folder / "short.yaml"), "--bag", str(folder / "short_bag"), "--seed", "3"]
    )
    assert code == 0, err
    return folder, printed


def first_contacts(route, contacts):
    """A route cut after its first contacts (format version 1: points inline)."""
    read = read_route(route)
    times, positions, velocities, accelerations = read.times, read.positions, read.velocities, read.accelerations
    data = yaml.safe_load(Path(route).read_text())
    last = [i for i, seg in enumerate(data["segments"]) if seg["type"] == "release"][contacts - 1]
    end = data["segments"][last]["last_point"]
    points = [
        {
            "positions": positions[k].tolist(),
            "velocities": velocities[k].tolist(),
            "accelerations": accelerations[k].tolist(),
            "effort": [],
            "time_from_start": dict(zip(("sec", "nanosec"), divmod(round(times[k] * 1e9), 10**9), strict=True)),
        }
        for k in range(end + 1)
    ]
    trajectory = {"header": data["trajectory"]["header"], "joint_names": data["trajectory"]["joint_names"]}
    keep = ("format", "provenance", "postures", "skipped", "summary")
    return {
        **{key: data[key] for key in keep},
        "format_version": 1,
        "trajectory": {**trajectory, "points": points},
        "segments": data["segments"][: last + 1],
    }


def run_plain(argv):
    """Run a command outside a test function (capsys is per test); return code, stdout, stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def test_every_routed_contact_is_measured(chain):
    folder, printed = chain
    assert f"measure: {K} contacts" in printed["measure"]
    data = yaml.safe_load((folder / "measurements.yaml").read_text())
    ends = [c["end_s"] for c in data["contacts"]]
    for window in data["rejected"]:  # a hold's tail as the release starts, not a contact lost
        assert window["reason"].startswith("too short") and min(abs(window["start_s"] - e) for e in ends) < 0.1
    assert f"{len(data['rejected'])} windows left out" in printed["measure"]
    recording = data["provenance"]["recording"]
    assert recording["bag_sha256"] == RecordedBag(folder / "bag").sha256()
    assert recording["topics"] == {
        "joint_states": "/joint_states",
        "wrenches": {"left": "/left_wrist_ft", "right": "/right_wrist_ft"},
    }
    assert recording["thresholds"]["force_threshold_n"] == 15.0 and recording["route"].endswith("route.yaml")
    assert {c["chain"] for c in data["contacts"]} == {CHAIN}
    labels = [c["label"] for c in data["contacts"]]
    assert len(set(labels)) == K and all("posture" in label for label in labels)


def test_the_simulated_robot_is_recovered(chain, scene):
    folder, _ = chain
    train = read_measurements(folder / "measurements.yaml", scene).contacts
    held = read_measurements(folder / "held.yaml", scene).contacts
    calibration = calibrate(scene, train, ["sim"], Settings(candidates=("full",), fold_seeds=1))
    residuals = held_out_residuals(calibration, held)["training_plane"]
    before = np.abs(residuals["before"]).mean(axis=0)  # m, rad, rad
    after = np.abs(residuals["after"]).mean(axis=0)
    assert len(held) >= 40 and np.all(before >= 10 * after), (before, after)  # 49 held-out contacts of the arm

    # Consistent with the posterior: each held-out residual over its predicted sigma: the
    # posterior's spread through the contact's Jacobian, and the held-out recording's own
    # noise. The held-out contacts are single encoder readings (``simulate`` of a pool), the
    # training ones the mean of a hold's readings: the calibration's noise (the training
    # residuals') is not theirs. Theirs is the encoder noise through the joints' Jacobian.
    model = calibration.model
    unit = Noise((1.0, 1.0, 1.0), (1.0,) * 6)  # the raw Jacobian
    observations = model.observations(held)
    jacobian, _ = frozen_jacobian(model, observations, calibration.spec, unit, calibration.after.x)
    covariance = posterior_of(calibration).covariance
    spread = np.einsum("nmf,fg,nmg->nm", jacobian, covariance, jacobian)  # (n, 3)
    x = calibration.after.x
    bent = held.at(model.deflected(x, observations))
    _, _, d_joints = model.contact.derivatives(model.theta(x), bent)  # (n, 3, nj)
    encoder = np.deg2rad(ENCODER_NOISE_DEG) ** 2 * np.einsum("nmj,nmj->nm", d_joints, d_joints)  # (n, 3)
    z = residuals["after"] / np.sqrt(spread + encoder)
    assert np.mean(z**2) < 3.0 and np.abs(z).max() < 6.0, (np.mean(z**2), np.abs(z).max())


def test_export_writes_every_segment(chain, tmp_path):
    folder, _ = chain
    code, printed, err = run_plain(["export", str(folder / "short.yaml"), "--bag", str(tmp_path / "route_bag")])
    assert code == 0, err
    assert f"in {5 * SHORT} segments" in printed
    bag = RecordedBag(tmp_path / "route_bag")
    assert bag.topics == {
        "/joint_trajectory_controller/joint_trajectory": "trajectory_msgs/msg/JointTrajectory",
        "/posegen/segments": "diagnostic_msgs/msg/DiagnosticArray",
    }


def test_simulation_is_deterministic(chain, tmp_path):
    folder, _ = chain
    again = tmp_path / "short_bag"  # same name, another folder
    code, _, err = run_plain(["simulate", str(folder / "short.yaml"), "--bag", str(again), "--seed", "3"])
    assert code == 0, err
    for name in ("metadata.yaml", "short_bag.mcap"):
        assert (again / name).read_bytes() == (folder / "short_bag" / name).read_bytes(), name


def _rewritten(folder, tmp_path, name, joints=None, wrenches=True):
    """The short simulated bag written again with its joint states (or wrenches) changed."""
    bag = RecordedBag(folder / "short_bag")
    recorded, forces = bag.read("/joint_states", ["/left_wrist_ft", "/right_wrist_ft"])
    series = {"/left_wrist_ft": forces[0], "/right_wrist_ft": forces[1]} if wrenches else {}
    if wrenches == "idle":
        series = {t: Wrenches(w.times_s, np.zeros_like(w.forces), w.torques) for t, w in series.items()}
    write_recording(tmp_path / name, joints or recorded, "/joint_states", series, {})
    return recorded


def test_any_joint_order_and_no_wrench_topic(chain, tmp_path):
    folder, _ = chain
    route = str(folder / "short.yaml")
    out = tmp_path / "reference.yaml"
    code, _, err = run_plain(["measure", str(folder / "short_bag"), "--route", route, "-o", str(out)])
    assert code == 0, err
    reference = yaml.safe_load(out.read_text())["contacts"]
    assert len(reference) == SHORT
    recorded = RecordedBag(folder / "short_bag").read("/joint_states")[0]
    order = np.argsort(recorded.names)  # alphabetical, as many drivers publish
    shuffled = JointStates(tuple(np.array(recorded.names)[order]), recorded.times_s, recorded.positions[:, order])
    _rewritten(folder, tmp_path, "shuffled", joints=shuffled)
    code, _, err = run_plain(["measure", str(tmp_path / "shuffled"), "--route", route, "-o", str(out)])
    assert code == 0, err
    contacts = yaml.safe_load(out.read_text())["contacts"]
    assert np.array_equal([c["joints"] for c in contacts], [c["joints"] for c in reference])

    _rewritten(folder, tmp_path, "no_wrench", wrenches=False)
    argv = ["measure", str(tmp_path / "no_wrench"), "--route", route, "--no-wrench", "-o", str(out)]
    code, printed, err = run_plain(argv)
    assert code == 0 and "joint speed and the route" in printed, err
    contacts = yaml.safe_load(out.read_text())["contacts"]
    assert [c["chain"] for c in contacts] == [c["chain"] for c in reference]
    assert [c["label"].split(":")[1].split("@")[0] for c in contacts] == [
        c["label"].split(":")[1].split("@")[0] for c in reference
    ]
    assert np.abs(np.array([c["joints"] for c in contacts]) - [c["joints"] for c in reference]).max() < 1e-4  # rad


def test_bad_bags_fail_cleanly(chain, tmp_path, capsys):
    folder, _ = chain
    out = tmp_path / "m.yaml"
    short = folder / "short_bag"

    def measure(bag, *extra):
        return assert_fails_cleanly(["measure", str(bag), "-o", str(out), *extra], out, capsys)

    assert "not a rosbag2 directory" in measure(folder / "short.yaml")
    assert "no topic '/nope'" in measure(short, "--joint-topic", "/nope")
    assert "holds geometry_msgs/msg/WrenchStamped, expected sensor_msgs/msg/JointState" in measure(
        short, "--joint-topic", "/left_wrist_ft"
    )
    code, _, err = run_plain(["export", str(folder / "short.yaml"), "--bag", str(tmp_path / "route_bag")])
    assert code == 0, err
    assert "no topic '/joint_states'; its topics: /joint_trajectory_controller" in measure(tmp_path / "route_bag")

    broken = tmp_path / "broken"
    shutil.copytree(short, broken)
    meta = broken / "metadata.yaml"
    meta.write_text(meta.read_text().replace("storage_identifier: mcap", "storage_identifier: rosbag_v3"))
    assert "unknown storage plugin 'rosbag_v3'; valid: mcap, sqlite3" in measure(broken)
    meta.write_text(meta.read_text().replace("storage_identifier: rosbag_v3", "storage_identifier: mcap"))
    storage = broken / "short_bag.mcap"
    storage.write_bytes(storage.read_bytes()[: storage.stat().st_size * 2 // 3])
    assert "truncated MCAP file" in measure(broken)

    _rewritten(folder, tmp_path, "idle", wrenches="idle")
    assert "no contact window found (0 rejected; the joints still in " in measure(tmp_path / "idle")

    recorded = RecordedBag(short).read("/joint_states")[0]
    shifted = recorded.positions.copy()
    shifted[:, recorded.names.index("arm_left_4_joint")] += 3.0  # a wrong encoder offset
    _rewritten(folder, tmp_path, "shifted", joints=JointStates(recorded.names, recorded.times_s, shifted))
    assert "arm_left_4_joint outside its limits" in measure(tmp_path / "shifted")
    renamed = JointStates(("elbow_joint", *recorded.names[1:]), recorded.times_s, recorded.positions)
    _rewritten(folder, tmp_path, "renamed", joints=renamed)
    err = measure(tmp_path / "renamed")
    assert "unknown joint 'elbow_joint'; valid joints: " in err and "arm_left_1_joint" in err

    assert "--route is needed" in assert_fails_cleanly(
        ["measure", str(short), "--no-wrench", "-o", str(out)], out, capsys
    )
    bag = tmp_path / "bag_out"
    assert "route" in assert_fails_cleanly(["simulate", str(folder / "selected.yaml"), "--bag", str(bag)], bag, capsys)
