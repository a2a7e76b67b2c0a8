"""How far points lie outside a body's collision shapes: the hulls of the points standing for them."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

from posegen.robot.enclosure import Enclosure, enclosure_of, shape_points


def _body(*shapes: tuple[coal.CollisionGeometry, pin.SE3]) -> pin.GeometryModel:
    geom = pin.GeometryModel()
    for k, (shape, placement) in enumerate(shapes):
        geom.addGeometryObject(pin.GeometryObject(f"s{k}", 1, 0, placement, shape))
    return geom


@pytest.mark.parametrize("shape", [coal.Cylinder(0.05, 0.2), coal.Capsule(0.05, 0.2), coal.Sphere(0.05)])
def test_round_shapes_are_sampled_on_their_surface_within_2_percent(shape):
    points = shape_points(shape)
    radial = np.linalg.norm(points[:, :2], axis=1)
    assert radial.max() == pytest.approx(0.05) and np.all(radial <= 0.05 + 1e-12)
    inside = np.array([[0.049 * np.cos(a), 0.049 * np.sin(a), 0.0] for a in np.linspace(0, np.pi, 7)])
    assert enclosure_of(_body((shape, pin.SE3.Identity())), 1).outside_m(inside) < 0.0  # 2 % in: enclosed


def test_a_point_beyond_a_face_is_that_far_outside_and_the_nearest_shape_counts():
    moved = pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.5]))
    enclosure = enclosure_of(_body((coal.Box(0.2, 0.1, 0.04), pin.SE3.Identity()), (coal.Sphere(0.1), moved)), 1)
    assert enclosure.outside_m(np.array([[0.0, 0.0, 0.05]])) == pytest.approx(0.03)  # 3 cm over the box's top
    assert enclosure.outside_m(np.array([[0.0, 0.0, 0.45]])) < 0.0  # inside the sphere
    assert enclosure.outside_m(np.array([[0.0, 0.0, 0.0], [0.13, 0.0, 0.0]])) == pytest.approx(0.03)  # the worst
    assert enclosure_of(_body(), 1).outside_m(np.zeros((1, 3))) == float("inf")  # no shape: nothing encloses
    assert Enclosure(()).outside_m(np.zeros((1, 3))) == float("inf")
