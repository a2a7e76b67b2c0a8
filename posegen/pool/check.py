"""Independent re-verification of contact postures (``posegen check``).

Kinematics by pinocchio from the joint angles alone; collisions by coal on the robot's
original meshes (not the convex hulls the sampler used), with the configured margin.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from posegen.progress import Progress, ProgressCallback, ignore_progress
from posegen.robot import CollisionChecker, Invariant, Posture, Scene, Verification, assess, summarize


def verify_postures(
    scene: Scene,
    postures: Sequence[Posture],
    progress: ProgressCallback = ignore_progress,
) -> Verification:
    """Re-check every posture's invariants from scratch.

    Args:
        scene: The scene the postures were made for.
        postures: Postures to check.
        progress: Told after each posture.

    """
    meshes = CollisionChecker(scene, convex=False)
    margin = scene.margins.collision_m
    excess: dict[Invariant, list[float]] = {k: [] for k in Invariant}
    details: dict[Invariant, list[str]] = {k: [] for k in Invariant}
    for index, posture in enumerate(postures):
        joints = np.array(posture.joints, dtype=float)
        found = assess(scene, None, joints, posture.chain)
        excess_of = found.excess(scene)
        values = {
            Invariant.SOLE: f"sole {found.sole_position_error_m:.2e} m, {found.sole_angle_error_rad:.2e} rad",
            Invariant.CONTACT: f"height {found.contact_height_m:.2e} m, roll {found.contact_roll_rad:.2e} rad, "
            f"pitch {found.contact_pitch_rad:.2e} rad",
            Invariant.COM: f"CoM margin {found.com_margin_m:.4f} m",
            Invariant.JOINT_LIMITS: f"joint-limit margin {found.joint_limit_margin_rad:.4f} rad",
        }
        measured = {k: (excess_of[k], text) for k, text in values.items()}
        hits = meshes.colliding_pairs(scene.configuration(joints), posture.chain, margin)
        if hits:
            pair = f"{hits[0].pair[0]} - {hits[0].pair[1]}"
            measured[Invariant.COLLISION] = (margin - hits[0].distance_m, f"{pair} at {hits[0].distance_m:.4f} m")
        else:
            measured[Invariant.COLLISION] = (0.0, f"no pair closer than {margin} m (meshes)")
        for key, (value, text) in measured.items():
            excess[key].append(value)
            details[key].append(text)
        progress(Progress(index + 1, len(postures), "posture"))
    return summarize(len(postures), excess, details)
