"""The converted URDF against MuJoCo's own reading of random MJCF robots (not pinocchio's).

pinocchio's MJCF parser read five things otherwise than MuJoCo, each found here: a
joint's ``ref`` (its zero at the pose as written), a slide's range under ``angle="degree"``
(converted as an angle), a ``pos`` from a class (skipped, for joints and geoms), a body's
``childclass`` laid over an element's own ``class``, and an upper-case ``eulerseq``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from posegen.draft.mjcf import convert_mjcf
from tests.draft.random_mjcf import RandomMjcf

mujoco = pytest.importorskip("mujoco")

MODELS = 40  # random robots (about 20 ms each)
POSTURES = 3  # random joint values per robot
TOL = 1e-9  # m, and in rotation
SHAPES = {  # MuJoCo geom type -> the collision shape the URDF carries, its number of sizes, and of shapes
    int(mujoco.mjtGeom.mjGEOM_SPHERE): ("Sphere", 1, 1),
    int(mujoco.mjtGeom.mjGEOM_BOX): ("Box", 3, 1),
    int(mujoco.mjtGeom.mjGEOM_CYLINDER): ("Cylinder", 2, 1),
    int(mujoco.mjtGeom.mjGEOM_CAPSULE): ("Cylinder", 2, 3),  # a cylinder and two spheres
}


def _converted(seed: int, folder: Path) -> tuple[object, pin.Model, pin.GeometryModel]:
    path = folder / f"random_{seed}.xml"
    path.write_text(RandomMjcf(seed).text())
    native = mujoco.MjModel.from_xml_path(str(path))
    urdf = folder / f"random_{seed}.urdf"
    urdf.write_text(convert_mjcf(path).text)
    model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    return native, model, pin.buildGeomFromUrdf(model, str(urdf), pin.GeometryType.COLLISION)


def _name(native: object, kind: object, index: int) -> str:
    return str(mujoco.mj_id2name(native, kind, index))


def _same_posture(native: object, data: object, model: pin.Model, rng: np.random.Generator) -> np.ndarray:
    """Random joint values within MuJoCo's ranges set in both models (the root where MuJoCo has it)."""
    data.qpos[:] = native.qpos0
    q = pin.neutral(model)
    for j in range(1, native.njnt):  # joint 0: the free root
        name = _name(native, mujoco.mjtObj.mjOBJ_JOINT, j)
        low, high = native.jnt_range[j]
        index = model.joints[model.getJointId(name)].idx_q
        assert (model.lowerPositionLimit[index], model.upperPositionLimit[index]) == pytest.approx((low, high)), name
        data.qpos[native.jnt_qposadr[j]] = q[index] = rng.uniform(low, high)
    mujoco.mj_kinematics(native, data)
    q[:3], q[3:7] = data.xpos[1], np.roll(data.xquat[1], -1)  # MuJoCo's (w, x, y, z) as (x, y, z, w)
    return q


def _size(geometry: object) -> tuple[float, ...]:
    """A coal shape's MuJoCo size: radius; half sides; radius and half length."""
    kind = type(geometry).__name__
    if kind == "Sphere":
        return (geometry.radius,)
    if kind == "Box":
        return tuple(geometry.halfSide)
    return (geometry.radius, geometry.halfLength)


def _check_shapes(native: object, data: object, model: pin.Model, collision: pin.GeometryModel, q: np.ndarray) -> None:
    """Each colliding geom a shape of its type and size at its world place; visual ones none of their own."""
    placed = collision.createData()
    pin.updateGeometryPlacements(model, model.createData(), collision, placed, q)
    shapes = [
        (type(obj.geometry).__name__, placed.oMg[k].translation, _size(obj.geometry))
        for k, obj in enumerate(collision.geometryObjects)
    ]
    expected = 0
    for g in range(native.ngeom):
        if not (native.geom_contype[g] or native.geom_conaffinity[g]):
            continue
        kind, sizes, count = SHAPES[int(native.geom_type[g])]
        size = native.geom_size[g][:sizes]
        expected += count
        assert any(
            s[0] == kind and np.abs(s[1] - data.geom_xpos[g]).max() < TOL and np.allclose(s[2], size, atol=TOL)
            for s in shapes
        ), _name(native, mujoco.mjtObj.mjOBJ_GEOM, g)
    assert len(shapes) == expected  # no visual geom among the collision shapes


@pytest.mark.parametrize("seed", range(MODELS))
def test_every_body_limit_and_collision_shape_is_where_mujoco_puts_it(seed, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # a MuJoCo warning goes to MUJOCO_LOG.TXT in the working folder
    native, model, collision = _converted(seed, tmp_path)
    data = mujoco.MjData(native)
    rng = np.random.default_rng(seed)
    for _ in range(POSTURES):
        q = _same_posture(native, data, model, rng)
        placed = model.createData()
        pin.framesForwardKinematics(model, placed, q)
        for b in range(1, native.nbody):
            frame = placed.oMf[model.getFrameId(_name(native, mujoco.mjtObj.mjOBJ_BODY, b))]
            assert np.abs(frame.translation - data.xpos[b]).max() < TOL, b
            assert np.abs(frame.rotation - data.xmat[b].reshape(3, 3)).max() < TOL, b
        _check_shapes(native, data, model, collision, q)
