"""The pool: invariants re-checked from raw pinocchio, determinism, resume, CLI errors."""

import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial import ConvexHull

from posegen.errors import ConfigError, InfeasibleError
from posegen.io import load_pool, pool_from_dict
from posegen.pool import generate_pool, verify_postures


def independent_invariants(scene, config, posture):
    """Measure the invariants with a fresh pinocchio model of the original URDF."""
    model = pin.buildModelFromUrdf(str(scene.files.urdf), pin.JointModelFreeFlyer())
    data = model.createData()
    q = pin.neutral(model)
    for name, value in zip(scene.joint_names, posture.joints, strict=True):
        q[model.joints[model.getJointId(name)].idx_q] = value
    left, right = config.stance.sole_frames
    pin.framesForwardKinematics(model, data, q)
    base = pin.SE3(scene.sole_poses[left]) * data.oMf[model.getFrameId(left)].inverse()
    q[:7] = pin.SE3ToXYZQUAT(base)
    pin.framesForwardKinematics(model, data, q)
    out = {}
    err = pin.SE3(scene.sole_poses[right]).actInv(data.oMf[model.getFrameId(right)])
    out["sole_m"] = np.linalg.norm(err.translation)
    out["sole_rad"] = np.linalg.norm(pin.log3(err.rotation))
    chain = config.chain(posture.chain)
    grip = data.oMf[model.getFrameId(chain.gripper_frame)]
    ends = [
        data.oMf[model.getFrameId(f)].translation - chain.fingertip_length_m * grip.rotation[:, 2]
        for f in chain.fingertip_frames
    ]
    table_z = config.table.top_center_m[2]
    out["height_m"] = max(abs(e[2] - table_z) for e in ends)
    out["tilt_rad"] = np.arccos(np.clip(grip.rotation[2, 2], -1, 1))
    com = pin.centerOfMass(model, data, q)[:2]
    corners = np.array(
        [
            (pose @ [x, y, 0, 1])[:2]
            for pose in scene.sole_poses.values()
            for x in config.stance.foot_x_m
            for y in config.stance.foot_y_m
        ]
    )
    hull = ConvexHull(corners)
    out["com_margin_m"] = -np.max(hull.equations[:, :2] @ com + hull.equations[:, 2])
    joints = np.array(posture.joints)
    lower = np.array([model.lowerPositionLimit[model.joints[model.getJointId(n)].idx_q] for n in scene.joint_names])
    upper = np.array([model.upperPositionLimit[model.joints[model.getJointId(n)].idx_q] for n in scene.joint_names])
    free = np.array([n not in config.locked_joints for n in scene.joint_names])
    out["limit_margin_rad"] = np.min(np.minimum(joints - lower, upper - joints)[free])
    return out


def test_every_posture_satisfies_the_invariants(scene, config, small_pool):
    assert len(small_pool.postures) == 24
    for posture in small_pool.postures:
        m = independent_invariants(scene, config, posture)
        assert m["sole_m"] < 1e-4 and m["sole_rad"] < 1e-3
        assert m["height_m"] < 1e-4 and m["tilt_rad"] < 1e-3
        assert m["com_margin_m"] >= config.margins.com_m
        assert m["limit_margin_rad"] >= config.margins.joint_limit_rad - 1e-9
    result = verify_postures(scene, small_pool.postures)  # meshes, not the sampler's hulls
    assert result.ok, result.worst


def test_both_chains_and_several_spots_are_used(small_pool):
    assert {p.chain for p in small_pool.postures} == {"left", "right"}
    assert len({p.spot for p in small_pool.postures}) >= 8
    assert small_pool.attempted > len(small_pool.postures)
    assert sum(small_pool.rejected.values()) == small_pool.attempted - len(small_pool.postures)


def test_same_seed_same_pool_whatever_the_workers(config, small_pool):
    parallel = generate_pool(config, n=24, seed=7, workers=2)
    assert parallel.to_dict() == small_pool.to_dict()
    other_seed = generate_pool(config, n=4, seed=8, workers=1)
    assert other_seed.postures[0].joints != small_pool.postures[0].joints


def test_resume_after_interruption(config, tmp_path):
    n = 3 * config.sampling.chunk_size  # more than two chunks accept (4 samples in 5 do)
    uninterrupted = generate_pool(config, n=n, seed=7, workers=2)
    checkpoint = tmp_path / "pool.yaml.partial.jsonl"
    calls = []

    def interrupt(progress):
        calls.append(progress.attempts)
        if progress.attempts >= 2 * config.sampling.chunk_size:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        generate_pool(config, n=n, seed=7, workers=2, checkpoint_path=checkpoint, progress=interrupt)
    done = checkpoint.read_text().splitlines()
    assert len(done) == 1 + 2  # header and the two chunks finished before the kill
    with checkpoint.open("a") as handle:
        handle.write('[{"sample": 1, "cha')  # a line cut short by the kill
    seen = []
    resumed = generate_pool(
        config, n=n, seed=7, workers=1, checkpoint_path=checkpoint, progress=lambda p: seen.append(p.attempts)
    )
    assert seen[0] == 2 * config.sampling.chunk_size  # it did not start over
    assert resumed.to_dict() == uninterrupted.to_dict()


def test_pool_file_round_trip(small_pool, tmp_path):
    from posegen.io import write_yaml

    path = tmp_path / "pool.yaml"
    write_yaml(path, small_pool.to_dict())
    again = load_pool(path)
    assert again.to_dict() == small_pool.to_dict()
    prov = again.provenance
    assert prov["seed"] == 7 and len(prov["robot_model_sha256"]) == 64 and prov["posegen_version"]
    assert prov["config"]["table"]["top_center_m"] == [0.65, 0.0, 0.68]


def test_pool_file_with_sidecar_round_trip(small_pool, tmp_path):
    """What ``posegen pool`` writes: a YAML header and a .npz of the postures, read back exactly."""
    import yaml

    from posegen.io import write_pool

    path = tmp_path / "pool.yaml"
    write_pool(path, small_pool)
    header = yaml.safe_load(path.read_text())
    assert header["format_version"] == 2 and "postures" not in header
    assert header["summary"]["accepted"] == len(small_pool.postures)
    assert load_pool(path) == small_pool
    sidecar = header["arrays"]["file"]
    first = (path.read_bytes(), (tmp_path / sidecar).read_bytes())
    write_pool(tmp_path / "again" / "pool.yaml", small_pool)
    assert first == ((tmp_path / "again" / "pool.yaml").read_bytes(), (tmp_path / "again" / sidecar).read_bytes())


def test_table_out_of_reach_is_infeasible(config):
    import dataclasses

    high = dataclasses.replace(config.table, top_center_m=(0.65, 0.0, 1.9))  # within the chains' length
    with pytest.raises(InfeasibleError, match=r"table\.top_center_m\) within the arms' reach"):
        generate_pool(dataclasses.replace(config, table=high), n=5, seed=0, workers=1)


def test_table_beyond_the_chains_length_names_the_field(config):
    import dataclasses

    far = dataclasses.replace(config.table, top_center_m=(0.65, 0.0, 2.5))
    with pytest.raises(ConfigError, match=r"^table\.top_center_m: out of reach of chain 'left'"):
        generate_pool(dataclasses.replace(config, table=far), n=5, seed=0, workers=1)


def test_nonpositive_n_is_rejected(config):
    with pytest.raises(InfeasibleError, match="positive"):
        generate_pool(config, n=0, seed=0)


def test_malformed_pool_is_an_input_error():
    from posegen.errors import InputError

    with pytest.raises(InputError, match="posture 0"):
        pool_from_dict({"format_version": 1, "joint_names": ["a"], "postures": [{"joints": [0.1]}]})


def test_example_pool_is_reproducible_and_valid(scene, config, example_pool):
    """plans/talos/pool.yaml is what posegen makes today, and it passes the mesh check.

    To solver precision rather than bit for bit: another CPU rounds the last bits otherwise
    (see tests/numeric_fingerprint.py); a change of the projection moves postures by far more.
    """
    again = generate_pool(config, n=15, seed=example_pool.provenance["seed"], workers=1)
    assert [p.sample for p in again.postures] == [p.sample for p in example_pool.postures[:15]]
    np.testing.assert_allclose(again.joints(), example_pool.joints()[:15], rtol=0, atol=1e-6)
    assert example_pool.provenance["config"] == config.to_dict()
    assert verify_postures(scene, example_pool.postures).ok


def test_too_low_an_acceptance_says_why_the_samples_were_rejected(example_pool):
    """The probe's error named its rejections; the one at the acceptance floor did not (a helper's box-shaped robot)."""
    from posegen.pool.generation import MAX_SAMPLES_PER_POSTURE, _sample_until
    from posegen.pool.sampler import Rejection
    from posegen.progress import ignore_progress

    chunk = [example_pool.postures[0]] + [Rejection.COLLISION] * 180 + [Rejection.NOT_CONVERGED] * 119  # 1 in 300
    outcomes: list = []
    message = r"^only 2 feasible postures in 600 samples \(rejections: \{'not_converged': 238, 'collision': 360\}\); "
    with pytest.raises(InfeasibleError, match=message + "loosen the margins or move the table$"):
        _sample_until(3, outcomes, iter([chunk] * 10), None, ignore_progress)
    assert len(outcomes) == MAX_SAMPLES_PER_POSTURE * 3  # the floor: one posture in MAX_SAMPLES_PER_POSTURE samples
