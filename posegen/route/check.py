"""Independent re-verification of an exported route (``posegen check ROUTE``).

Every point of the file is checked from its joint angles with pinocchio and coal on
the original meshes, not with anything the planner used: strictly increasing times;
joint limits (with margin); velocities within the URDF limits (the exported values and
the average between consecutive points); accelerations within the configured limit;
the second sole at its pose; the CoM inside the support polygon with margin; no
collision with margin, fingertip-table contact allowed only in contact segments (where
the margin shrinks by the commanded overshoot).
"""

from __future__ import annotations

import enum
from typing import Any

import numpy as np
import pinocchio as pin

from posegen.errors import InputError
from posegen.progress import Progress, ProgressCallback, ignore_progress
from posegen.robot import (
    SOLE_ANGLE_TOL_RAD,
    SOLE_POSITION_TOL_M,
    CollisionChecker,
    Scene,
    SegmentType,
    Verification,
    route_arrays,
    summarize,
)

TOLERANCE = 1e-6  # relative, on velocity and acceleration limits


class RouteInvariant(str, enum.Enum):
    """What every route point must satisfy."""

    TIMES = "times"
    JOINT_LIMITS = "joint_limits"
    VELOCITY = "velocity"
    ACCELERATION = "acceleration"
    SOLE = "sole"
    COM = "com"
    COLLISION = "collision"


def verify_route(scene: Scene, data: dict[str, Any], progress: ProgressCallback = ignore_progress) -> Verification:
    """Check every point of a route file's plain data (see :mod:`posegen.robot.trajectory`).

    Raises:
        InputError: The route's joints are not the scene's.

    """
    if tuple(data["trajectory"]["joint_names"]) != scene.joint_names:
        raise InputError("the route's joint names differ from the robot model's")
    times, positions, velocities, accelerations = route_arrays(data)
    m = len(times)
    contact_chain: list[str | None] = [None] * m
    in_contact = np.zeros(m, dtype=bool)
    for seg in data["segments"]:
        if SegmentType(seg["type"]).in_contact:
            for k in range(int(seg["first_point"]), int(seg["last_point"]) + 1):
                contact_chain[k] = seg["chain"]
                in_contact[k] = True
    excess: dict[RouteInvariant, np.ndarray] = {k: np.full(m, -np.inf) for k in RouteInvariant}
    detail: dict[RouteInvariant, list[str]] = {k: [""] * m for k in RouteInvariant}

    dt = np.diff(times)
    excess[RouteInvariant.TIMES][1:] = -dt
    for k in range(1, m):
        detail[RouteInvariant.TIMES][k] = f"dt {dt[k - 1]:.2e} s"
    margin = scene.margins.joint_limit_rad
    limit_gap = scene.limit_margin(positions)
    excess[RouteInvariant.JOINT_LIMITS] = margin - 1e-9 - limit_gap
    v_ratio = np.max(np.abs(velocities) / scene.velocity_limit, axis=1)
    mean_v = np.zeros(m)
    mean_v[1:] = np.max(
        np.abs(np.diff(positions, axis=0)) / np.maximum(dt, 1e-12)[:, None] / scene.velocity_limit, axis=1
    )
    excess[RouteInvariant.VELOCITY] = np.maximum(v_ratio, mean_v) - 1.0 - TOLERANCE
    a_ratio = np.max(np.abs(accelerations), axis=1) / scene.route.acceleration_limit_rad_s2
    excess[RouteInvariant.ACCELERATION] = a_ratio - 1.0 - TOLERANCE
    for k in range(m):
        detail[RouteInvariant.JOINT_LIMITS][k] = f"limit margin {limit_gap[k]:.4f} rad"
        detail[RouteInvariant.VELOCITY][k] = f"{100 * max(v_ratio[k], mean_v[k]):.1f}% of the velocity limit"
        detail[RouteInvariant.ACCELERATION][k] = f"{100 * a_ratio[k]:.1f}% of the acceleration limit"

    meshes = CollisionChecker(scene, convex=False)
    data_pin = scene.model.createData()
    second = scene.second_sole
    target = pin.SE3(scene.sole_poses[second])
    contact_margin = scene.contact_collision_margin_m
    for k in range(m):
        q = scene.configuration(positions[k])
        pin.framesForwardKinematics(scene.model, data_pin, q)
        error = target.actInv(data_pin.oMf[scene.frame_id(second)])
        position_error = float(np.linalg.norm(error.translation))
        angle_error = float(np.linalg.norm(pin.log3(error.rotation)))
        excess[RouteInvariant.SOLE][k] = max(position_error - SOLE_POSITION_TOL_M, angle_error - SOLE_ANGLE_TOL_RAD)
        detail[RouteInvariant.SOLE][k] = f"sole {position_error:.2e} m, {angle_error:.2e} rad"
        com_margin = scene.com_margin(q, data_pin)
        excess[RouteInvariant.COM][k] = scene.margins.com_m - com_margin
        detail[RouteInvariant.COM][k] = f"CoM margin {com_margin:.4f} m"
        margin_k = contact_margin if in_contact[k] else scene.margins.collision_m
        hits = meshes.colliding_pairs(q, contact_chain[k], margin_k)
        if hits:
            excess[RouteInvariant.COLLISION][k] = margin_k - hits[0].distance_m
            detail[RouteInvariant.COLLISION][k] = f"{hits[0].pair[0]} - {hits[0].pair[1]} at {hits[0].distance_m:.4f} m"
        else:
            excess[RouteInvariant.COLLISION][k] = 0.0
            detail[RouteInvariant.COLLISION][k] = f"no pair closer than {margin_k} m (meshes)"
        progress(Progress(k + 1, m, "point"))
    return summarize(m, excess, detail)
