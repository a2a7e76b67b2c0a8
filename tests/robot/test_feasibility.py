"""A posture's assessment: the same with a reused workspace as with a fresh one."""

from __future__ import annotations

import numpy as np

from posegen.io import Pool
from posegen.robot import Scene, Statics, assess


def test_a_reused_workspace_assesses_as_a_fresh_one(scene: Scene, example_pool: Pool) -> None:
    """The pool's sampler reuses one pinocchio workspace: nothing of the last posture may leak into the next."""
    statics, data = Statics(scene), scene.model.createData()
    postures = example_pool.postures[:6]
    for posture in postures:
        joints = np.array(posture.joints)
        reused = assess(scene, None, joints, posture.chain, statics, data)
        fresh = assess(scene, None, joints, posture.chain)
        assert reused == fresh
    assert len({assess(scene, None, np.array(p.joints), p.chain).com_margin_m for p in postures}) == len(postures)
