"""Independent re-verification of contact postures (``posegen check``).

Kinematics by pinocchio from the joint angles alone; collisions by coal on the robot's
original meshes (not the convex hulls the sampler used), with the configured margin.
Postures are checked in chunks by workers (local processes or a Dask cluster) and
streamed into the worst case of each invariant, so a pool of any size is checked in
bounded memory.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Iterable, Sequence

import numpy as np

from posegen.errors import BackendError
from posegen.io import Posture
from posegen.parallel import Backend, Job, as_backend, job_name
from posegen.progress import Progress, ProgressCallback, ignore_progress
from posegen.robot import (
    Assessment,
    CollisionChecker,
    Config,
    Invariant,
    Scene,
    Statics,
    Verification,
    WorstSoFar,
    assess,
)

CHUNK = 16  # postures per unit of work
Measured = tuple[dict[Invariant, float], dict[Invariant, str]]  # excess and what was measured, per invariant


def _checker(config: Config, model_sha256: str) -> tuple[Scene, CollisionChecker]:
    scene = Scene(config)
    found = scene.files.sha256()
    if found != model_sha256:
        raise BackendError(
            f"a worker's robot model differs from this one (sha256 {found[:12]} vs {model_sha256[:12]}); "
            "install the same robot description on every worker"
        )
    return scene, CollisionChecker(scene, convex=False)


def torque_detail(scene: Scene, found: Assessment) -> str:
    """The worst holding torque of a posture, as a short text."""
    if not found.effort_joint:
        return "no effort limit in the URDF: torques not checked"
    force = scene.route.contact_force_n
    return (
        f"holding torque {found.effort_ratio:.3f} x the effort limit at {found.effort_joint} "
        f"(hand unloaded and pressing {force:g} N)"
    )


def _measure(state: tuple[Scene, CollisionChecker], postures: Sequence[Posture]) -> list[Measured]:
    scene, meshes = state
    statics = Statics(scene)
    data = scene.model.createData()
    margin = scene.margins.collision_m
    out = []
    for posture in postures:
        joints = np.array(posture.joints, dtype=float)
        found = assess(scene, None, joints, posture.chain, statics, data)
        excess = found.excess(scene)
        details = {
            Invariant.SOLE: f"sole {found.sole_position_error_m:.2e} m, {found.sole_angle_error_rad:.2e} rad",
            Invariant.CONTACT: found.contact_detail(),
            Invariant.COM: f"CoM margin {found.com_margin_m:.4f} m",
            Invariant.JOINT_LIMITS: f"joint-limit margin {found.joint_limit_margin_rad:.4f} rad",
            Invariant.ZMP: f"centre of pressure {found.pressed_zmp_margin_m:.4f} m inside, the hand pressing "
            f"{scene.route.contact_force_n:g} N",
            Invariant.TORQUE: torque_detail(scene, found),
        }
        q = scene.configuration(joints)
        # the bounding spheres screen first (as the route check): coal only on the pairs they cannot clear
        hits = meshes.colliding_pairs(q, posture.chain, margin) if meshes.collides(q, posture.chain, margin) else []
        if hits:
            excess[Invariant.COLLISION] = margin - hits[0].distance_m
            details[Invariant.COLLISION] = f"{hits[0].pair[0]} - {hits[0].pair[1]} at {hits[0].distance_m:.4f} m"
        else:
            excess[Invariant.COLLISION] = 0.0
            details[Invariant.COLLISION] = f"no pair closer than {margin} m (meshes)"
        out.append((excess, details))
    return out


def checking_job(scene: Scene) -> Job[tuple[Scene, CollisionChecker], Sequence[Posture], list[Measured]]:
    """The check's work: chunks of postures, each measured on a worker's meshes."""
    sha = scene.files.sha256()
    return Job(
        name=job_name("check", scene.config.to_dict(), sha),
        setup=functools.partial(_checker, scene.config, sha),
        run=_measure,
    )


def _chunks(postures: Iterable[Posture]) -> Iterable[tuple[Posture, ...]]:
    iterator = iter(postures)
    while chunk := tuple(itertools.islice(iterator, CHUNK)):
        yield chunk


def verify_postures(
    scene: Scene,
    postures: Sequence[Posture],
    progress: ProgressCallback = ignore_progress,
    workers: int | Backend = 1,
) -> Verification:
    """Re-check every posture's invariants from scratch.

    Args:
        scene: The scene the postures were made for.
        postures: Postures to check.
        progress: Told after each chunk of postures.
        workers: Local worker processes (1: in this process), or the backend to run on.

    Raises:
        BackendError: A worker cannot run the check (another version or robot model).

    """
    backend = as_backend(workers)
    worst: WorstSoFar[Invariant] = WorstSoFar(list(Invariant))
    for measured in backend.map(checking_job(scene), _chunks(postures)):
        for excess, details in measured:
            worst.add(excess, details)
        progress(Progress(worst.checked, len(postures), "posture"))
    return worst.result()
