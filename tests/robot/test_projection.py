"""The projection's stop rule: an iteration whose errors repeat is stuck, a shrinking one is not."""

import pytest

from posegen.pool.sampler import draw
from posegen.robot.projection import Projector, _cycling


def test_repeating_errors_are_stuck():
    alternating = [(0.18, 0.37), (0.19, 0.36), (0.18, 0.37), (0.19, 0.36), (0.18, 0.37)]
    assert _cycling(alternating)
    plateau = [(0.05, 0.2), (0.05, 0.2), (0.05, 0.2)]
    assert _cycling(plateau)


def test_shrinking_or_wandering_errors_go_on():
    shrinking = [(0.1 * 0.8**k, 0.5 * 0.8**k) for k in range(20)]
    assert not any(_cycling(shrinking[: k + 1]) for k in range(len(shrinking)))
    wandering = [(0.67, 2.6), (0.18, 1.9), (0.17, 2.3), (0.21, 1.9), (0.14, 2.0), (0.16, 2.2)]
    assert not any(_cycling(wandering[: k + 1]) for k in range(len(wandering)))
    slow = [(0.0079, 0.01), (0.0070, 0.01), (0.0051, 0.01), (0.0045, 0.01), (0.0034, 0.01)]
    assert not _cycling(slow)


def test_the_hard_phase_of_a_flush_contact_converges_quadratically(scene):
    """The hard phase is a least-change Gauss-Newton projection: no pull toward the sample fights the equalities.

    With the sample's pull kept in the hard phase, the error only shrank about twofold per
    iteration (median 6 hard iterations, up to 14, last step's ratio 0.17 on these samples).
    """
    projector = Projector(scene)
    log: list[tuple[bool, float]] = []  # (hard phase, contact/sole position error m) per iteration
    errors, limit = projector._errors, projector._limit_torques
    hard = [False]

    def record_errors(problem, target, contact):
        found = errors(problem, target, contact)
        log.append((hard[0], found[0]))
        return found

    def mark_hard(problem, chain):
        hard[0] = True
        return limit(problem, chain)

    projector._errors, projector._limit_torques = record_errors, mark_hard
    converged = 0
    for index in range(40):
        log.clear()
        hard[0] = False
        sample = draw(scene, 0, index)
        assert scene.chain(sample.chain).contact_kind.aligned
        if not projector.project(sample.joints, sample.chain, scene.spot_world(sample.spot)).converged:
            continue
        converged += 1
        steps = [e for in_hard, e in log if in_hard]
        assert 1 <= len(steps) <= 4
        if len(steps) >= 2:
            assert steps[-1] <= 0.02 * steps[-2]  # quadratic: the last step gains orders of magnitude
    assert converged >= 25


def test_the_equality_errors_are_the_soles_and_contacts_distances_from_their_targets(scene):
    """``_errors`` on plain floats against the same quantities with numpy, at random postures."""
    import numpy as np

    projector = Projector(scene)
    rng = np.random.default_rng(6)
    normal = scene.table_pose[:3, 2]
    for chain in scene.chains:
        problem = projector._problems[chain.name]
        for _ in range(20):
            projector._set_joints(rng.uniform(*scene.planning_limits()))
            contact = np.array(projector.robot.get_T_world_frame(problem.contact))  # (4, 4)
            target = rng.normal(0.0, 0.1, 3)
            position, angle = projector._errors(problem, target.tolist(), contact.tolist())
            soles = [(np.array(projector.robot.get_T_world_frame(f)), pose) for f, pose in scene.sole_poses.items()]
            assert position == pytest.approx(
                max(*(np.linalg.norm(a[:3, 3] - p[:3, 3]) for a, p in soles), abs(normal @ (contact[:3, 3] - target))),
                rel=1e-12,
            )
            angles = [np.linalg.norm(a[:3, :3] - p[:3, :3]) for a, p in soles]  # Frobenius
            if problem.kind.aligned:
                angles.append(np.arccos(np.clip(contact[:3, 2] @ normal, -1.0, 1.0)))
            assert angle == pytest.approx(max(angles), rel=1e-12)
