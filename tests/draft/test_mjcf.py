"""An MJCF humanoid converted to URDF: the kinematics, limits, masses and collision shapes pinocchio reads from it."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest

from posegen.draft.mjcf import convert_mjcf, is_mjcf
from posegen.errors import ConfigError
from tests.draft.humanoid_mjcf import MULTI_JOINT_BODIES, humanoid_mjcf

RNG_SEED = 7


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    """The MJCF model and geometry as pinocchio reads them, and those of the converted URDF."""
    folder = tmp_path_factory.mktemp("mjcf")
    path = humanoid_mjcf(folder)
    converted = convert_mjcf(path)
    urdf = folder / "robot.urdf"
    urdf.write_text(converted.text)
    mjcf_model = pin.buildModelFromMJCF(str(path))
    urdf_model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    geometry = {
        "mjcf": pin.buildGeomFromMJCF(mjcf_model, str(path), pin.GeometryType.COLLISION),
        "urdf": pin.buildGeomFromUrdf(urdf_model, str(urdf), pin.GeometryType.COLLISION),
        "mjcf_visual": pin.buildGeomFromMJCF(mjcf_model, str(path), pin.GeometryType.VISUAL),
        "urdf_visual": pin.buildGeomFromUrdf(urdf_model, str(urdf), pin.GeometryType.VISUAL),
    }
    return mjcf_model, urdf_model, geometry, converted


def _mjcf_joint_names(model: pin.Model) -> list[list[str]]:
    """The names of the hinges of each MJCF pinocchio joint, composite ones from the fixture's table."""
    names = []
    for j in range(model.njoints):
        owner = next((f.name for f in model.frames if f.type == pin.FrameType.BODY and f.parentJoint == j), "")
        names.append(MULTI_JOINT_BODIES.get(owner, [str(model.names[j])]))
    return names


def _same_configuration(mjcf: pin.Model, urdf: pin.Model, q_urdf: np.ndarray) -> np.ndarray:
    """The MJCF model's configuration with the URDF's joint values, matched by joint name."""
    q = pin.neutral(mjcf)
    q[:7] = q_urdf[:7]
    for j, names in enumerate(_mjcf_joint_names(mjcf)):
        if j < 2:
            continue
        for k, name in enumerate(names):
            q[mjcf.joints[j].idx_q + k] = q_urdf[urdf.joints[urdf.getJointId(name)].idx_q]
    return q


def _random_configuration(model: pin.Model, rng: np.random.Generator) -> np.ndarray:
    q = pin.neutral(model)
    q[7:] = rng.uniform(model.lowerPositionLimit[7:], model.upperPositionLimit[7:])
    q[:3] = rng.normal(size=3)
    q[3:7] = pin.Quaternion(pin.SE3.Random().rotation).coeffs()
    return q


def test_every_body_is_where_the_mjcf_puts_it(models):
    mjcf, urdf, _, _ = models
    bodies = [f.name for f in mjcf.frames if f.type == pin.FrameType.BODY]
    assert {"camera", "head", "l_foot", "r_upper_arm"} <= set(bodies)  # a welded body, a joint off its body's origin
    rng = np.random.default_rng(RNG_SEED)
    d_mjcf, d_urdf = mjcf.createData(), urdf.createData()
    for _ in range(10):
        q_urdf = _random_configuration(urdf, rng)
        pin.framesForwardKinematics(urdf, d_urdf, q_urdf)
        pin.framesForwardKinematics(mjcf, d_mjcf, _same_configuration(mjcf, urdf, q_urdf))
        root_mjcf = d_mjcf.oMf[mjcf.getFrameId("pelvis")].inverse()  # the MJCF root is placed at 1 m: dropped
        root_urdf = d_urdf.oMf[urdf.getFrameId("pelvis")].inverse()
        for body in bodies:
            expected = root_mjcf * d_mjcf.oMf[mjcf.getFrameId(body, pin.FrameType.BODY)]
            found = root_urdf * d_urdf.oMf[urdf.getFrameId(body, pin.FrameType.BODY)]
            assert np.abs(found.homogeneous - expected.homogeneous).max() < 1e-9, body


def test_several_joints_of_one_body_become_a_chain_and_the_free_root_is_dropped(models):
    mjcf, urdf, _, _ = models
    composites = [j for j in range(mjcf.njoints) if mjcf.joints[j].shortname() == "JointModelComposite"]
    assert len(composites) == len(MULTI_JOINT_BODIES)  # pinocchio reads each multi-hinge body as one joint
    hinges = (
        sum(len(n) for n in MULTI_JOINT_BODIES.values()) + 2 * (1 + 1 + 1) + 2
    )  # + knees, elbows, wrists, waist, neck
    assert urdf.njoints == 2 + hinges and urdf.nq == 7 + hinges  # the URDF's own root, then one revolute per hinge
    assert "root" not in list(urdf.names)
    for names in MULTI_JOINT_BODIES.values():
        chain = [urdf.getJointId(n) for n in names]
        assert [urdf.parents[j] for j in chain[1:]] == chain[:-1]  # one after the other
        assert all(urdf.inertias[j].mass == 0.0 for j in chain[:-1])  # through massless links
        assert all(urdf.joints[j].nq == 1 for j in chain)


def test_limits_and_masses_are_the_mjcf_ones(models, tmp_path):
    mjcf, urdf, _, _ = models
    text = ET.parse(humanoid_mjcf(tmp_path)).getroot()
    for element in text.iter("joint"):  # the ranges as the MJCF text gives them
        low, high = (float(v) for v in element.get("range", "").split())
        j = urdf.getJointId(element.get("name"))
        assert (urdf.lowerPositionLimit[urdf.joints[j].idx_q], urdf.upperPositionLimit[urdf.joints[j].idx_q]) == (
            low,
            high,
        )
    assert pin.computeTotalMass(urdf) == pytest.approx(pin.computeTotalMass(mjcf), abs=1e-12)
    assert pin.computeTotalMass(urdf) == pytest.approx(sum(float(e.get("mass")) for e in text.iter("inertial")))
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(5):  # gravity torques: every mass and centre of mass where the MJCF has it
        q_urdf = _random_configuration(urdf, rng)
        q_mjcf = _same_configuration(mjcf, urdf, q_urdf)
        g_urdf = pin.computeGeneralizedGravity(urdf, urdf.createData(), q_urdf)
        g_mjcf = pin.computeGeneralizedGravity(mjcf, mjcf.createData(), q_mjcf)
        assert np.abs(g_urdf[:6] - g_mjcf[:6]).max() < 1e-9
        for j, names in enumerate(_mjcf_joint_names(mjcf)[2:], start=2):
            for k, name in enumerate(names):
                assert g_urdf[urdf.joints[urdf.getJointId(name)].idx_v] == pytest.approx(
                    g_mjcf[mjcf.joints[j].idx_v + k], abs=1e-9
                )


def _distances(model: pin.Model, geometry: pin.GeometryModel, q: np.ndarray, point: np.ndarray) -> dict[str, float]:
    """The distance (m) from a point to each link's collision geometry (the nearest of its shapes)."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    probe, placement = coal.Sphere(1e-6), coal.Transform3s(np.eye(3), point)
    out: dict[str, float] = {}
    for obj in geometry.geometryObjects:
        world = data.oMi[obj.parentJoint] * obj.placement
        result = coal.DistanceResult()
        coal.distance(
            obj.geometry,
            coal.Transform3s(world.rotation, world.translation),
            probe,
            placement,
            coal.DistanceRequest(),
            result,
        )
        link = model.frames[obj.parentFrame].name
        out[link] = min(out.get(link, np.inf), result.min_distance)
    return out


def test_capsules_boxes_and_spheres_cover_the_same_space(models):
    mjcf, urdf, geometry, _ = models
    kinds = sorted(type(o.geometry).__name__ for o in geometry["urdf"].geometryObjects)
    capsules = sum(type(o.geometry).__name__ == "Capsule" for o in geometry["mjcf"].geometryObjects)
    assert capsules == 8 and "Capsule" not in kinds and kinds.count("Cylinder") == capsules
    assert len(kinds) == len(geometry["mjcf"].geometryObjects) + 2 * capsules  # a cylinder and two spheres each
    assert len(geometry["urdf_visual"].geometryObjects) == len(kinds) + 1  # and the camera, visual only
    rng = np.random.default_rng(RNG_SEED)
    q_urdf = _random_configuration(urdf, rng)
    q_urdf[:7] = pin.neutral(urdf)[:7]
    q_mjcf = _same_configuration(mjcf, urdf, q_urdf)
    q_mjcf[:3] = [0.0, 0.0, 0.0]  # the MJCF root's own placement (1 m up) puts it where the URDF's is
    q_mjcf[2] -= mjcf.jointPlacements[1].translation[2]
    for point in rng.uniform([-0.4, -0.5, -1.0], [0.4, 0.5, 0.6], size=(60, 3)):
        expected = _distances(mjcf, geometry["mjcf"], q_mjcf, point)
        found = _distances(urdf, geometry["urdf"], q_urdf, point)
        assert found.keys() == expected.keys()
        for link, distance in expected.items():
            if distance > 1e-3:  # outside: the distance to a union is the nearest part's
                assert found[link] == pytest.approx(distance, abs=1e-9), link


def test_what_is_not_carried_is_listed(models, tmp_path):
    *_, converted = models
    unseen = "1 body with visual-only geoms and no <inertial> (MuJoCo counts their mass, pinocchio does not)"
    assert converted.dropped == ("1 actuator", "1 site", unseen, "1 worldbody geom (floor, scenery)")  # the camera
    path = humanoid_mjcf(tmp_path)
    path.write_text(
        path.read_text().replace(
            'type="sphere" pos="0 0 0.1" size="0.08"', 'type="ellipsoid" pos="0 0 0.1" size="0.08 0.07 0.09"'
        )
    )
    text = path.read_text().replace('contype="0" conaffinity="0" group="1"', 'contype="0" conaffinity="0" density="0"')
    path.write_text(text)  # the camera weighs nothing: nothing for pinocchio to leave out
    dropped = convert_mjcf(path).dropped
    assert not [d for d in dropped if "visual-only" in d]
    assert "1 visual ellipsoid geoms (head)" in dropped and "1 collision ellipsoid geoms (head)" in dropped
    assert is_mjcf(path) and not is_mjcf(tmp_path / "none.xml")


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda t: t[:-30], r"robot\.xml: not valid XML"),
        (
            lambda t: t.replace('<joint name="l_wrist" axis="0 1 0"', '<joint name="l_wrist" type="ball"'),
            r"robot\.xml: joint 'l_wrist' is a ball joint",
        ),
        (lambda t: t.replace('<freejoint name="root"/>', ""), r"robot\.xml: root body 'pelvis' has no <freejoint>"),
        (
            lambda t: t.replace("</worldbody>", '<body name="box"><freejoint/><geom size="0.1"/></body></worldbody>'),
            r"robot\.xml: a second body 'box' in <worldbody>",
        ),
        (
            lambda t: t.replace(
                '<joint name="l_elbow"', '<joint name="l_elbow" type="slide" range="0 1"/><joint name="x"'
            ),
            None,
        ),
        (
            lambda t: t.replace("<worldbody>", '<worldbody><include file="nothing.xml"/>'),
            r"robot\.xml: <include file=\"nothing\.xml\"> not found",
        ),
    ],
)
def test_bad_mjcf_is_one_line_naming_the_file_and_element(edit, message, tmp_path):
    path = humanoid_mjcf(tmp_path)
    path.write_text(edit(path.read_text()))
    if message is None:  # a slide joint is carried as a prismatic one
        assert '<joint name="l_elbow" type="prismatic"' in convert_mjcf(path).text
        return
    with pytest.raises(ConfigError, match=message) as error:
        convert_mjcf(path)
    assert len(str(error.value).splitlines()) == 1
    assert str(Path(path).resolve()) in str(error.value)


def _with_mesh_foot(folder: Path) -> Path:
    """The fixture with its left foot a mesh (an STL box, scaled) instead of a box."""
    import trimesh

    path = humanoid_mjcf(folder)
    trimesh.creation.box(extents=(0.22, 0.10, 0.02)).export(folder / "foot.stl")
    text = path.read_text().replace("<worldbody>", '<asset><mesh file="foot.stl" scale="1 1 2"/></asset><worldbody>', 1)
    start = text.index('<body name="l_foot"')
    box = text.index('<geom type="box"', start)
    path.write_text(
        text[:box] + '<geom type="mesh" mesh="foot" pos="0.03 0 -0.06"/>' + text[text.index("/>", box) + 2 :]
    )
    return path


def test_a_mesh_is_carried_where_the_mjcf_puts_it(tmp_path):
    path = _with_mesh_foot(tmp_path)
    urdf = tmp_path / "robot.urdf"
    urdf.write_text(convert_mjcf(path).text)
    mjcf_model = pin.buildModelFromMJCF(str(path))
    urdf_model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    mjcf_geometry = pin.buildGeomFromMJCF(mjcf_model, str(path), pin.GeometryType.COLLISION)
    urdf_geometry = pin.buildGeomFromUrdf(urdf_model, str(urdf), pin.GeometryType.COLLISION)
    vertices = {}
    for name, model, geometry in (("mjcf", mjcf_model, mjcf_geometry), ("urdf", urdf_model, urdf_geometry)):
        data = model.createData()
        q = pin.neutral(model)
        q[2] = -model.jointPlacements[1].translation[2]  # both roots at the origin
        pin.framesForwardKinematics(model, data, q)
        (mesh,) = [o for o in geometry.geometryObjects if type(o.geometry).__name__ == "BVHModelOBBRSS"]
        local = np.asarray(mesh.geometry.vertices())  # (n, 3), scaled
        world = data.oMi[mesh.parentJoint] * mesh.placement
        vertices[name] = local @ world.rotation.T + world.translation
    assert np.ptp(vertices["urdf"], axis=0) == pytest.approx([0.22, 0.10, 0.04])  # the MJCF's scale is carried
    assert np.abs(vertices["urdf"] - vertices["mjcf"]).max() < 1e-9
    (folder := tmp_path / "moved").mkdir()
    moved = folder / "robot.xml"
    moved.write_text(path.read_text())  # the model without its mesh file
    with pytest.raises(ConfigError, match=r"robot\.xml: mesh 'foot' file 'foot\.stl' not found in"):
        convert_mjcf(moved)
