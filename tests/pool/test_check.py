"""The pool check's collision verdict: screened by bounding spheres, the same as coal on every pair."""

import dataclasses

import numpy as np

from posegen.pool.check import _checker, _measure
from posegen.robot import Invariant


def test_screened_verdict_equals_every_pair_checked(scene, example_pool):
    """Postures leaned and twisted until some collide: the check flags exactly those coal finds on all pairs."""
    rng = np.random.default_rng(5)
    state = _checker(scene.config, scene.files.sha256())
    _, meshes = state
    margin = scene.margins.collision_m
    postures = []
    for posture in example_pool.postures[:30]:
        joints = np.array(posture.joints) + np.where(scene.locked, 0.0, rng.normal(0.0, 0.25, len(posture.joints)))
        postures.append(dataclasses.replace(posture, joints=tuple(joints)))
    measured = _measure(state, postures)
    flagged = [excess[Invariant.COLLISION] > 0 for excess, _ in measured]
    direct = [bool(meshes.colliding_pairs(scene.configuration(np.array(p.joints)), p.chain, margin)) for p in postures]
    assert flagged == direct
    assert 0 < sum(flagged) < len(flagged)  # both verdicts occur
