"""The robot drawn in the viewer: one viser node per joint, nested as the kinematic tree.

Each joint's node carries its local placement (``data.liMi``: the joint placement times
the joint motion), and each geometry hangs under its parent joint at its fixed
placement. Posing the robot therefore sends one rotation per joint that moved (and a
position only for the root and prismatic joints), not a pose per mesh: a recorded
route stays small.

Meshes: the URDF's visual meshes when they fit a triangle budget, else the collision
geometry posegen checks (the URDF's meshes and the config's shapes; for TALOS: 158,856
visual triangles, 26,202 collision ones, which still look like the robot), else the
convex hulls of that geometry, else those of the visual meshes: a robot whose visual
meshes are heavy and whose URDF has no collision geometry is drawn all the same. Visual
meshes whose binary STL files alone hold more than ``SKIP_FACTOR`` times the budget (their
headers say how many triangles) are not loaded to be counted.
"""

from __future__ import annotations

import enum
import logging
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import trimesh
import viser

from posegen.robot import FloatArray, Scene, resolve_path, robot_geometry

LOG = logging.getLogger(__name__)

TRIANGLE_BUDGET = 60_000  # above this the visual meshes make the page heavy: use the collision ones
SKIP_FACTOR = 2  # visual meshes whose STL headers hold this many budgets are over it for sure (not loaded)
STL_HEADER_BYTES = 80  # a binary STL: this header, a uint32 triangle count, 50 bytes per triangle
POSE_TOLERANCE = 1e-4  # m, or quaternion component (~0.2 mrad): smaller changes of a joint's pose are not re-sent
RGB = tuple[int, int, int]


class MeshSource(str, enum.Enum):
    """Which meshes of the URDF the figure is drawn with."""

    VISUAL = "visual"
    COLLISION = "collision"
    COLLISION_HULLS = "collision hulls"
    VISUAL_HULLS = "visual hulls"


@dataclass(frozen=True)
class Mesh:
    """One geometry of the robot as triangles, in its parent joint's frame."""

    parent_joint: int
    placement: pin.SE3  # geometry frame in the parent joint frame
    vertices: FloatArray  # (v, 3) m, geometry frame
    faces: np.ndarray  # (f, 3) vertex indices


@dataclass(frozen=True)
class RobotMeshes:
    """The robot's meshes, chosen once per scene and drawn by every figure of it."""

    source: MeshSource
    meshes: tuple[Mesh, ...]

    @property
    def triangles(self) -> int:
        """Number of triangles drawn."""
        return sum(len(m.faces) for m in self.meshes)


def _triangles(geometry: object) -> tuple[FloatArray, np.ndarray] | None:
    """Vertices and faces of a coal geometry, or None when it is of a kind not drawn."""
    if isinstance(geometry, coal.BVHModelBase):
        vertices = np.asarray(geometry.vertices(), dtype=float)
        tris = [geometry.tri_indices(i) for i in range(geometry.num_tris)]
        return vertices, np.array([[t[0], t[1], t[2]] for t in tris], dtype=np.uint32).reshape(-1, 3)
    if isinstance(geometry, coal.Convex):
        vertices = np.asarray(geometry.points(), dtype=float)
        polygons = [geometry.polygons(i) for i in range(geometry.num_polygons)]
        return vertices, np.array([[t[0], t[1], t[2]] for t in polygons], dtype=np.uint32).reshape(-1, 3)
    shape: trimesh.Trimesh
    if isinstance(geometry, coal.Box):
        shape = trimesh.creation.box(extents=2.0 * np.asarray(geometry.halfSide))
    elif isinstance(geometry, coal.Cylinder):
        shape = trimesh.creation.cylinder(radius=geometry.radius, height=2.0 * geometry.halfLength, sections=24)
    elif isinstance(geometry, coal.Sphere):
        shape = trimesh.creation.icosphere(subdivisions=2, radius=geometry.radius)
    elif isinstance(geometry, coal.Capsule):
        shape = trimesh.creation.capsule(height=2.0 * geometry.halfLength, radius=geometry.radius)
    else:
        return None
    return np.asarray(shape.vertices, dtype=float), np.asarray(shape.faces, dtype=np.uint32)


def _triangle_count(geometry: object) -> int:
    """Triangles a geometry is drawn with (a primitive counts as a few hundred)."""
    if isinstance(geometry, coal.BVHModelBase):
        return int(geometry.num_tris)
    if isinstance(geometry, coal.Convex):
        return int(geometry.num_polygons)
    return 200


def _meshes_of(geometry_model: pin.GeometryModel) -> tuple[Mesh, ...]:
    meshes = []
    for obj in geometry_model.geometryObjects:
        triangles = _triangles(obj.geometry)
        if triangles is None:
            LOG.warning("geometry %s (%s) is not drawn", obj.name, type(obj.geometry).__name__)
            continue
        meshes.append(Mesh(int(obj.parentJoint), pin.SE3(obj.placement), triangles[0], triangles[1]))
    return tuple(meshes)


def _geometry(scene: Scene, source: MeshSource) -> pin.GeometryModel:
    package_dirs = scene.files.package_dirs
    if source in (MeshSource.COLLISION, MeshSource.COLLISION_HULLS):
        convex = source == MeshSource.COLLISION_HULLS
        return robot_geometry(scene.model, scene.urdf_xml, package_dirs, scene.config.collision, convex)
    geometry_model = pin.buildGeomFromUrdfString(
        scene.model, scene.urdf_xml, pin.GeometryType.VISUAL, package_dirs=list(package_dirs)
    )
    if source == MeshSource.VISUAL_HULLS:
        for obj in geometry_model.geometryObjects:
            if isinstance(obj.geometry, coal.BVHModelBase):
                obj.geometry.buildConvexHull(True, "Qt")
                obj.geometry = obj.geometry.convex
    return geometry_model


def _stl_triangles(path: Path) -> int:
    """The triangles of a binary STL file (its header's count, checked against its size); 0 for any other file."""
    try:
        size = path.stat().st_size
        with path.open("rb") as stream:
            stream.seek(STL_HEADER_BYTES)
            raw = stream.read(4)
    except OSError:
        return 0
    count = int.from_bytes(raw, "little") if len(raw) == 4 else -1
    return count if size == STL_HEADER_BYTES + 4 + 50 * count else 0


def visual_triangles_at_least(scene: Scene) -> int:
    """How many triangles the URDF's visual meshes hold at least: its binary STL files', read from their headers.

    Example:
        >>> visual_triangles_at_least(scene) > TRIANGLE_BUDGET  # heavy: drawn with the collision geometry

    """
    package_dirs = tuple(scene.files.package_dirs)
    meshes = ET.fromstring(scene.urdf_xml).iterfind("link/visual/geometry/mesh")
    return sum(_stl_triangles(resolve_path(m.get("filename", ""), package_dirs)) for m in meshes)


def robot_meshes(scene: Scene, budget: int = TRIANGLE_BUDGET) -> RobotMeshes:
    """The meshes to draw a scene's robot with: the first of :class:`MeshSource` that has some within ``budget``.

    When none fits, the one with the fewest triangles (never an empty figure when any
    geometry exists). Visual meshes over ``SKIP_FACTOR`` budgets by their STL headers
    alone are loaded only if they are that one.
    """
    found: list[tuple[int, MeshSource, pin.GeometryModel | None]] = []
    for source in MeshSource:
        heavy = visual_triangles_at_least(scene) if source == MeshSource.VISUAL else 0
        if heavy > SKIP_FACTOR * budget:
            found.append((heavy, source, None))  # over the budget for sure: loaded only if it is the lightest
            continue
        geometry_model = _geometry(scene, source)
        triangles = sum(_triangle_count(g.geometry) for g in geometry_model.geometryObjects)
        if geometry_model.ngeoms and triangles <= budget:
            found = [(triangles, source, geometry_model)]
            break
        if geometry_model.ngeoms:
            found.append((triangles, source, geometry_model))
    if not found:
        return RobotMeshes(MeshSource.VISUAL, ())
    _, source, lightest = min(found, key=lambda item: item[0])
    geometry_model = _geometry(scene, source) if lightest is None else lightest
    chosen = RobotMeshes(source, _meshes_of(geometry_model))
    LOG.info("robot drawn with its %s meshes (%d triangles)", chosen.source.value, chosen.triangles)
    return chosen


def wxyz(rotation: FloatArray) -> FloatArray:
    """Quaternion (w, x, y, z) of a rotation matrix. Shape (4,)."""
    x, y, z, w = pin.Quaternion(rotation).coeffs()
    return np.array([w, x, y, z])


class RobotFigure:
    """A robot drawn in a viser scene, posed from full pinocchio configurations.

    Attributes:
        root: Name of the figure's root node (``/name``).
        node_names: Node name of each joint (index 0: the root).

    """

    def __init__(
        self,
        server: viser.ViserServer,
        model: pin.Model,
        meshes: RobotMeshes,
        name: str,
        rgb: RGB,
        opacity: float | None = None,
    ) -> None:
        self._model = model
        self._data = model.createData()
        self.root = f"/{name}"
        names = [self.root]
        self._joints: list[viser.FrameHandle] = []
        for j in range(1, model.njoints):
            names.append(f"{names[model.parents[j]]}/{j}")
            placement = model.jointPlacements[j]
            self._joints.append(
                server.scene.add_frame(
                    names[j], show_axes=False, position=placement.translation, wxyz=wxyz(placement.rotation)
                )
            )
        self.node_names = tuple(names)
        for k, mesh in enumerate(meshes.meshes):
            server.scene.add_mesh_simple(
                f"{names[mesh.parent_joint]}/mesh{k}",
                mesh.vertices,
                mesh.faces,
                color=rgb,
                opacity=opacity,
                position=mesh.placement.translation,
                wxyz=wxyz(mesh.placement.rotation),
                cast_shadow=False,
                receive_shadow=False,
            )
        self._sent = np.full((model.njoints - 1, 7), np.nan)  # (nj, 7) last position and wxyz sent per joint

    def pose(self, q: FloatArray) -> None:
        """Place the robot at a full configuration ``q`` (nq,), re-sending only what moved."""
        pin.forwardKinematics(self._model, self._data, q)
        local = np.array([np.concatenate([m.translation, wxyz(m.rotation)]) for m in self._data.liMi[1:]])  # (nj, 7)
        flip = np.einsum("ij,ij->i", local[:, 3:], self._sent[:, 3:]) < 0
        local[flip, 3:] *= -1.0  # the same rotations, kept continuous with the last ones sent
        change = np.abs(local - self._sent)
        moved = ~(change[:, :3] < POSE_TOLERANCE).all(axis=1)
        turned = ~(change[:, 3:] < POSE_TOLERANCE).all(axis=1)
        for j in np.flatnonzero(moved):
            self._joints[j].position = local[j, :3]
        for j in np.flatnonzero(turned):
            self._joints[j].wxyz = local[j, 3:]
        self._sent[moved, :3] = local[moved, :3]
        self._sent[turned, 3:] = local[turned, 3:]
