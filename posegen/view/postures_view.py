"""The view of a pool or a selection: the robot at each posture, every contact on the table.

One step per posture, in file order: in the HTML page, second ``k`` of the playback bar
is posture ``k`` (type a number in its time field to jump there). The live viewer has a
posture slider instead. Contact points are drawn on the table top, coloured by chain:
a selection's pool postures small, the selected ones large, the current one in red.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import viser

from posegen.arguments import is_finite_number
from posegen.io import Pool
from posegen.robot import FloatArray, Scene
from posegen.view.artefact import ArtefactKind, PosturesArtefact
from posegen.view.robot_figure import RobotFigure, robot_meshes
from posegen.view.scenery import ROBOT_RGB, chain_colours, info_label, set_scenery
from posegen.view.stepped_view import SteppedView

CURRENT_RGB = (225, 30, 30)
POOL_POINT_M, PLAN_POINT_M = 0.008, 0.02  # contact marker sizes: a selection's pool, the postures shown


def contact_points(scene: Scene, chosen: Pool, lift_m: float = 0.0) -> FloatArray:
    """World positions (m) of the postures' contact points, ``lift_m`` above the table top. Shape (n, 3)."""
    xy = np.array([p.contact_xy_m for p in chosen.postures], dtype=float).reshape(-1, 2)
    local = np.column_stack([xy, np.full(len(xy), lift_m), np.ones(len(xy))])
    return (scene.table_pose @ local.T).T[:, :3]


def _chain_rgb(scene: Scene, chosen: Pool) -> np.ndarray:
    colours = chain_colours(scene)
    return np.array([colours[p.chain] for p in chosen.postures], dtype=np.uint8).reshape(-1, 3)


def describe(artefact: PosturesArtefact, k: int) -> str:
    """One line about posture ``k`` of a pool or selection."""
    posture: Any = artefact.postures.postures[k]
    entry = artefact.entries[k]
    parts = [
        f"{artefact.kind.value} posture {k + 1}/{len(artefact.postures.postures)}",
        f"id {entry.get('pool_id', entry.get('id', k))}",
        posture.chain,
        posture.spot,
    ]
    if artefact.kind == ArtefactKind.SELECTION:
        weight = entry.get("weight", 0.0)
        shown = f"{weight:.4f}" if is_finite_number(weight) else repr(weight)  # a label: what the file says
        parts.append(f"IROC rank {entry.get('rank')}, weight {shown}")
    parts.append(f"CoM margin {posture.com_margin_m * 1e3:.0f} mm")
    parts.append(f"min distance {posture.min_distance_m * 1e3:.1f} mm")
    return " | ".join(parts[:4]) + "\n" + " | ".join(parts[4:])


class PosturesView(SteppedView):
    """A pool or a selection drawn in a viser scene, one posture at a time."""

    STEP_NAME = "posture"

    def __init__(self, server: viser.ViserServer, artefact: PosturesArtefact) -> None:
        super().__init__(server)
        self._artefact = artefact
        scene = artefact.scene
        set_scenery(server, scene)
        self._robot = RobotFigure(server, scene.model, robot_meshes(scene), "robot", ROBOT_RGB)
        big = artefact.kind == ArtefactKind.SELECTION
        size = PLAN_POINT_M if big else POOL_POINT_M
        points = contact_points(scene, artefact.postures, size)  # a marker is a disc: lift it out of the table
        background = artefact.pool if artefact.kind == ArtefactKind.SELECTION else None
        if background is not None:
            server.scene.add_point_cloud(
                "/contacts/pool",
                contact_points(scene, background, POOL_POINT_M),
                _chain_rgb(scene, background),
                point_size=POOL_POINT_M,
                point_shape="circle",
            )
        server.scene.add_point_cloud(
            "/contacts/postures",
            points,
            _chain_rgb(scene, artefact.postures),
            point_size=size,
            point_shape="circle",
        )
        self._points = points
        self._current = server.scene.add_icosphere("/contacts/current", radius=0.018, color=CURRENT_RGB)
        self._label = info_label(server, scene)

    @property
    def steps(self) -> int:
        """Number of postures."""
        return len(self._artefact.postures.postures)

    def show(self, k: int) -> None:
        """Pose the robot at posture ``k`` and describe it."""
        posture = self._artefact.postures.postures[k]
        self._robot.pose(self._artefact.scene.configuration(np.array(posture.joints)))
        self._current.position = self._points[k] + np.array([0.0, 0.0, 0.01])
        self._label.text = self.describe(k)

    def describe(self, k: int) -> str:
        """Posture ``k`` in words."""
        return describe(self._artefact, k)
