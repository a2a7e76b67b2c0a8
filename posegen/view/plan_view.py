"""The view of a pool or a selection: the robot at each posture, every contact on the table.

One step per posture, in file order: in the HTML page, second ``k`` of the playback bar
is posture ``k`` (type a number in its time field to jump there). The live viewer has a
posture slider instead. Contact points are drawn on the table top, coloured by chain:
a selection's pool postures small, the selected ones large, the current one in red.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import viser

from posegen.robot import FloatArray, Pool, Scene
from posegen.view.artefact import ArtefactKind, PlanArtefact
from posegen.view.robot_figure import RobotFigure, robot_meshes
from posegen.view.scenery import ROBOT_RGB, chain_colours, set_scenery

STEP_S = 1.0  # playback time per posture in the HTML page
CURRENT_RGB = (225, 30, 30)
POOL_POINT_M, PLAN_POINT_M = 0.008, 0.02  # contact marker sizes: a selection's pool, the postures shown


def contact_points(scene: Scene, plan: Pool, lift_m: float = 0.0) -> FloatArray:
    """World positions (m) of the postures' contact points, ``lift_m`` above the table top. Shape (n, 3)."""
    xy = np.array([p.contact_xy_m for p in plan.postures], dtype=float).reshape(-1, 2)
    local = np.column_stack([xy, np.full(len(xy), lift_m), np.ones(len(xy))])
    return (scene.table_pose @ local.T).T[:, :3]


def _chain_rgb(scene: Scene, plan: Pool) -> np.ndarray:
    colours = chain_colours(scene)
    return np.array([colours[p.chain] for p in plan.postures], dtype=np.uint8).reshape(-1, 3)


def describe(artefact: PlanArtefact, k: int) -> str:
    """One line about posture ``k`` of a pool or selection."""
    posture: Any = artefact.plan.postures[k]
    entry = artefact.entries[k]
    parts = [
        f"{artefact.kind.value} posture {k + 1}/{len(artefact.plan.postures)}",
        f"id {entry.get('pool_id', entry.get('id', k))}",
        posture.chain,
        posture.spot,
    ]
    if artefact.kind == ArtefactKind.SELECTION:
        parts.append(f"IROC rank {entry.get('rank')}, weight {float(entry.get('weight', 0.0)):.4f}")
    parts.append(f"CoM margin {posture.com_margin_m * 1e3:.0f} mm")
    parts.append(f"min distance {posture.min_distance_m * 1e3:.1f} mm")
    return " | ".join(parts[:4]) + "\n" + " | ".join(parts[4:])


class PlanView:
    """A pool or a selection drawn in a viser scene, one posture at a time."""

    def __init__(self, server: viser.ViserServer, artefact: PlanArtefact) -> None:
        self._artefact = artefact
        scene = artefact.scene
        set_scenery(server, scene)
        self._robot = RobotFigure(server, scene.model, robot_meshes(scene), "robot", ROBOT_RGB)
        big = artefact.kind == ArtefactKind.SELECTION
        size = PLAN_POINT_M if big else POOL_POINT_M
        points = contact_points(scene, artefact.plan, size)  # a marker is a disc: lift it out of the table
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
            _chain_rgb(scene, artefact.plan),
            point_size=size,
            point_shape="circle",
        )
        self._points = points
        self._current = server.scene.add_icosphere("/contacts/current", radius=0.018, color=CURRENT_RGB)
        top = scene.table_pose @ np.array([scene.table.size_m[0] / 2, 0.0, 0.45, 1.0])
        self._label = server.scene.add_label("/info", "", position=top[:3], anchor="bottom-center")
        self._server = server

    @property
    def steps(self) -> int:
        """Number of postures."""
        return len(self._artefact.plan.postures)

    def show(self, k: int) -> None:
        """Pose the robot at posture ``k`` and describe it."""
        posture = self._artefact.plan.postures[k]
        self._robot.pose(self._artefact.scene.configuration(np.array(posture.joints)))
        self._current.position = self._points[k] + np.array([0.0, 0.0, 0.01])
        self._label.text = describe(self._artefact, k)

    def frames(self) -> Iterator[float]:
        """Show each posture in turn; yield the playback time (s) it stays on screen."""
        for k in range(self.steps):
            self.show(k)
            yield STEP_S

    def add_controls(self) -> None:
        """A posture slider and the posture's fields, for the live viewer."""
        gui = self._server.gui
        slider = gui.add_slider("posture", min=0, max=max(self.steps - 1, 1), step=1, initial_value=0)
        text = gui.add_markdown("")

        def update(_: object = None) -> None:
            k = min(int(slider.value), self.steps - 1)
            self.show(k)
            text.content = describe(self._artefact, k).replace("\n", " | ").replace(" | ", "  \n")

        slider.on_update(update)
        update()
