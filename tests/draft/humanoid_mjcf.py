"""A small synthetic MJCF humanoid (z up, free root) for the MJCF conversion and ``robot init`` tests.

The same robot as :mod:`tests.draft.humanoid_urdf`, written the MuJoCo way: the hip's
three hinges in one body (the thigh), the ankle's two in one body (the foot), the
shoulder's three in one (the upper arm); capsule limbs, box feet, palms and trunk; a
free joint at the root; a neck hinge placed off its body's origin (``pos``), a camera
body welded to the head, a floor plane, an actuator and a site (none carried).
"""

from __future__ import annotations

from pathlib import Path

FOOT = (0.22, 0.10, 0.04)  # m, forward, lateral, vertical
HAND = (0.08, 0.06, 0.02)

# joint names of each body with several joints, in order (the test reads them independently of posegen)
MULTI_JOINT_BODIES = {
    "l_thigh": ["l_hip_yaw", "l_hip_roll", "l_hip_pitch"],
    "r_thigh": ["r_hip_yaw", "r_hip_roll", "r_hip_pitch"],
    "l_foot": ["l_ankle_pitch", "l_ankle_roll"],
    "r_foot": ["r_ankle_pitch", "r_ankle_roll"],
    "l_upper_arm": ["l_shoulder_pitch", "l_shoulder_roll", "l_shoulder_yaw"],
    "r_upper_arm": ["r_shoulder_pitch", "r_shoulder_roll", "r_shoulder_yaw"],
}


def _inertial(mass: float, z: float) -> str:
    return f'<inertial pos="0 0 {z}" mass="{mass}" diaginertia="0.01 0.012 0.008"/>'


def _leg(side: str, sign: float) -> str:
    fx, fy, fz = (s / 2 for s in FOOT)
    return f"""
      <body name="{side}_thigh" pos="0 {0.1 * sign} -0.05">
        {_inertial(7.0, -0.2)}
        <joint name="{side}_hip_yaw" axis="0 0 1" range="-1 1"/>
        <joint name="{side}_hip_roll" axis="1 0 0" range="-1 1"/>
        <joint name="{side}_hip_pitch" axis="0 1 0" range="-1.5 1"/>
        <geom type="capsule" fromto="0 0 -0.08 0 0 -0.32" size="0.05"/>
        <body name="{side}_shank" pos="0 0 -0.4">
          {_inertial(3.0, -0.2)}
          <joint name="{side}_knee" axis="0 1 0" range="0 2"/>
          <geom type="capsule" fromto="0 0 -0.08 0 0 -0.32" size="0.04"/>
          <body name="{side}_foot" pos="0 0 -0.4">
            {_inertial(1.5, -0.05)}
            <joint name="{side}_ankle_pitch" axis="0 1 0" range="-1 1"/>
            <joint name="{side}_ankle_roll" axis="1 0 0" range="-0.5 0.5"/>
            <geom type="box" pos="0.03 0 -0.06" size="{fx} {fy} {fz}"/>
          </body>
        </body>
      </body>"""


def _arm(side: str, sign: float) -> str:
    low, high = (0.1, 1.5) if sign > 0 else (-1.5, -0.1)  # the arm away from the body
    hx, hy, hz = (s / 2 for s in HAND)
    return f"""
        <body name="{side}_upper_arm" pos="0 {0.2 * sign} 0.35">
          {_inertial(3.0, -0.12)}
          <joint name="{side}_shoulder_pitch" axis="0 1 0" range="-1.5 1.5"/>
          <joint name="{side}_shoulder_roll" axis="1 0 0" range="{low} {high}"/>
          <joint name="{side}_shoulder_yaw" axis="0 0 1" range="-1.5 1.5"/>
          <geom type="capsule" fromto="0 0 -0.06 0 0 -0.2" size="0.035"/>
          <body name="{side}_forearm" pos="0 0 -0.25">
            {_inertial(1.5, -0.12)}
            <joint name="{side}_elbow" axis="0 1 0" range="-2 0"/>
            <geom type="capsule" fromto="0 0 -0.05 0 0 -0.19" size="0.03"/>
            <body name="{side}_hand" pos="0 0 -0.25">
              {_inertial(0.5, -0.04)}
              <joint name="{side}_wrist" axis="0 1 0" range="-1 1"/>
              <geom type="box" pos="0 0 -0.06" size="{hx} {hy} {hz}"/>
            </body>
          </body>
        </body>"""


def humanoid_mjcf(folder: Path, legs: int = 2) -> Path:
    """Write the MJCF model (``legs`` legs) to ``folder/robot.xml``; its path."""
    folder.mkdir(parents=True, exist_ok=True)
    leg_bodies = "".join(_leg(side, sign) for side, sign in (("l", 1.0), ("r", -1.0))[:legs])
    arms = "".join(_arm(side, sign) for side, sign in (("l", 1.0), ("r", -1.0)))
    text = f"""<mujoco model="synthetic_mjcf">
  <compiler angle="radian"/>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="pelvis" pos="0 0 1">
      <freejoint name="root"/>
      {_inertial(10.0, 0.0)}
      <geom type="box" size="0.06 0.08 0.04"/>{leg_bodies}
      <body name="torso" pos="0 0 0.1">
        {_inertial(15.0, 0.2)}
        <joint name="waist" axis="0 0 1" range="-1 1"/>
        <geom type="box" pos="0 0 0.2" size="0.08 0.12 0.15"/>
        <body name="head" pos="0 0 0.45">
          {_inertial(4.0, 0.1)}
          <joint name="neck" axis="0 0 1" range="-1 1" pos="0 0 0.02"/>
          <geom type="sphere" pos="0 0 0.1" size="0.08"/>
          <site name="eye" pos="0.08 0 0.1"/>
          <body name="camera" pos="0.07 0 0.12" euler="0 0.3 0">
            <geom type="box" size="0.01 0.02 0.01" contype="0" conaffinity="0" group="1"/>
          </body>
        </body>{arms}
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="waist_motor" joint="waist"/>
  </actuator>
</mujoco>
"""
    path = folder / "robot.xml"
    path.write_text(text)
    return path
