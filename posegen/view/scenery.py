"""What every view shows around the robot: floor, table, lights, colours and the camera.

Colours are chosen so that each kind of object is told apart at a glance (and by the
browser tests): the robot is the only blue thing in the scene.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import viser

from posegen.robot import FloatArray, Scene
from posegen.view.robot_figure import RGB, wxyz

ROBOT_RGB: RGB = (70, 110, 200)  # the robot (solid): no other object is blue
GHOST_RGB: RGB = (120, 120, 120)  # the nominal robot behind a calibrated one
TABLE_RGB: RGB = (215, 200, 170)
CHAIN_RGB: tuple[RGB, ...] = ((40, 160, 70), (235, 120, 25), (170, 60, 160), (200, 40, 40))  # chains in config order
FIELD_OF_VIEW_DEG = 45.0
CAMERA_AZIMUTH_DEG = -50.0  # from the robot-to-table direction, to the robot's right
CAMERA_ELEVATION_DEG = 22.0
MARGIN = 1.25  # the arms reach above the reference posture's head


@dataclass(frozen=True)
class Camera:
    """Where the camera looks from (world frame, m)."""

    position: FloatArray  # (3,)
    look_at: FloatArray  # (3,)
    fov_deg: float


def chain_colours(scene: Scene) -> dict[str, RGB]:
    """A colour per chain, in the config's chain order."""
    return {c.name: CHAIN_RGB[i % len(CHAIN_RGB)] for i, c in enumerate(scene.chains)}


def robot_height(scene: Scene) -> float:
    """Height (m) of the highest frame of the robot in its reference posture."""
    data = scene.model.createData()
    pin.framesForwardKinematics(scene.model, data, scene.configuration(scene.reference))
    return float(max(f.translation[2] for f in data.oMf))


def framing(scene: Scene) -> Camera:
    """A camera that sees the whole robot and the whole table, from the front-right and above.

    The robot and the table top are bounded by a box; the camera looks at its centre from
    the distance at which the box's bounding sphere fills the field of view.
    """
    feet = np.array([pose[:3, 3] for pose in scene.sole_poses.values()])  # (2, 3)
    half = np.array(scene.table.size_m[:2]) / 2
    corners = np.array([[sx * half[0], sy * half[1], 0.0, 1.0] for sx in (-1, 1) for sy in (-1, 1)])
    table = (scene.table_pose @ corners.T).T[:, :3]  # (4, 3)
    top = np.array([0.0, 0.0, robot_height(scene)])
    points = np.vstack([feet, feet + top, table])
    low, high = points.min(axis=0), points.max(axis=0)
    centre = (low + high) / 2
    radius = float(np.linalg.norm(high - low) / 2)
    ahead = scene.table_pose[:3, 3] - feet.mean(axis=0)
    ahead[2] = 0.0
    ahead = ahead / np.linalg.norm(ahead) if np.linalg.norm(ahead) > 1e-9 else np.array([1.0, 0.0, 0.0])
    left = np.cross([0.0, 0.0, 1.0], ahead)
    az, el = np.deg2rad(CAMERA_AZIMUTH_DEG), np.deg2rad(CAMERA_ELEVATION_DEG)
    direction = np.cos(el) * (np.cos(az) * ahead + np.sin(az) * left) + np.sin(el) * np.array([0.0, 0.0, 1.0])
    distance = MARGIN * radius / np.sin(np.deg2rad(FIELD_OF_VIEW_DEG) / 2)
    return Camera(position=centre + distance * direction, look_at=centre, fov_deg=FIELD_OF_VIEW_DEG)


def set_scenery(server: viser.ViserServer, scene: Scene) -> None:
    """Lights, floor grid, the table and the camera of a view."""
    server.scene.set_up_direction("+z")
    server.scene.configure_default_lights(enabled=True, cast_shadow=False)
    server.scene.configure_environment_map(None)  # its prefiltering takes ~20 s in a GPU-less browser
    server.scene.add_light_hemisphere("/lights/sky", sky_color=(255, 255, 255), ground_color=(120, 110, 100))
    table = scene.table
    thickness = table.size_m[2]
    centre = scene.table_pose @ np.array([0.0, 0.0, -thickness / 2, 1.0])
    server.scene.add_box(
        "/table",
        dimensions=np.asarray(table.size_m, dtype=float),
        color=TABLE_RGB,
        position=centre[:3],
        wxyz=wxyz(scene.table_pose[:3, :3]),
        cast_shadow=False,
        receive_shadow=False,
    )
    server.scene.add_grid("/floor", width=3.0, height=3.0, cell_size=0.25, position=(0.3, 0.0, 0.0))
    camera = framing(scene)
    server.initial_camera.fov = float(np.deg2rad(camera.fov_deg))
    server.initial_camera.position = tuple(camera.position)
    server.initial_camera.look_at = tuple(camera.look_at)
    server.initial_camera.up = (0.0, 0.0, 1.0)


def info_label(server: viser.ViserServer, scene: Scene) -> viser.LabelHandle:
    """The label that tells what is shown, above the far edge of the table."""
    above = scene.table_pose @ np.array([scene.table.size_m[0] / 2, 0.0, 0.45, 1.0])
    return server.scene.add_label("/info", "", position=above[:3], anchor="bottom-center")
