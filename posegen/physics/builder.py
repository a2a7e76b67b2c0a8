"""The MuJoCo model of the robot at the table, built with MjSpec from a URDF.

The robot is the URDF's (its links as bodies: fixed links are kept, not fused, so the
soles, the force/torque frames and the fingertips stay bodies; its inertials as they
are), on a free base, with the geoms of :mod:`posegen.physics.geometry`. Added to it:

* one actuator per actuated joint: a joint position loop with implicit damping
  (``gain * ctrl - kp q - kd qdot``, MuJoCo's affine bias), its force limited to the
  URDF's effort (a joint without an effort limit is not limited); the controller sets
  ``ctrl`` so that its feed-forward torque rides on the PD (:mod:`posegen.physics.joint_control`);
* each joint's rotor inertia (armature) and the URDF's damping and friction;
* a passive spring joint after each compliant joint (same axis, stiffness the inverse
  of the compliance): the joint gives way under load and its encoder does not see it;
* a force/torque sensor at each chain's wrist (its wrench frame) and at each sole;
* with glued feet, a weld of each sole's link to the world (set from the initial state
  by :func:`glue_feet`).

Solver: fixed step ``TIMESTEP_S`` with ``implicitfast``, elliptic friction cones and the
noslip pass (without it, MuJoCo's soft friction lets a loaded sole creep).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.physics.gains import Gains
from posegen.physics.geometry import Shape, add_shapes, sole_in_link
from posegen.physics.tool import Tool
from posegen.robot import FloatArray, Scene, kinematic_urdf

TIMESTEP_S = 0.002
NOSLIP_ITERATIONS = 5  # MuJoCo's soft friction lets a loaded sole creep (0.1 mm/s); its noslip pass stops it
SPRING_DAMPING_S = 0.02  # a compliant joint's damping = stiffness x this (structural damping of the drive)
SPRING_ARMATURE = 1e-3  # kg m^2 on a spring joint (numerical: keeps its dof from being massless)
MIN_INERTIA = 1e-6  # kg m^2: the least principal inertia MuJoCo is given
SPECK_KG = 1e-6  # the mass a massless moving link is given
FT_SITE = "ft:{}"  # a chain's wrist sensor site, and its sensors (force, torque)
SOLE_SITE = "sole_ft:{}"
GLUE = "glue:"  # a glued sole's weld to the world: this, then the sole frame


NDIntArray = np.ndarray  # integer indices


@dataclass(frozen=True)
class Sensor:
    """Where a 6-axis force/torque sensor's readings are in ``MjData.sensordata``."""

    frame: str  # the frame it reads in
    site: int  # its site's id (at the frame)
    force: slice  # (3,) N
    torque: slice  # (3,) N m


@dataclass(frozen=True)
class Layout:
    """Where the scene's joints, sensors and shapes are in the compiled model.

    Joint arrays are in the scene's joint order (``scene.joint_names``).
    """

    qpos: NDIntArray  # (nj,) index in qpos of each actuated joint (what its encoder reads)
    dof: NDIntArray  # (nj,) index in qvel
    actuator: NDIntArray  # (nj,) actuator id
    springs: tuple[tuple[int, int], ...]  # (scene joint, its spring joint's qpos index)
    effort: FloatArray  # (nj,) N m, the URDF's effort limit (inf: none)
    wrists: dict[str, Sensor]  # chain -> its wrist sensor
    soles: dict[str, Sensor]  # sole frame -> its sensor (the floor's wrench on the sole, in the sole frame)
    shapes: tuple[Shape, ...]  # geom id -> shape
    base_body: int  # the free base's body id
    sole_bodies: dict[str, int]  # sole frame -> body id of its link
    glue: tuple[int, ...] = ()  # the soles' welds to the world (equality ids; glued feet); empty: standing free


@dataclass(frozen=True)
class Built:
    """A compiled model and where things are in it."""

    model: mujoco.MjModel
    layout: Layout


def _positive_inertias(root: ET.Element) -> None:
    """Make every link's inertia positive definite (eigenvalues at least ``MIN_INERTIA``), as MuJoCo requires.

    Some descriptions carry a singular inertia on a light link (iCub's base); pinocchio
    accepts it, MuJoCo does not. Masses and centres of mass are left as they are.
    """
    for inertia in root.iter("inertia"):
        names = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
        xx, xy, xz, yy, yz, zz = (float(inertia.get(n, "0")) for n in names)
        matrix = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        values, vectors = np.linalg.eigh(matrix)
        if values.min() >= MIN_INERTIA:
            continue
        fixed = vectors @ np.diag(np.maximum(values, MIN_INERTIA)) @ vectors.T
        for name, (i, j) in zip(names, ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)), strict=True):
            inertia.set(name, repr(float(fixed[i, j])))


def _weighted_moving_links(root: ET.Element) -> None:
    """Give a massless link that a moving joint moves a speck of mass (``SPECK_KG``), as MuJoCo requires.

    (A link lighter than the speck is given the speck instead.)

    A description may split a ball joint into three hinges through massless links (the
    example-robot-data body models); the joints' rotor inertia carries their dynamics.
    """
    moving = {
        str(child.get("link"))
        for joint in root.findall("joint")
        if joint.get("type") in ("revolute", "continuous", "prismatic") and (child := joint.find("child")) is not None
    }
    speck = repr(SPECK_KG * 1e-4)
    for link in root.findall("link"):
        if link.get("name") not in moving:
            continue
        inertial = link.find("inertial")
        mass = None if inertial is None else inertial.find("mass")
        if mass is not None and float(mass.get("value", "0")) >= SPECK_KG:
            continue
        if inertial is not None:
            link.remove(inertial)
        inertial = ET.SubElement(link, "inertial")
        ET.SubElement(inertial, "mass", value=repr(SPECK_KG))
        ET.SubElement(inertial, "inertia", ixx=speck, ixy="0", ixz="0", iyy=speck, iyz="0", izz=speck)


def _mjcf_urdf(urdf_text: str) -> str:
    """The URDF without visual and collision elements (the geoms are added from posegen's shapes), for MuJoCo."""
    root = ET.fromstring(kinematic_urdf(urdf_text))
    _positive_inertias(root)
    _weighted_moving_links(root)
    extension = ET.SubElement(root, "mujoco")
    ET.SubElement(
        extension,
        "compiler",
        strippath="false",
        fusestatic="false",
        discardvisual="true",
        balanceinertia="true",
        inertiafromgeom="false",
    )
    return ET.tostring(root, encoding="unicode")


def _add_actuators(spec: mujoco.MjSpec, scene: Scene, gains: Gains) -> FloatArray:
    """One position loop per actuated joint (force limited to the effort); returns the efforts (nj,)."""
    efforts = np.full(len(scene.joint_names), np.inf)
    for i, name in enumerate(scene.joint_names):
        joint = spec.joint(name)
        effort = float(scene.model.effortLimit[scene.velocity_indices()[i]])
        joint.armature = gains.armature[i]
        actuator = spec.add_actuator(name=f"act:{name}", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        actuator.gainprm[0] = gains.kp[i]
        actuator.biasprm[:3] = [0.0, -gains.kp[i], -gains.kd[i]]
        actuator.ctrllimited = False
        if effort > 0 and np.isfinite(effort):
            actuator.forcelimited = True
            actuator.forcerange = [-effort, effort]
            efforts[i] = effort
        else:
            actuator.forcelimited = False
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE  # the actuator holds the limit
    return efforts


def _add_springs(spec: mujoco.MjSpec, springs: Mapping[str, float]) -> list[str]:
    """A passive hinge after each compliant joint: same body, axis and origin; stiffness 1 / compliance."""
    names = []
    for name, compliance in springs.items():
        if compliance <= 0:
            continue
        joint = spec.joint(name)
        body = joint.parent
        stiffness = 1.0 / compliance
        spring = body.add_joint(name=f"spring:{name}", type=mujoco.mjtJoint.mjJNT_HINGE)
        spring.axis = joint.axis
        spring.pos = joint.pos
        spring.stiffness = [stiffness, 0.0, 0.0]  # a 3-vector in MuJoCo 4.0: linear term first
        spring.damping = [stiffness * SPRING_DAMPING_S, 0.0, 0.0]
        spring.armature = SPRING_ARMATURE
        names.append(spring.name)
    return names


def _add_sensor_pair(spec: mujoco.MjSpec, site_name: str, body_name: str, pose: FloatArray) -> None:
    """A force and a torque sensor at a site of ``body_name``, placed at ``pose`` (4, 4) in that body."""
    body = spec.body(body_name)
    if body is None:
        raise ConfigError(f"'{body_name}' is not a link of the robot: a force/torque sensor needs one")
    site = body.add_site(name=site_name)
    site.pos = pose[:3, 3]
    site.quat = pin.Quaternion(pose[:3, :3]).coeffs()[[3, 0, 1, 2]]
    for kind, suffix in ((mujoco.mjtSensor.mjSENS_FORCE, "force"), (mujoco.mjtSensor.mjSENS_TORQUE, "torque")):
        sensor = spec.add_sensor(name=f"{site_name}:{suffix}", type=kind, objname=site_name)
        sensor.objtype = mujoco.mjtObj.mjOBJ_SITE


def _options(spec: mujoco.MjSpec) -> None:
    spec.option.timestep = TIMESTEP_S
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.noslip_iterations = NOSLIP_ITERATIONS
    spec.option.gravity = [0.0, 0.0, -9.81]


def build(
    scene: Scene,
    urdf_text: str,
    table_top: FloatArray,
    gains: Gains,
    tools: Mapping[str, Tool],
    springs: Mapping[str, float] | None = None,
    glued_feet: bool = False,
) -> Built:
    """Compile the robot of ``urdf_text`` at the scene's table.

    Args:
        scene: The nominal scene (joints, frames, shapes, foot rectangle, table size).
        urdf_text: The robot's URDF (the nominal one, or a perturbed robot's), the config's
            frames declared in it as links.
        table_top: World pose of the table's top face centre, (4, 4).
        gains: The joint loops and rotor inertias, in the scene's joint order.
        tools: Chain -> where its wrist sensor sits (:func:`posegen.physics.tool.wrist_tool`).
        springs: Joint name -> compliance (rad/N m): a passive spring joint after it.
        glued_feet: Weld each sole's link to the world (:func:`glue_feet` sets where).

    Raises:
        ConfigError: The URDF does not compile, or a sensor frame is not a link.

    Example:
        >>> built = build(scene, scene.urdf_xml, scene.table_pose, joint_gains(scene), tools)

    """
    try:
        spec = mujoco.MjSpec.from_string(_mjcf_urdf(urdf_text))
    except ValueError as exc:
        raise ConfigError(f"MuJoCo cannot read the robot's URDF: {str(exc).strip()}") from exc
    _options(spec)
    base = spec.worldbody.bodies[0]
    base.add_freejoint(name="base")
    shapes = add_shapes(spec, scene, table_top)
    efforts = _add_actuators(spec, scene, gains)
    spring_names = _add_springs(spec, springs or {})
    for chain, tool in tools.items():
        _add_sensor_pair(spec, FT_SITE.format(chain), tool.link, tool.frame_in_link)
    soles = {sole: spec.geom(f"sole:{sole}").parent.name for sole in scene.stance.sole_frames}
    for sole, link in soles.items():
        _add_sensor_pair(spec, SOLE_SITE.format(sole), link, sole_in_link(scene, sole))
    if glued_feet:
        for sole, link in soles.items():
            weld = spec.add_equality(name=GLUE + sole, type=mujoco.mjtEq.mjEQ_WELD, objtype=mujoco.mjtObj.mjOBJ_BODY)
            weld.name1 = link
    try:
        model = spec.compile()
    except ValueError as exc:
        raise ConfigError(f"MuJoCo cannot compile the robot: {str(exc).strip()}") from exc
    return Built(model, _layout(model, scene, shapes, efforts, spring_names, soles, base.name, tools, glued_feet))


def _sensor(model: mujoco.MjModel, site: str, frame: str) -> Sensor:
    force = model.sensor(f"{site}:force")
    torque = model.sensor(f"{site}:torque")
    return Sensor(
        frame,
        model.site(site).id,
        slice(int(force.adr[0]), int(force.adr[0]) + 3),
        slice(int(torque.adr[0]), int(torque.adr[0]) + 3),
    )


def _layout(
    model: mujoco.MjModel,
    scene: Scene,
    shapes: tuple[Shape, ...],
    efforts: FloatArray,
    springs: list[str],
    soles: dict[str, str],
    base: str,
    tools: Mapping[str, Tool],
    glued_feet: bool,
) -> Layout:
    joints = [model.joint(name) for name in scene.joint_names]
    by_geom = {s.name: s for s in shapes}
    ordered = tuple(by_geom[model.geom(g).name] for g in range(model.ngeom))
    spring_qpos = tuple(
        (scene.joint_index(name.split(":", 1)[1]), int(model.joint(name).qposadr[0])) for name in springs
    )
    return Layout(
        qpos=np.array([int(j.qposadr[0]) for j in joints]),
        dof=np.array([int(j.dofadr[0]) for j in joints]),
        actuator=np.array([model.actuator(f"act:{name}").id for name in scene.joint_names]),
        springs=spring_qpos,
        effort=efforts,
        wrists={chain: _sensor(model, FT_SITE.format(chain), tool.frame) for chain, tool in tools.items()},
        soles={sole: _sensor(model, SOLE_SITE.format(sole), link) for sole, link in soles.items()},
        shapes=ordered,
        base_body=model.body(base).id,
        sole_bodies={sole: model.body(link).id for sole, link in soles.items()},
        glue=tuple(int(model.equality(GLUE + sole).id) for sole in soles) if glued_feet else (),
    )


def glue_feet(model: mujoco.MjModel, data: mujoco.MjData, welds: Sequence[int]) -> None:
    """Weld each glued sole where it is now (``data``'s kinematics computed): the welds' relative poses.

    A weld's default relative pose is the one at ``qpos0``; the robot stands elsewhere.
    ``welds``: the soles' welds (:attr:`Layout.glue`); the model's other equalities (a
    URDF's mimic joints) are left as they are.
    """
    for k in welds:
        body = model.eq_obj1id[k]
        rotation = data.xmat[body].reshape(3, 3)
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, rotation.T.ravel())
        model.eq_data[k][0:3] = 0.0  # the anchor: the body's origin
        model.eq_data[k][3:6] = -rotation.T @ data.xpos[body]  # the world's origin in the body
        model.eq_data[k][6:10] = quat  # the world's orientation in the body
        model.eq_data[k][10] = 1.0
