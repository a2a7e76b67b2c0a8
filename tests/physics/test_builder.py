"""The MuJoCo model: the URDF's robot (masses, CoM, frames as pinocchio has them), the perturbed robot's
kinematics as the calibration model has them, compliance the encoders do not see, and only the
experiment's contacts kept."""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin

from posegen.physics.builder import Built, glue_feet
from posegen.physics.geometry import ShapeRole, Touches
from posegen.physics.stance import put_down
from posegen.physics.true_robot import TrueRobot
from posegen.robot import Scene

TOLERANCE = 1e-9


def _postures(scene: Scene, count: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    span = scene.upper - scene.lower
    return scene.lower + span * rng.uniform(0.1, 0.9, (count, len(scene.joint_names)))


def _set(built: Built, data: mujoco.MjData, q: np.ndarray, scene: Scene) -> None:
    """The pinocchio configuration q (nq,) in MuJoCo's state (free base x, y, z, w, x, y, z; actuated joints)."""
    data.qpos[:] = built.model.qpos0
    data.qpos[:3] = q[:3]
    data.qpos[3:7] = q[[6, 3, 4, 5]]
    data.qpos[built.layout.qpos] = scene.joints_of(q)
    mujoco.mj_kinematics(built.model, data)
    mujoco.mj_comPos(built.model, data)


def test_masses_centre_of_mass_and_frames_are_pinocchio_s(scene: Scene, nominal: Built) -> None:
    model, pmodel = nominal.model, scene.model
    pdata = pmodel.createData()
    data = mujoco.MjData(model)
    assert abs(model.body_subtreemass[nominal.layout.base_body] - pin.computeTotalMass(pmodel)) < TOLERANCE
    links = [str(f.name) for f in pmodel.frames if f.type == pin.FrameType.BODY and model.body(str(f.name)).id >= 0]
    assert len(links) > 40
    for joints in _postures(scene, 5, 1):
        q = scene.configuration(joints)
        _set(nominal, data, q, scene)
        pin.framesForwardKinematics(pmodel, pdata, q)
        com = pin.centerOfMass(pmodel, pdata, q)
        assert np.abs(data.subtree_com[nominal.layout.base_body] - com).max() < TOLERANCE
        for link in links:
            body = model.body(link).id
            placement = pdata.oMf[pmodel.getFrameId(link)]
            assert np.abs(data.xpos[body] - placement.translation).max() < TOLERANCE, link
            assert np.abs(data.xmat[body].reshape(3, 3) - placement.rotation).max() < TOLERANCE, link


def _contact_in_sole(built: Built, data: mujoco.MjData, chain: str, sole: str) -> np.ndarray:
    """The flush contact frame's origin (3,) from the tip spheres, in a sole's site frame."""
    layout = built.layout
    tips = [i for i, s in enumerate(layout.shapes) if s.role == ShapeRole.TIP and s.chain == chain]
    site = layout.soles[sole].site
    rotation, origin = data.site_xmat[site].reshape(3, 3), data.site_xpos[site]
    radius = built.model.geom_size[tips[0]][0]
    centres = np.array([data.geom_xpos[i] for i in tips])
    normal = np.cross(centres[1] - centres[0], centres[2] - centres[0])
    normal /= np.linalg.norm(normal)
    if normal @ (data.xpos[built.model.geom_bodyid[tips[0]]] - centres.mean(axis=0)) < 0:
        normal = -normal  # toward the gripper, as the contact frame's z
    return rotation.T @ (centres.mean(axis=0) - radius * normal - origin)


def test_the_perturbed_robot_is_the_truth_s_kinematics(scene: Scene, perturbed: Built, true_robot: TrueRobot) -> None:
    """At random angles, the encoders' angles through the true parameters (placements, zero offsets
    included) put each contact frame where the tip spheres of the MuJoCo robot are."""
    model, x = true_robot.model, true_robot.x
    theta = model.theta(x)
    data = mujoco.MjData(perturbed.model)
    for joints in _postures(scene, 4, 2):
        data.qpos[:] = perturbed.model.qpos0
        data.qpos[perturbed.layout.qpos] = joints
        mujoco.mj_kinematics(perturbed.model, data)
        for chain in scene.chains:
            chain_model = model.contact.chains[chain.name]
            kind = chain.contact_kind
            elements, tip = chain_model.transforms(
                joints[None],
                model.contact._placements(theta, chain_model),
                theta[model.contact.tip_columns(chain.name, kind)],
                kind=kind,
            )
            frame = np.eye(4)
            for element in elements:
                frame = frame @ element[0]
            expected = (frame @ tip)[:3, 3]
            assert np.abs(_contact_in_sole(perturbed, data, chain.name, chain.sole_frame) - expected).max() < TOLERANCE


def test_compliance_is_a_spring_behind_the_encoder(scene: Scene, perturbed: Built, true_robot: TrueRobot) -> None:
    layout, model = perturbed.layout, perturbed.model
    assert true_robot.springs and {scene.joint_names[j] for j, _ in layout.springs} == set(true_robot.springs)
    encoders = set(layout.qpos.tolist())
    data = mujoco.MjData(model)
    for joint, address in layout.springs:
        assert address not in encoders  # the encoder reads the actuated joint, not its spring
        spring = model.jnt_qposadr.tolist().index(address)
        data.qpos[:] = model.qpos0
        data.qpos[address] = 0.01  # the link turned 10 mrad past its drive
        mujoco.mj_forward(model, data)
        torque = data.qfrc_spring[model.jnt_dofadr[spring]]
        assert abs(torque + 0.01 / true_robot.springs[scene.joint_names[joint]]) < 1e-6  # -delta / compliance


def test_only_the_experiment_s_contacts_are_kept(scene: Scene, nominal: Built) -> None:
    model, layout = nominal.model, nominal.layout
    floor_links = {"leg_left_6_link", "leg_right_6_link", "left_sole_link", "right_sole_link"}
    for g, shape in enumerate(layout.shapes):
        if shape.role in (ShapeRole.FLOOR, ShapeRole.TABLE):
            assert model.geom_conaffinity[g] == 0 and model.geom_contype[g] in (Touches.FLOOR, Touches.TABLE)
            continue
        assert model.geom_contype[g] == 0  # a robot shape never touches another
        touches = Touches(int(model.geom_conaffinity[g]))
        if shape.role == ShapeRole.SOLE:
            assert touches == Touches.FLOOR
        elif shape.role == ShapeRole.TIP:
            assert touches == Touches.TABLE
        elif shape.link in floor_links:
            assert Touches.FLOOR not in touches
        elif "fingertip" in shape.link:
            assert Touches.TABLE not in touches
        else:
            assert touches == Touches.FLOOR | Touches.TABLE, shape.link


def test_put_down_lays_both_soles_flat_and_glued_feet_stay(scene: Scene, gains, tools, true_robot: TrueRobot) -> None:
    from posegen.physics.builder import build

    built = build(scene, true_robot.urdf, true_robot.table_top, gains, tools, glued_feet=True)
    data = mujoco.MjData(built.model)
    put_down(scene, built.model, data, built.layout, scene.reference)
    sites = [s.site for s in built.layout.soles.values()]
    for site in sites:
        assert abs(data.site_xpos[site][2]) < 1e-9 and np.abs(data.site_xmat[site].reshape(3, 3)[2, :2]).max() < 1e-9
    assert len(built.layout.glue) == len(scene.stance.sole_frames)
    glue_feet(built.model, data, built.layout.glue)
    before = [data.site_xpos[s].copy() for s in sites]
    data.ctrl[built.layout.actuator] = data.qpos[built.layout.qpos]
    for _ in range(250):
        mujoco.mj_step(built.model, data)
    assert max(np.abs(data.site_xpos[s] - b).max() for s, b in zip(sites, before, strict=True)) < 2e-3


def test_a_robot_with_mimic_joints_and_declared_tips() -> None:
    """JVRC-1's fingers are mimic joints (MuJoCo joint equalities): standing free, its stabilizer stays on.

    ``Run`` once took any equality for the soles' welds, and the stabilizer rested for good.
    Its contact points are frames the config declares: the physics once exempted their own
    bodies (which carry no shape) from the table, not the finger links they are fixed to.
    """
    from pathlib import Path

    from posegen.physics.builder import build
    from posegen.physics.gains import joint_gains
    from posegen.physics.run import Run
    from posegen.physics.sensors import SensorNoise, Sensors
    from posegen.physics.tool import wrist_tool
    from posegen.robot import load_config
    from tests.physics.test_stabilizer import standing_plan

    jvrc = Scene(load_config(Path(__file__).resolve().parents[2] / "configs" / "jvrc_table.yaml"))
    tools = {c.name: wrist_tool(jvrc, c.sensor_frame) for c in jvrc.chains}
    gains = joint_gains(jvrc)
    free = build(jvrc, jvrc.urdf_xml, jvrc.table_pose, gains, tools)
    mimic = [k for k in range(free.model.neq) if free.model.eq_type[k] == mujoco.mjtEq.mjEQ_JOINT]
    assert mimic and free.layout.glue == ()  # equalities there are, welds none
    glued = build(jvrc, jvrc.urdf_xml, jvrc.table_pose, gains, tools, glued_feet=True)
    assert len(glued.layout.glue) == 2 and not set(glued.layout.glue) & set(mimic)
    # its point contacts are frames the config declares on the little fingers: those links
    # may touch the table (as the planner's collision check has them), their tip spheres make the contact
    for g, shape in enumerate(free.layout.shapes):
        if shape.role == ShapeRole.BODY and shape.link in ("L_LLITTLE_S", "R_LLITTLE_S"):
            assert Touches.TABLE not in Touches(int(free.model.geom_conaffinity[g])), shape.name
    tips = {s.link for s in free.layout.shapes if s.role == ShapeRole.TIP}
    assert tips == {"left_tip", "right_tip"}
    plan = standing_plan(jvrc, 0.1)
    for built, stands_free in ((free, True), (glued, False)):
        run = Run(jvrc, built, gains, plan, (), Sensors(built.layout, SensorNoise(), 1), tools, 30.0, 1)
        assert run.stabilizer.glued_feet is not stands_free  # the stabilizer balances a robot standing free
    data = mujoco.MjData(glued.model)
    mujoco.mj_forward(glued.model, data)
    before = glued.model.eq_data[mimic].copy()
    glue_feet(glued.model, data, glued.layout.glue)
    assert np.array_equal(glued.model.eq_data[mimic], before)  # the fingers' couplings untouched
