"""The joints at an arm's end that a plan cannot use, dropped from the arm and locked by ``robot init``.

Two kinds, each said in a ``# CHECK:`` line:

* :func:`without_narrow_ends`: a joint whose range leaves no room inside the margins (a
  slide finger): it could not move in a plan;
* :func:`without_idle_ends`: a light joint whose part the hand's tip does not follow (a
  gripper's motor link between fingers fixed to the wrist, as in a reduced model): the
  contact would not depend on it, so the data could not calibrate it, and its part hides
  nothing of the hand's.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin

from posegen.draft.geometry import Geometry, carried, forearm, link_of_joint
from posegen.draft.limits import limits
from posegen.robot import leaves_no_room

MIN_ARM_JOINTS = 3  # an arm keeps at least this many joints
BEYOND_M = 0.001  # the wrist's geometry reaches beyond the end's by more than this


def without_narrow_ends(model: pin.Model, arm: list[int], margin: float) -> tuple[list[int], str]:
    """An arm without the joints at its end too narrow to keep ``margin`` from both limits (a gripper's finger).

    Such a joint could not move in a plan; off the arm, it is locked and its link is part of the hand.
    Returns the arm and a ``# CHECK:`` line ("" when none was dropped).

    Example:
        >>> arm, check = without_narrow_ends(model, [16, 17, 18, 19, 20], 0.02)  # 20: a slide finger of 2 cm
        >>> arm
        [16, 17, 18, 19]

    """
    kept = list(arm)
    while len(kept) > MIN_ARM_JOINTS and leaves_no_room(*limits(model, kept[-1]), margin):
        kept.pop()
    if len(kept) == len(arm):
        return kept, ""
    names = ", ".join(f"'{model.names[j]}'" for j in arm[len(kept) :])
    return kept, (
        f"{names} ended an arm with a range under twice margins.joint_limit_rad ({2.0 * margin:g}): locked, as a "
        f"gripper's finger; the hand is the link of '{model.names[kept[-1]]}'"
    )


def without_idle_ends(
    model: pin.Model,
    data: pin.Data,
    geometry: Geometry,
    arm: list[int],
    subtree: Callable[[int], list[int]],
    light_kg: float,
) -> tuple[list[int], str]:
    """An arm without the light joints at its end whose part the hand's tip does not follow.

    The arm's last joint is dropped while what it carries (its subtree) weighs under
    ``light_kg`` and the geometry of the joint before it (the wrist's body, with the links
    fixed to it) reaches farther along the forearm than that subtree's, at the posture of
    ``data``: the hand's tip, where a point contact goes, is then not on the dropped part.
    A joint whose subtree has no geometry is kept (what it moves is unknown).

    Returns:
        The arm and a ``# CHECK:`` line ("" when none was dropped).

    Example:
        >>> arm, check = without_idle_ends(model, data, geometry, arm, tree.subtree, 0.01 * robot_mass_kg)

    """
    kept = list(arm)
    while len(kept) > MIN_ARM_JOINTS and _idle(model, data, geometry, kept, subtree, light_kg):
        kept.pop()
    if len(kept) == len(arm):
        return kept, ""
    names = ", ".join(f"'{model.names[j]}'" for j in arm[len(kept) :])
    hand = link_of_joint(model, kept[-1])
    return kept, (
        f"{names} ended an arm moving only a light part (under {light_kg:.2f} kg) that the hand's tip does not "
        f"follow: the geometry fixed to '{hand}' reaches beyond it along the forearm (a gripper's motor between "
        f"fixed fingers); locked, and the hand is '{hand}'"
    )


def _idle(
    model: pin.Model,
    data: pin.Data,
    geometry: Geometry,
    arm: list[int],
    subtree: Callable[[int], list[int]],
    light_kg: float,
) -> bool:
    """Whether the arm's last joint is light and the joint before it carries the hand's tip."""
    end, wrist = arm[-1], arm[-2]
    carried_by_end = set(subtree(end))
    if sum(model.inertias[j].mass for j in carried_by_end) >= light_kg:
        return False
    reach = forearm(data, arm)  # (3,) m, world
    length = float(np.linalg.norm(reach))
    if length == 0.0:
        return False
    along = reach / length  # (3,) world, the forearm's direction
    world = pin.SE3.Identity()
    end_points = carried(model, data, geometry, carried_by_end, world)  # (k, 3) m, world
    wrist_points = carried(model, data, geometry, {wrist}, world)  # (k', 3) m, world
    if not len(end_points) or not len(wrist_points):
        return False
    return float((wrist_points @ along).max()) > float((end_points @ along).max()) + BEYOND_M
