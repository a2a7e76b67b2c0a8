"""How far points lie outside a rigid body's collision shapes (whether its geometry encloses a link).

A body (the links one joint moves) encloses a point when the point lies inside the convex
hull of one of its collision shapes. The hulls are taken from points standing for each
shape (a mesh's vertices, a box's corners, round shapes sampled on circles of 16
directions, within 2 % of their radius), so a distance reported here is a lower bound of
the true distance to the shape (exact on a face, short of it near an edge or a corner).
"""

from __future__ import annotations

from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from posegen.robot.geometry import FloatArray

ROUND_DIRECTIONS = 16  # a round shape's circles are sampled in this many directions
CHUNK = 4096  # points compared with the hulls at once (memory: CHUNK x facets)


def shape_points(shape: object) -> FloatArray:
    """Points standing for a collision shape, in its own frame. Shape (k, 3).

    A mesh's vertices, a convex's points, a box's corners; a sphere, capsule, cylinder or
    cone by circles of ROUND_DIRECTIONS points at its ends (and a capsule's or sphere's
    poles); none for a plane or a half-space.

    Example:
        >>> shape_points(coal.Box(0.2, 0.1, 0.04)).max(axis=0)
        array([0.1 , 0.05, 0.02])

    """
    if hasattr(shape, "num_vertices") and hasattr(shape, "vertices"):
        return np.asarray(shape.vertices(), dtype=float).reshape(-1, 3)
    if hasattr(shape, "points") and hasattr(shape, "num_points"):
        return np.asarray(shape.points(), dtype=float).reshape(-1, 3)
    if isinstance(shape, coal.Box):
        sides = np.asarray(shape.halfSide, dtype=float)
        return np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * sides
    if not isinstance(shape, coal.Sphere | coal.Capsule | coal.Cylinder | coal.Cone):
        return np.zeros((0, 3))
    radius = float(shape.radius)
    half = float(getattr(shape, "halfLength", 0.0))
    angles = np.linspace(0.0, 2.0 * np.pi, ROUND_DIRECTIONS, endpoint=False)
    circle = np.column_stack([radius * np.cos(angles), radius * np.sin(angles), np.zeros(ROUND_DIRECTIONS)])
    top = circle if not isinstance(shape, coal.Cone) else np.zeros((1, 3))  # a cone's apex at +halfLength
    axis = np.array([0.0, 0.0, half])
    out = [circle - axis, top + axis]
    if isinstance(shape, coal.Sphere | coal.Capsule):
        out.append(np.array([[0.0, 0.0, -half - radius], [0.0, 0.0, half + radius]]))
    return np.vstack(out)


def object_points(obj: pin.GeometryObject) -> FloatArray:
    """Points standing for a geometry object, in its joint's frame. Shape (k, 3)."""
    points = shape_points(obj.geometry)  # a mesh's scale is applied by pinocchio when it loads it
    return points @ obj.placement.rotation.T + obj.placement.translation


@dataclass(frozen=True, eq=False)
class Enclosure:
    """The convex hulls of a body's collision shapes, as facets in its joint's frame."""

    facets: tuple[FloatArray, ...]  # each (m, 4): outward unit normal, offset (n . p + d <= 0 inside)

    def outside_m(self, points: FloatArray) -> float:
        """How far the farthest of ``points`` (k, 3; joint frame) lies outside the nearest hull (m).

        Negative when every point is inside one; infinite without any hull (nothing encloses).

        Example:
            >>> enclosure_of(geom, joint).outside_m(np.zeros((1, 3)))  # the joint inside its link's shape
            -0.021

        """
        if not self.facets:
            return float("inf")
        worst = -float("inf")
        for start in range(0, len(points), CHUNK):
            chunk = points[start : start + CHUNK]
            beyond = np.min([np.max(chunk @ f[:, :3].T + f[:, 3], axis=1) for f in self.facets], axis=0)
            worst = max(worst, float(beyond.max()))
        return worst


def enclosure_of(geom: pin.GeometryModel, joint: int) -> Enclosure:
    """The hulls of the collision shapes ``joint`` carries (its links and those fixed to them)."""
    return Enclosure(tuple(f for o in geom.geometryObjects if o.parentJoint == joint for f in _facets(o)))


def _facets(obj: pin.GeometryObject) -> tuple[FloatArray, ...]:
    """The facets of one object's hull (none for a shape without volume points)."""
    from scipy.spatial import ConvexHull, QhullError  # here: scipy.spatial takes 0.2 s to import, pools never ask

    points = object_points(obj)
    if len(points) < 4:
        return ()
    try:
        hull = ConvexHull(points, qhull_options="QJ")  # joggled: flat shapes still make a (thin) hull
    except QhullError:
        return ()
    return (np.asarray(hull.equations, dtype=float),)
