"""Independent re-verification of contact postures (``posegen check``).

Kinematics by pinocchio from the joint angles alone; collisions by coal on the robot's
original meshes (not the convex hulls the sampler used), with the configured margin.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TypeVar

import numpy as np

from posegen.collision import CollisionChecker
from posegen.feasibility import Invariant, assess
from posegen.geometry import FloatArray
from posegen.sampler import Posture
from posegen.scene import Scene

K = TypeVar("K", bound=enum.Enum)


@dataclass(frozen=True)
class Worst:
    """The worst case of one invariant over a set of postures."""

    invariant: enum.Enum  # an Invariant, or a route's invariant
    excess: float  # how far past its bound (> 0: violated), in the invariant's unit
    posture: int  # index of the posture where it occurs
    violations: int  # number of postures violating it
    detail: str


@dataclass(frozen=True)
class Verification:
    """Result of re-checking postures."""

    checked: int
    worst: tuple[Worst, ...]  # one per invariant

    @property
    def ok(self) -> bool:
        """True if no posture violates any invariant."""
        return all(w.violations == 0 for w in self.worst)


def verify_postures(
    scene: Scene,
    postures: Sequence[Posture],
    progress: Callable[[int], None] | None = None,
) -> Verification:
    """Re-check every posture's invariants from scratch.

    Args:
        scene: The scene the postures were made for.
        postures: Postures to check.
        progress: Called with the number of postures checked so far.

    """
    meshes = CollisionChecker(scene, convex=False)
    margin = scene.config.margins.collision_m
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
        if progress:
            progress(index + 1)
    return summarize(len(postures), excess, details)


def summarize(
    checked: int, excess: Mapping[K, Sequence[float] | FloatArray], details: Mapping[K, Sequence[str]]
) -> Verification:
    """The worst case of each invariant, in the mapping's order.

    Args:
        checked: Number of items checked.
        excess: Per invariant, each item's excess over its bound (> 0: violated).
        details: Per invariant, each item's description of what was measured.

    """
    worst = []
    for key, values in excess.items():
        array = np.asarray(values, dtype=float)
        if array.size == 0:
            worst.append(Worst(key, 0.0, -1, 0, "nothing checked"))
            continue
        i = int(np.argmax(array))
        worst.append(Worst(key, float(array[i]), i, int(np.sum(array > 0)), details[key][i]))
    return Verification(checked=checked, worst=tuple(worst))
