"""An MJCF (MuJoCo) humanoid as a URDF: the kinematics, inertias and geometry pinocchio reads from it.

posegen's stages read a URDF (placo, collision, the calibrated URDF's exporter), so
``posegen robot init`` converts an MJCF model to URDF text with :func:`convert_mjcf`:

* each body becomes a link of its name with its geoms; the body holding a joint carries
  the joint's inertia (pinocchio's, which includes the bodies welded to it);
* a body with several joints (a pinocchio composite joint) becomes a chain of URDF
  joints through massless links named ``<joint>_link``;
* a body whose frame is not its joint's frame (an MJCF joint ``pos``) is fixed to a
  massless link ``<joint>_link`` at the joint; a body welded to a moving one (no joint)
  is fixed where pinocchio places it;
* the root body's free joint is dropped (posegen floats the root itself); a ball joint
  or a second body in ``<worldbody>`` (which pinocchio passes over) is refused;
* boxes, spheres, cylinders and meshes become URDF visuals and collisions; a capsule
  becomes a cylinder and two spheres (URDF has no capsule); ellipsoids, planes and
  height fields are not carried, nor are actuators, tendons, equality constraints,
  sensors, sites, contact exclusions and keyframes: :attr:`MjcfUrdf.dropped` lists them.

Joint names come from pinocchio, and for the joints of a composite from the MJCF's
``<joint>`` elements of that body (``<body>_joint<k>`` when unnamed). Infinite limits
are written as ``continuous`` joints and infinite speeds or efforts as 0 (URDF has no
infinity).
"""

from __future__ import annotations

import dataclasses
import hashlib
import tempfile
import xml.etree.ElementTree as ET
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from posegen.draft.mjcf_checks import check_elements, check_numbers
from posegen.draft.mjcf_joints import MjcfJoint, body_joints
from posegen.draft.mjcf_text import flattened_mjcf
from posegen.errors import ConfigError
from posegen.io import native_output

MJCF_ROOT = "mujoco"
_IDENTITY_TOL = 1e-12
_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}
_NOTHING_WRITTEN = MjcfJoint("", 0.0, None)  # a joint whose MJCF element is not told apart: pinocchio's reading
_NOT_CARRIED = ("actuator", "tendon", "equality", "sensor", "contact", "keyframe")  # top-level sections


@dataclass(frozen=True)
class MjcfUrdf:
    """An MJCF model converted to a URDF."""

    mjcf: Path  # the MJCF file (absolute)
    sha256: str  # of the MJCF file's bytes
    text: str  # the URDF
    dropped: tuple[str, ...]  # what the URDF does not carry, e.g. "2 ellipsoid geoms (a body name)", "12 actuators"


def is_mjcf(path: Path) -> bool:
    """Whether ``path`` is an XML file whose root element is ``<mujoco>`` (False if it is not XML).

    Example:
        >>> is_mjcf(Path("humanoid.xml")), is_mjcf(Path("robot.urdf"))  # doctest: +SKIP
        (True, False)

    """
    try:
        return ET.parse(path).getroot().tag == MJCF_ROOT
    except (ET.ParseError, OSError):
        return False


def convert_mjcf(path: str | Path) -> MjcfUrdf:
    """Convert an MJCF humanoid (a free-floating root body) to URDF text.

    Args:
        path: The MJCF file.

    Returns:
        The URDF, and what it could not carry.

    Raises:
        ConfigError: The file is not XML, a number of it is not finite, pinocchio cannot load it, an include or
            mesh is missing,
            its root has no free joint, or it has a ball joint or a second body in
            ``<worldbody>`` (the file and the element named).

    Example:
        >>> converted = convert_mjcf("humanoid.xml")  # doctest: +SKIP
        >>> Path("humanoid.urdf").write_text(converted.text)  # doctest: +SKIP

    """
    path = Path(path).resolve()
    root = flattened_mjcf(path)
    check_elements(root, path)
    check_numbers(root, path)
    model, collision, visual = _load(root, path)
    _check_tree(model, path)
    writer = _UrdfWriter(model, body_joints(root, path), path)
    text = writer.write(collision, visual)
    dropped = tuple(writer.dropped) + _sections_dropped(root)
    return MjcfUrdf(path, hashlib.sha256(path.read_bytes()).hexdigest(), text, dropped)


def _load(root: ET.Element, path: Path) -> tuple[pin.Model, pin.GeometryModel, pin.GeometryModel]:
    """The model, collision and visual geometry pinocchio reads from the flattened MJCF (a temporary copy)."""
    with tempfile.TemporaryDirectory(prefix="posegen-mjcf-") as folder:
        flat = str(Path(folder) / path.name)
        ET.ElementTree(root).write(flat, encoding="unicode")
        try:
            with native_output():  # the parser's own lines, kept off the terminal
                model = pin.buildModelFromMJCF(flat)
                collision = pin.buildGeomFromMJCF(model, flat, pin.GeometryType.COLLISION)
                visual = pin.buildGeomFromMJCF(model, flat, pin.GeometryType.VISUAL)
        except (RuntimeError, ValueError, IndexError) as exc:
            lines = str(exc).strip().splitlines()
            first = lines[0] if lines else type(exc).__name__
            raise ConfigError(f"{path}: pinocchio cannot load the MJCF: {first}") from exc
    return model, collision, visual


def _check_tree(model: pin.Model, path: Path) -> None:
    """One body tree under a free-floating root, no ball joint (refused with the joint named)."""
    if model.njoints < 2 or model.joints[1].shortname() != "JointModelFreeFlyer":
        body = next((f.name for f in model.frames if f.type == pin.FrameType.BODY and f.parentJoint == 0), "")
        raise ConfigError(
            f"{path}: root body '{body}' has no <freejoint>: posegen floats the root body itself; add one to it"
        )
    for j in range(2, model.njoints):
        kind = model.joints[j].shortname()
        if kind == "JointModelSpherical" or kind.startswith("JointModelSphericalZYX"):
            raise ConfigError(f"{path}: joint '{model.names[j]}' is a ball joint; posegen needs hinges: split it")
        if kind == "JointModelFreeFlyer":
            raise ConfigError(f"{path}: joint '{model.names[j]}' is a second free joint; one free root body only")
        if model.parents[j] == 0:
            raise ConfigError(f"{path}: joint '{model.names[j]}' starts a second body tree; posegen reads one robot")


def _sections_dropped(root: ET.Element) -> tuple[str, ...]:
    """The MJCF parts a URDF has no place for, counted: ``"12 actuator"``."""
    counts: Counter[str] = Counter()
    for section in _NOT_CARRIED:
        for element in root.findall(section):
            counts[section] += len(list(element))
    counts["site"] = len(list(root.iter("site")))
    counts["body with mesh geoms and no <inertial> (pinocchio's default inertia: check its mass)"] = sum(
        body.find("inertial") is None and any(g.get("mesh") for g in body.findall("geom")) for body in root.iter("body")
    )
    counts["body with visual-only geoms and no <inertial> (MuJoCo counts their mass, pinocchio does not)"] = sum(
        body.find("inertial") is None and any(map(_weighs_unseen, body.findall("geom"))) for body in root.iter("body")
    )
    counts["worldbody geom (floor, scenery)"] = sum(len(w.findall("geom")) for w in root.findall("worldbody"))
    return tuple(f"{n} {kind}" for kind, n in counts.items() if n)


def _weighs_unseen(geom: ET.Element) -> bool:
    """A geom without collisions (``contype`` and ``conaffinity`` 0, written by the flattening) that has mass."""
    visual = geom.get("contype") == "0" and geom.get("conaffinity") == "0"
    return visual and geom.get("mass") not in ("0", "0.0") and geom.get("density") not in ("0", "0.0")


def _f(value: float) -> str:
    """A float written so that it reads back exactly."""
    return repr(float(value) + 0.0)


def _vec(values: np.ndarray | tuple[float, ...]) -> str:
    return " ".join(_f(v) for v in values)


def _origin(placement: pin.SE3) -> str:
    rpy = pin.rpy.matrixToRpy(placement.rotation)
    return f'<origin xyz="{_vec(placement.translation)}" rpy="{_vec(rpy)}"/>'


def _motion(axis: np.ndarray, value: float, prismatic: bool) -> pin.SE3:
    """A joint's motion by ``value`` (m along a slide's unit ``axis``, rad about a hinge's)."""
    if prismatic:
        return pin.SE3(np.eye(3), value * axis)
    return pin.SE3(pin.AngleAxis(value, axis).matrix(), np.zeros(3))


def _is_identity(placement: pin.SE3) -> bool:
    return bool(np.allclose(placement.homogeneous, np.eye(4), atol=_IDENTITY_TOL, rtol=0.0))


class _UrdfWriter:
    """The URDF elements of a pinocchio model read from an MJCF, in the model's joint order."""

    def __init__(self, model: pin.Model, joints: dict[str, list[MjcfJoint]], path: Path) -> None:
        self.model = model
        self.mjcf_joints = joints  # body -> its <joint> elements, read as MuJoCo does
        self.path = path
        self.links: dict[str, list[str]] = {}  # link -> its inner elements (inertial, visuals, collisions)
        self.joints: list[str] = []
        self.dropped: list[str] = []
        self.link_of = [""] * model.njoints  # the URDF link at each pinocchio joint's frame

    def write(self, collision: pin.GeometryModel, visual: pin.GeometryModel) -> str:
        """The URDF text: the links and joints of every pinocchio joint, the welded bodies, the geometry."""
        for j in range(1, self.model.njoints):
            self._joint(j)
        self._welded_bodies()
        skipped: dict[str, list[str]] = {}
        for kind, geometry in (("visual", visual), ("collision", collision)):
            for obj in geometry.geometryObjects:
                frame = self.model.frames[obj.parentFrame]
                if frame.type == pin.FrameType.BODY and frame.name in self.links:  # on its body, in its frame
                    self.links[frame.name] += _shape_xml(kind, obj, frame.placement.inverse(), skipped)
                else:
                    self.links[self.link_of[obj.parentJoint]] += _shape_xml(kind, obj, pin.SE3.Identity(), skipped)
        self.dropped += [
            f"{len(links)} {kind} geoms ({', '.join(sorted(set(links)))})" for kind, links in skipped.items()
        ]
        name = self.model.name or self.path.stem
        links = [f'<link name="{link}">{"".join(inner)}</link>' for link, inner in self.links.items()]
        return (
            f'<?xml version="1.0"?>\n<!-- converted by posegen from the MJCF {self.path.name} -->\n'
            f'<robot name="{name}">\n' + "\n".join(links + self.joints) + "\n</robot>\n"
        )

    def _link(self, name: str, inner: str = "") -> str:
        """Declare a link (once: a name given twice in the URDF is refused)."""
        if name in self.links:
            raise ConfigError(f"{self.path}: the name '{name}' is given twice in the converted URDF; rename one")
        self.links[name] = [inner] if inner else []
        return name

    def _owner(self, j: int) -> pin.Frame:
        """The body frame a joint moves (the body that holds the MJCF joint)."""
        joint_frame = self.model.getFrameId(self.model.names[j], pin.FrameType.JOINT)
        return next(f for f in self.model.frames if f.type == pin.FrameType.BODY and f.parentFrame == joint_frame)

    def _joint(self, j: int) -> None:
        """The link at pinocchio joint ``j``'s frame, its body's (with the joint's inertia), its URDF joint(s)."""
        body = self._owner(j)
        inertial = _inertial_xml(body.placement.actInv(self.model.inertias[j]))  # in the body's frame
        if _is_identity(body.placement):
            self.link_of[j] = self._link(body.name, inertial)
        else:  # an MJCF joint off its body's origin: the body is fixed to a link at the joint
            self.link_of[j] = self._link(f"{self.model.names[j]}_link")
            self._fixed(self.link_of[j], self._link(body.name, inertial), body.placement)
        if j > 1:
            self._moving(j, self.link_of[j], body.name)

    def _moving(self, j: int, link: str, body: str) -> None:
        """The URDF joint(s) of pinocchio joint ``j``: one, or a chain for a composite."""
        joint = self.model.joints[j]
        parent = self.link_of[self.model.parents[j]]
        placement = self.model.jointPlacements[j]
        written = self.mjcf_joints.get(body, [])
        if joint.shortname() != "JointModelComposite":
            own = written[0] if len(written) == 1 else _NOTHING_WRITTEN
            self._hinge(dataclasses.replace(own, name=str(self.model.names[j])), joint, parent, link, placement)
            return
        composite = joint.extract()
        if len(written) != len(composite.joints):
            written = [
                dataclasses.replace(_NOTHING_WRITTEN, name=f"{body}_joint{k}") for k in range(len(composite.joints))
            ]
        idx_q = joint.idx_q
        for k, (sub, inner) in enumerate(zip(composite.joints, composite.jointPlacements, strict=True)):
            child = link if k == len(composite.joints) - 1 else self._link(f"{written[k].name}_link")
            self._hinge(written[k], sub, parent, child, placement * inner, idx_q)
            parent, placement, idx_q = child, pin.SE3.Identity(), idx_q + sub.nq

    def _hinge(
        self, written: MjcfJoint, joint: pin.JointModel, parent: str, child: str, at: pin.SE3, idx_q: int | None = None
    ) -> None:
        """A one-dof URDF joint (revolute, continuous or prismatic) with pinocchio's axis and limits.

        ``written`` is the MJCF joint (its name, ``ref``, a slide's range); ``idx_q`` its
        configuration index (default: ``joint``'s). The origin is turned back by ``ref``
        (rad or m): pinocchio's zero is the pose as written, MuJoCo's (the limits' and the
        encoders') is ``ref`` from it. A slide's limits are its range as written (pinocchio
        reads them as degrees under ``angle="degree"``).
        """
        name = written.name
        idx_q = joint.idx_q if idx_q is None else idx_q
        kind = joint.shortname().removeprefix("JointModel")
        if kind in ("RevoluteUnaligned", "PrismaticUnaligned"):
            axis = tuple(float(v) for v in joint.extract().axis)
        elif kind[:-1] in ("R", "P") and kind[-1] in _AXES:
            axis = _AXES[kind[-1]]
        else:
            raise ConfigError(f"{self.path}: joint '{name}' is a {kind} joint; posegen converts hinges and slides")
        low, high = float(self.model.lowerPositionLimit[idx_q]), float(self.model.upperPositionLimit[idx_q])
        prismatic = kind.startswith("P")
        if prismatic and written.slide_range_m is not None:
            low, high = written.slide_range_m
        if written.ref:
            at = at * _motion(np.array(axis), -written.ref, prismatic)
        urdf_kind = "prismatic" if prismatic else "revolute" if np.isfinite([low, high]).all() else "continuous"
        idx_v = idx_q - self.model.joints[1].nq + self.model.joints[1].nv  # one-dof joints after the free root
        speed, effort = (float(self.model.velocityLimit[idx_v]), float(self.model.effortLimit[idx_v]))
        speed, effort = (v if np.isfinite(v) else 0.0 for v in (speed, effort))
        bounds = f'lower="{_f(low)}" upper="{_f(high)}" ' if urdf_kind != "continuous" else ""
        self._check_name(name)
        self.joints.append(
            f'<joint name="{name}" type="{urdf_kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'{_origin(at)}<axis xyz="{_vec(axis)}"/><limit {bounds}effort="{_f(effort)}" velocity="{_f(speed)}"/>'
            "</joint>"
        )

    def _check_name(self, joint: str) -> None:
        if any(f'<joint name="{joint}"' in j for j in self.joints):
            raise ConfigError(f"{self.path}: the joint name '{joint}' is given twice in the converted URDF; rename one")

    def _fixed(self, parent: str, child: str, at: pin.SE3) -> None:
        self._check_name(f"{child}_fixed")
        self.joints.append(
            f'<joint name="{child}_fixed" type="fixed"><parent link="{parent}"/>'
            f'<child link="{child}"/>{_origin(at)}</joint>'
        )

    def _welded_bodies(self) -> None:
        """Bodies without a joint of their own: massless links fixed where pinocchio places them."""
        for frame in self.model.frames:
            if frame.type == pin.FrameType.BODY and frame.parentJoint > 0 and frame.name not in self.links:
                self._fixed(self.link_of[frame.parentJoint], self._link(frame.name), frame.placement)


def _inertial_xml(inertia: pin.Inertia) -> str:
    if inertia.mass <= 0.0:
        return ""
    i = inertia.inertia  # (3, 3) about the centre of mass, kg m^2
    return (
        f'<inertial><origin xyz="{_vec(inertia.lever)}" rpy="0 0 0"/><mass value="{_f(inertia.mass)}"/>'
        f'<inertia ixx="{_f(i[0, 0])}" ixy="{_f(i[0, 1])}" ixz="{_f(i[0, 2])}" iyy="{_f(i[1, 1])}" '
        f'iyz="{_f(i[1, 2])}" izz="{_f(i[2, 2])}"/></inertial>'
    )


def _shape_xml(kind: str, obj: pin.GeometryObject, to_link: pin.SE3, skipped: dict[str, list[str]]) -> list[str]:
    """The URDF ``<visual>``/``<collision>`` elements of one geometry (a capsule: three), [] if none fits.

    ``to_link`` takes the geometry's placement from its joint's frame to its link's.
    """
    shape = obj.geometry
    name = type(shape).__name__
    at = to_link * obj.placement
    parts: list[tuple[pin.SE3, str]] = []
    if name == "Box":
        parts.append((at, f'<box size="{_vec(2.0 * shape.halfSide)}"/>'))
    elif name == "Sphere":
        parts.append((at, f'<sphere radius="{_f(shape.radius)}"/>'))
    elif name in ("Cylinder", "Capsule"):
        length = 2.0 * shape.halfLength
        parts.append((at, f'<cylinder radius="{_f(shape.radius)}" length="{_f(length)}"/>'))
        if name == "Capsule":  # a cylinder and a sphere at each end
            for end in (-shape.halfLength, shape.halfLength):
                parts.append(
                    (at * pin.SE3(np.eye(3), np.array([0.0, 0.0, end])), f'<sphere radius="{_f(shape.radius)}"/>')
                )
    elif obj.meshPath and Path(obj.meshPath).is_file():
        parts.append((at, f'<mesh filename="{obj.meshPath}" scale="{_vec(obj.meshScale)}"/>'))
    else:
        skipped.setdefault(f"{kind} {name.lower()}", []).append(obj.name.rsplit("_", 1)[0])
        return []
    return [f"<{kind}>{_origin(place)}<geometry>{xml}</geometry></{kind}>" for place, xml in parts]
