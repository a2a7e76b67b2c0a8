"""Bounding spheres: a cheap lower bound of every collision pair's distance.

Each robot geometry gets a sphere that contains it (its hull's vertices, or its
primitive's bounding box); obstacles fixed in the world (table, floor) keep their exact
box. For a pair, centre distance minus both radii (or the signed distance from a
sphere's centre to the box, minus the radius) is never above the pair's true distance,
penetration included (a shape inside its sphere cannot penetrate deeper than the
sphere). Sorting pairs by it lets a collision check run the exact GJK on a few pairs only.
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin

from posegen.robot.geometry import FloatArray

INFLATE = 1e-9  # relative and absolute (m) padding of each radius against rounding


def _sphere(shape: coal.CollisionGeometry) -> tuple[FloatArray, float]:
    """Centre (in the shape's frame, m) and radius (m) of a sphere containing ``shape``."""
    if isinstance(shape, coal.Box):
        return np.zeros(3), float(np.linalg.norm(shape.halfSide))
    if isinstance(shape, coal.ConvexBase):
        points = np.array([shape.point(i) for i in range(shape.num_points)])  # (p, 3)
        centre = (points.min(axis=0) + points.max(axis=0)) / 2
        return centre, float(np.linalg.norm(points - centre, axis=1).max())
    shape.computeLocalAABB()
    return np.array(shape.aabb_center, dtype=float), float(shape.aabb_radius)


class BoundingSpheres:
    """Lower bounds of the distance of every collision pair of a geometry model."""

    def __init__(self, geom: pin.GeometryModel) -> None:
        objects = geom.geometryObjects
        count = len(objects)
        self._centres = np.zeros((count, 3))  # (g, 3) in each geometry's frame
        radii = np.zeros(count)
        fixed = np.zeros(count, dtype=bool)  # boxes attached to the world: exact bound
        self._half = np.zeros((count, 3))
        for k, obj in enumerate(objects):
            self._centres[k], radii[k] = _sphere(obj.geometry)
            if obj.parentJoint == 0 and isinstance(obj.geometry, coal.Box):
                fixed[k] = True
                self._half[k] = obj.geometry.halfSide
        self._radii = radii * (1 + INFLATE) + INFLATE
        first = np.array([p.first for p in geom.collisionPairs], dtype=int)
        second = np.array([p.second for p in geom.collisionPairs], dtype=int)
        to_box = fixed[first] | fixed[second]
        self._spheres = np.flatnonzero(~to_box)  # pair indices, sphere-sphere
        self._a, self._b = first[~to_box], second[~to_box]
        self._radii_a, self._radii_b = self._radii[self._a], self._radii[self._b]  # (sphere pairs,) m
        self._boxes = [int(b) for b in np.flatnonzero(fixed)]
        box_pairs = np.flatnonzero(to_box)
        box_of = np.where(fixed[first[box_pairs]], first[box_pairs], second[box_pairs])
        other = np.where(fixed[first[box_pairs]], second[box_pairs], first[box_pairs])
        # per box: its pairs, the other geometry of each, and that geometry's radius (m)
        self._against = {
            b: (box_pairs[box_of == b], other[box_of == b], self._radii[other[box_of == b]]) for b in self._boxes
        }
        self._moving = np.flatnonzero(~fixed)
        self._n_pairs = len(first)

    def lower_bounds(self, data: pin.GeometryData) -> FloatArray:
        """Lower bound (m) of each pair's distance at ``data``'s geometry placements. Shape (pairs,).

        Args:
            data: Geometry data after ``pin.updateGeometryPlacements``.

        """
        # one 4x4 per geometry read from pinocchio (a rotation and a translation apiece cost twice that)
        frames = np.array([m.homogeneous for m in data.oMg])  # (g, 4, 4)
        rotations = np.ascontiguousarray(frames[:, :3, :3])  # (g, 3, 3)
        origins = frames[:, :3, 3]  # (g, 3)
        centres = np.einsum("gij,gj->gi", rotations, self._centres) + origins  # (g, 3) world
        bounds = np.empty(self._n_pairs)
        gap = np.take(centres, self._a, axis=0) - np.take(centres, self._b, axis=0)
        square = gap * gap
        bounds[self._spheres] = np.sqrt(square[:, 0] + square[:, 1] + square[:, 2]) - self._radii_a - self._radii_b
        for box in self._boxes:
            pairs, other, radii = self._against[box]
            local = (np.take(centres, other, axis=0) - origins[box]) @ rotations[box]  # (m, 3) in the box frame
            excess = np.abs(local) - self._half[box]
            outside = np.sqrt((np.maximum(excess, 0.0) ** 2).sum(axis=1))
            bounds[pairs] = outside + np.minimum(excess.max(axis=1), 0.0) - radii
        return bounds
