import numpy as np
import pytest

from posegen.calibrate import Perturbation, simulate
from posegen.model import Contacts


def planned(pool, rows, session="sim"):
    joints = pool.joints()[rows]
    return Contacts(joints, tuple(pool.postures[i].chain for i in rows), (session,) * len(rows), ("",) * len(rows))


def test_settled_contacts_are_flush_on_the_true_robot(scene, example_pool):
    plan = planned(example_pool, list(range(20)))
    recorded, model, theta = simulate(scene, plan, Perturbation(), seed=1)
    assert np.abs(model.residuals(theta, recorded)).max() < 1e-9
    assert np.abs(model.residuals(model.nominal(), recorded)).max() > 1e-3  # the nominal robot is off
    moved = np.abs(recorded.joints - plan.joints).max(axis=0)
    for i, chain in enumerate(recorded.chains):
        outside = [j for j in range(len(scene.joint_names)) if j not in model.chains[chain].joint_indices]
        assert np.abs(recorded.joints[i, outside] - plan.joints[i, outside]).max() == 0.0
    assert 0 < moved.max() < 0.2  # a small correction, as a force-controlled contact makes


def test_errors_have_the_requested_size(scene, example_pool):
    plan = planned(example_pool, [0, 1])
    _, model, theta = simulate(scene, plan, Perturbation(length_m=2e-3, angle_rad=np.deg2rad(0.5)), seed=2)
    dev = theta - model.nominal()
    lengths = [dev[i] for i, p in enumerate(model.parameters) if p.unit.value == "m" and p.group.value != "plane"]
    angles = [dev[i] for i, p in enumerate(model.parameters) if p.unit.value == "rad" and p.group.value != "plane"]
    assert np.std(lengths) == pytest.approx(2e-3, rel=0.3)
    assert np.max(np.abs(angles)) <= np.deg2rad(1.5) + 1e-12


def test_encoder_noise_is_added(scene, example_pool):
    plan = planned(example_pool, list(range(5)))
    clean, _, _ = simulate(scene, plan, Perturbation(), seed=3)
    noisy, _, _ = simulate(scene, plan, Perturbation(encoder_noise_rad=1e-3), seed=3)
    assert 1e-4 < np.std(noisy.joints - clean.joints) < 2e-3
