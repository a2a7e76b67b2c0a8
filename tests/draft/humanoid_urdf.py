"""A small synthetic humanoid URDF (any up axis, relative mesh paths) for ``robot init`` tests.

Legs of 6 joints (hip yaw, roll, pitch, knee, ankle pitch, roll), a waist, arms of 5
joints, a head; feet and hands are box meshes (STL files beside the URDF, named by
relative paths). ``up`` picks the model's up axis: "z" (REP 103) or "y" (x forward, z
to the right, as biomechanics models are). ``waist`` roots the model at the torso instead
of the pelvis, with that many waist joints (1: yaw; 2: yaw then pitch) from the torso down
to the pelvis carrying the legs (the same body: the torso where it was, the pelvis below).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

FOOT = (0.22, 0.10, 0.04)  # m, x (forward), lateral, vertical
HAND = (0.08, 0.06, 0.02)  # flat palm: its lowest face is flat


def _axes(up: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Forward, left, up in the model's frame."""
    forward = np.array([1.0, 0.0, 0.0])
    if up == "z":
        return forward, np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])
    return forward, np.array([0.0, 0.0, -1.0]), np.array([0.0, 1.0, 0.0])


def _v(x: np.ndarray) -> str:
    return " ".join(f"{float(c):.6g}" for c in x)


def humanoid_urdf(folder: Path, up: str = "z", legs: int = 2, meshes: bool = True, waist: int = 0) -> Path:
    """Write the URDF (and its meshes under ``folder/meshes``); its path (``waist`` > 0: rooted at the torso)."""
    forward, left, upward = _axes(up)
    down = -upward
    (folder / "meshes").mkdir(parents=True, exist_ok=True)
    sizes = {"foot": FOOT, "hand": HAND}
    for name, (fx, fl, fu) in sizes.items():
        extents = np.abs(forward * fx + left * fl + upward * fu)  # the box's size along the model's axes
        trimesh.creation.box(extents=extents).export(folder / "meshes" / f"{name}.stl")
    links: list[str] = []
    joints: list[str] = []

    def link(name: str, mass: float, com: np.ndarray, mesh: str = "", offset: np.ndarray | None = None) -> None:
        geometry = ""
        if mesh and meshes:
            at = _v(np.zeros(3) if offset is None else offset)
            geometry = (
                f'<visual><origin xyz="{at}"/><geometry><mesh filename="meshes/{mesh}.stl"/></geometry></visual>'
                f'<collision><origin xyz="{at}"/><geometry><mesh filename="meshes/{mesh}.stl"/></geometry></collision>'
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
        link(f"{side}_foot", 1.0, 0.05 * down, "foot", 0.03 * forward + 0.06 * down)
        joint(f"{side}_ankle_roll", f"{side}_ankle", f"{side}_foot", np.zeros(3), forward, -0.5, 0.5)
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
    path = folder / "robot.urdf"
    path.write_text('<?xml version="1.0"?>\n<robot name="synthetic">\n' + "\n".join(links + joints) + "\n</robot>\n")
    return path
