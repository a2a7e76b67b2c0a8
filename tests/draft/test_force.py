"""The press a draft asks of weak wrists, and the stance it finds when the SRDF's is not balanced (iCub)."""

import numpy as np
import pinocchio as pin
import pytest

from posegen.draft import write_draft
from posegen.draft.force import DEFAULT_FORCE_N, EFFORT_RATIO, POSTURES, PRESS_SHARE, SEED, held_force
from posegen.draft.source import load_draft_source
from posegen.pool import generate_pool
from posegen.robot import load_config


@pytest.fixture(scope="module")
def icub(tmp_path_factory):
    """example-robot-data's iCub with its SRDF: wrists of 0.45-0.65 N m, a ``half_sitting`` on the polygon's edge."""
    path = tmp_path_factory.mktemp("icub") / "icub.yaml"
    return write_draft("icub", str(path), samples=40), path


def test_an_unbalanced_srdf_state_gives_way_to_the_drafts_own_stance(icub):
    """Before, the draft kept ``half_sitting`` (CoM 0.4 mm outside the soles' polygon) and did not load."""
    draft, _ = icub
    assert draft.reference_posture == "" and draft.reference_joints
    assert any(c.startswith("the SRDF's state 'half_sitting' is not balanced") for c in draft.checks)
    assert draft.notes[-1].startswith("the draft loads as a scene")


def test_weak_wrists_get_a_lighter_press_and_the_draft_finds_a_pool(icub):
    """At posegen's 30 N no sample converged within the wrists' torques: the pool found nothing in 256."""
    draft, path = icub
    config = load_config(path)
    assert draft.contact_force_n is not None and 1.0 <= draft.contact_force_n < DEFAULT_FORCE_N
    assert config.route.contact_force_n == draft.contact_force_n
    assert config.recording.force_threshold_n == draft.contact_force_n / 2
    pool = generate_pool(config, 10, seed=0)
    assert len(pool.postures) == 10


def test_the_press_is_half_what_the_weakest_joint_holds_by_pinocchios_jacobians(icub):
    """At the draft's postures, each arm joint's median lever ``|J^T n|`` (pinocchio's point Jacobians) gives
    the force it holds; the draft presses half of the least, and names that joint."""
    draft, _ = icub
    src = load_draft_source("icub", None, ())
    model = src.model
    q = pin.neutral(model)
    q[:7] = [0, 0, 0, 0, 0, 0, 1]
    for name, value in draft.reference_joints.items():
        q[model.joints[model.getJointId(name)].idx_q] = value
    arms = [(c.joints, c.contact.frames, c.contact.flush) for c in draft.chains]
    held = held_force(model, q, arms)
    assert held.force_n == draft.contact_force_n
    holds: dict[str, float] = {}  # N, what each arm joint holds at its median lever
    for joints, frames, flush in arms:
        ids = [model.getJointId(n) for n in joints]
        added = [
            model.addFrame(
                pin.Frame(f.name, model.frames[model.getFrameId(f.parent)].parentJoint, model.getFrameId(f.parent),
                          model.frames[model.getFrameId(f.parent)].placement
                          * pin.SE3(pin.rpy.rpyToMatrix(*np.deg2rad(f.rpy_deg)), np.array(f.xyz_m)), pin.OP_FRAME)
            )
            for f in frames
        ]  # fmt: skip
        data = model.createData()
        pin.framesForwardKinematics(model, data, q)
        hand = data.oMf[model.getFrameId(frames[0].parent)].rotation
        up = np.array([0.0, 0.0, 1.0])
        normal = hand.T @ up  # (3,) a flush contact's normal in the hand's frame: its up at the reference
        rng = np.random.default_rng(SEED)
        index = [model.joints[j].idx_q for j in ids]
        torques = np.zeros((POSTURES, len(ids)))  # N m per newton, the largest over the contact points
        for s in range(POSTURES):
            posture = q.copy()
            posture[index] = rng.uniform(model.lowerPositionLimit[index], model.upperPositionLimit[index])
            pin.computeJointJacobians(model, data, posture)
            pin.updateFramePlacements(model, data)
            hand_now = data.oMf[model.getFrameId(frames[0].parent)].rotation
            n = hand_now @ normal if flush else data.oMf[added[0]].rotation @ up  # (3,) world
            for f in added:
                jacobian = pin.getFrameJacobian(model, data, f, pin.LOCAL_WORLD_ALIGNED)[:3]  # (3, nv)
                per_newton = np.abs(jacobian.T @ n)[[model.joints[j].idx_v for j in ids]]
                torques[s] = np.maximum(torques[s], per_newton)
        median = np.median(torques, axis=0)  # (len(ids),) m, the median lever by pinocchio
        efforts = model.effortLimit[[model.joints[j].idx_v for j in ids]]  # (len(ids),) N m, every one given
        holds.update(zip(joints, EFFORT_RATIO * efforts / median, strict=True))
    weakest = min(holds, key=holds.__getitem__)
    assert holds[weakest] < DEFAULT_FORCE_N  # iCub's wrists cannot hold the default press at a median posture
    assert (held.joint, held.holds_n) == (weakest, pytest.approx(holds[weakest], rel=1e-9))
    assert held.force_n == np.floor(PRESS_SHARE * holds[weakest])
