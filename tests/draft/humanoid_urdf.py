"""A small synthetic humanoid URDF (any up axis, relative mesh paths) for ``robot init`` tests.

Legs of 6 joints (hip yaw, roll, pitch, knee, ankle pitch, roll), a waist, arms of 5
joints, a head; feet and hands are box meshes (STL files beside the URDF, named by
relative paths). ``up`` picks the model's up axis: "z" (REP 103) or "y" (x forward, z
to the right, as biomechanics models are). ``waist`` roots the model at the torso instead
of the pelvis, with that many waist joints (1: yaw; 2: yaw then pitch) from the torso down
to the pelvis carrying the legs (the same body: the torso where it was, the pelvis below).

Three variants give geometry a draft must not trust as it is: ``palms`` fixes a 14 cm palm
below each hand with a visual mesh only; ``rod_feet`` puts two thin collision rods (2 cm,
4 cm across) under each 10 cm wide sole mesh; ``disc_torso`` gives the torso a 39 cm tall
visual mesh over a 6 cm collision disc.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

FOOT = (0.22, 0.10, 0.04)  # m, x (forward), lateral, vertical
HAND = (0.08, 0.06, 0.02)  # flat palm: its lowest face is flat
PALM = (0.08, 0.03, 0.14)  # the palm variant's: below the hand, 14 cm long
TORSO = (0.2, 0.26, 0.39)  # the disc variant's torso mesh (its collision: a disc of DISC_M across)
DISC_M = 0.06
ROD_RADIUS_M = 0.01  # the rod variant's two rods, 2 cm thick, 4 cm across together


def _axes(up: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Forward, left, up in the model's frame ("z": z up; "zy": z up, y forward; "y": y up)."""
    forward = np.array([1.0, 0.0, 0.0])
    if up == "z":
        return forward, np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])
    if up == "zy":
        return np.array([0.0, 1.0, 0.0]), np.array([-1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    return forward, np.array([0.0, 0.0, -1.0]), np.array([0.0, 1.0, 0.0])


def _v(x: np.ndarray) -> str:
    return " ".join(f"{float(c):.6g}" for c in x)


def humanoid_urdf(
    folder: Path,
    up: str = "z",
    legs: int = 2,
    meshes: bool = True,
    waist: int = 0,
    palms: bool = False,
    rod_feet: bool = False,
    disc_torso: bool = False,
) -> Path:
    """Write the URDF (and its meshes under ``folder/meshes``); its path (``waist`` > 0: rooted at the torso)."""
    forward, left, upward = _axes(up)
    down = -upward
    (folder / "meshes").mkdir(parents=True, exist_ok=True)
    sizes = {"foot": FOOT, "hand": HAND, "palm": PALM, "torso": TORSO}
    for name, (fx, fl, fu) in sizes.items():
        extents = np.abs(forward * fx + left * fl + upward * fu)  # the box's size along the model's axes
        trimesh.creation.box(extents=extents).export(folder / "meshes" / f"{name}.stl")
    links: list[str] = []
    joints: list[str] = []

    def link(
        name: str, mass: float, com: np.ndarray, mesh: str = "", at: np.ndarray | None = None, collision: str = "mesh"
    ) -> None:
        """A link; ``mesh`` its visual (at ``at``), and its collision too unless ``collision`` gives other XML."""
        geometry = ""
        if mesh and meshes:
            origin = _v(np.zeros(3) if at is None else at)
            shape = f'<origin xyz="{origin}"/><geometry><mesh filename="meshes/{mesh}.stl"/></geometry>'
            geometry = f"<visual>{shape}</visual>" + (
                f"<collision>{shape}</collision>" if collision == "mesh" else collision
            )
        links.append(
            f'<link name="{name}"><inertial><origin xyz="{_v(com)}"/><mass value="{mass}"/>'
            f'<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>{geometry}</link>'
        )

    def joint(name: str, parent: str, child: str, at: np.ndarray, axis: np.ndarray, low: float, high: float) -> None:
        joints.append(
            f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{_v(at)}"/><axis xyz="{_v(axis)}"/>'
            f'<limit lower="{low}" upper="{high}" effort="100" velocity="3"/></joint>'
        )

    link("pelvis", 10.0, np.zeros(3))
    for side, sign in (("l", 1.0), ("r", -1.0))[:legs]:
        link(f"{side}_hip_yaw_link", 1.0, 0.005 * down)
        joint(f"{side}_hip_yaw", "pelvis", f"{side}_hip_yaw_link", sign * 0.1 * left + 0.05 * down, upward, -1, 1)
        link(f"{side}_hip_roll_link", 1.0, 0.005 * down)
        joint(f"{side}_hip_roll", f"{side}_hip_yaw_link", f"{side}_hip_roll_link", np.zeros(3), forward, -1, 1)
        link(f"{side}_thigh", 5.0, 0.2 * down)
        joint(f"{side}_hip_pitch", f"{side}_hip_roll_link", f"{side}_thigh", np.zeros(3), left, -1.5, 1.0)
        link(f"{side}_shank", 3.0, 0.2 * down)
        joint(f"{side}_knee", f"{side}_thigh", f"{side}_shank", 0.4 * down, left, 0.0, 2.0)
        link(f"{side}_ankle", 0.5, np.zeros(3))
        joint(f"{side}_ankle_pitch", f"{side}_shank", f"{side}_ankle", 0.4 * down, left, -1.0, 1.0)
        sole = 0.03 * forward + 0.06 * down  # the foot mesh's centre
        link(f"{side}_foot", 1.0, 0.05 * down, "foot", sole, _rods(sole, forward, left, down) if rod_feet else "mesh")
        joint(f"{side}_ankle_roll", f"{side}_ankle", f"{side}_foot", np.zeros(3), forward, -0.5, 0.5)
    if disc_torso:
        link("torso", 15.0, 0.2 * upward, "torso", 0.2 * upward, _cylinder(0.2 * upward, DISC_M / 2, 0.01, "0 0 0"))
    else:
        link("torso", 15.0, 0.2 * upward)
    if waist == 0:
        joint("waist", "pelvis", "torso", 0.1 * upward, upward, -1.0, 1.0)
    elif waist == 1:
        joint("waist", "torso", "pelvis", 0.1 * down, upward, -1.0, 1.0)
    else:
        link("waist_link", 0.5, np.zeros(3))
        joint("waist", "torso", "waist_link", 0.1 * down, upward, -1.0, 1.0)
        joint("waist_pitch", "waist_link", "pelvis", np.zeros(3), left, -0.5, 0.5)
    link("head", 4.0, 0.1 * upward)
    joint("neck", "torso", "head", 0.45 * upward, upward, -1.0, 1.0)
    for side, sign in (("l", 1.0), ("r", -1.0)):
        link(f"{side}_shoulder_pitch_link", 0.5, 0.005 * down)
        joint(
            f"{side}_shoulder_pitch",
            "torso",
            f"{side}_shoulder_pitch_link",
            sign * 0.2 * left + 0.35 * upward,
            left,
            -1.5,
            1.5,
        )
        low, high = (0.1, 1.5) if sign > 0 else (-1.5, -0.1)  # the arm away from the body
        link(f"{side}_shoulder_roll_link", 0.5, 0.005 * down)
        joint(
            f"{side}_shoulder_roll",
            f"{side}_shoulder_pitch_link",
            f"{side}_shoulder_roll_link",
            np.zeros(3),
            forward,
            low,
            high,
        )
        link(f"{side}_upper_arm", 2.0, 0.12 * down)
        joint(f"{side}_shoulder_yaw", f"{side}_shoulder_roll_link", f"{side}_upper_arm", np.zeros(3), upward, -1.5, 1.5)
        link(f"{side}_forearm", 1.5, 0.12 * down)
        joint(f"{side}_elbow", f"{side}_upper_arm", f"{side}_forearm", 0.25 * down, left, -2.0, 0.0)
        link(f"{side}_hand", 0.5, 0.04 * down, "hand", 0.06 * down)
        joint(f"{side}_wrist", f"{side}_forearm", f"{side}_hand", 0.25 * down, left, -1.0, 1.0)
        if palms:  # fixed below the hand, its mesh a visual only
            link(f"{side}_palm", 0.14, PALM[2] / 2 * down, "palm", PALM[2] / 2 * down, collision="")
            joints.append(
                f'<joint name="{side}_palm_fixed" type="fixed"><parent link="{side}_hand"/><child link="{side}_palm"/>'
                f'<origin xyz="{_v((0.06 + HAND[2] / 2) * down)}"/></joint>'
            )
    path = folder / "robot.urdf"
    path.write_text('<?xml version="1.0"?>\n<robot name="synthetic">\n' + "\n".join(links + joints) + "\n</robot>\n")
    return path


def _cylinder(centre: np.ndarray, radius: float, length: float, rpy: str) -> str:
    return (
        f'<collision><origin xyz="{_v(centre)}" rpy="{rpy}"/>'
        f'<geometry><cylinder radius="{radius}" length="{length}"/></geometry></collision>'
    )


def _rods(sole: np.ndarray, forward: np.ndarray, left: np.ndarray, down: np.ndarray) -> str:
    """Two collision rods along the foot, their bottoms on the sole mesh's, 4 cm across together."""
    rpy = "0 1.5707963267948966 0"  # the cylinder's axis (z) along forward (x, in both up conventions)
    low = sole + (FOOT[2] / 2 - ROD_RADIUS_M) * down
    return "".join(
        _cylinder(low + side * ROD_RADIUS_M * left, ROD_RADIUS_M, FOOT[0] - 0.02, rpy) for side in (-1.0, 1.0)
    )
