"""The view of a calibration: nominal and calibrated robot overlaid, residuals as arrows.

At each contact the nominal robot (grey ghost) and the calibrated one (``calibrated.urdf``,
solid) stand at the recorded joint angles. Every contact's height residual is an arrow
from the table top along its normal, magnified ``ARROW_GAIN`` times: grey under the
nominal URDF, and under calibrated.urdf (each as a stack loading it sees it) green within
one noise sigma, amber within three, red beyond. One step per
contact (training, then outliers, then held-out); the live viewer adds a contact
slider, toggles for the arrows and the parameter table.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
import viser

from posegen.calibrate import ContactResidual, ContactSet
from posegen.errors import InputError
from posegen.robot import FloatArray
from posegen.view.artefact import CalibrationArtefact
from posegen.view.robot_figure import RobotFigure, robot_meshes
from posegen.view.scenery import GHOST_RGB, ROBOT_RGB, info_label, set_scenery
from posegen.view.stepped_view import SteppedView

ARROW_GAIN = 20.0  # 1 mm of height residual is drawn 20 mm long
BEFORE_RGB = (140, 140, 140)
GOOD_RGB, FAIR_RGB, BAD_RGB = (40, 160, 70), (240, 170, 40), (215, 40, 40)
GHOST_OPACITY = 0.35


def residual_rgb(height_m: FloatArray, noise_m: float) -> np.ndarray:
    """Arrow colour per contact by |height residual| in noise sigmas (1, 3). Shape (n, 3) uint8."""
    sigmas = np.abs(height_m) / max(noise_m, 1e-12)
    rgb = np.where(sigmas[:, None] <= 1.0, GOOD_RGB, np.where(sigmas[:, None] <= 3.0, FAIR_RGB, BAD_RGB))
    return np.asarray(rgb, dtype=np.uint8)


def describe(contact: ContactResidual, k: int, n: int) -> str:
    """One line about contact ``k`` of ``n`` and its residuals (mm, deg)."""

    def shown(r: FloatArray) -> str:
        if not np.all(np.isfinite(r[1:])):  # a point contact measures its height only
            return f"{r[0] * 1e3:+.2f} mm"
        return f"{r[0] * 1e3:+.2f} mm, {np.rad2deg(r[1]):+.3f} / {np.rad2deg(r[2]):+.3f} deg"

    return (
        f"contact {k + 1}/{n}: {contact.label} ({contact.set.value}, {contact.chain}, {contact.session}, "
        f"{contact.kind.value})\n"
        f"before {shown(contact.before)} | after {shown(contact.after)}"
    )


class CalibrationView(SteppedView):
    """A calibration drawn in a viser scene, one contact at a time."""

    STEP_NAME = "contact"

    def __init__(self, server: viser.ViserServer, artefact: CalibrationArtefact) -> None:
        super().__init__(server)
        self._artefact = artefact
        nominal, calibrated = artefact.nominal, artefact.calibrated
        record = artefact.record
        if record.joint_names != nominal.joint_names:
            raise InputError(f"{record.directory}: the residual table's joints are not the robot's")
        if not record.contacts:
            raise InputError(f"{record.directory}: no contacts")
        order = list(ContactSet)  # training, outliers, held-out
        self._contacts = sorted(record.contacts, key=lambda c: order.index(c.set))
        set_scenery(server, nominal)
        meshes = robot_meshes(nominal)
        self._ghost = RobotFigure(server, nominal.model, meshes, "nominal", GHOST_RGB, opacity=GHOST_OPACITY)
        self._robot = RobotFigure(server, calibrated.model, meshes, "calibrated", ROBOT_RGB)
        self.arrows = self._residual_arrows(server)
        self._label = info_label(server, nominal)

    def _residual_arrows(self, server: viser.ViserServer) -> tuple[viser.ArrowsHandle, viser.ArrowsHandle]:
        scene = self._artefact.calibrated
        data = scene.model.createData()
        frames = {c.name: scene.frame_id(c.frame(c.contact_kind)) for c in scene.chains}
        normal = scene.table_pose[:3, 2]
        top = scene.table_pose[:3, 3]
        bases = []
        for contact in self._contacts:
            pin.framesForwardKinematics(scene.model, data, scene.configuration(contact.joints))
            point = np.array(data.oMf[frames[contact.chain]].translation)
            bases.append(point - ((point - top) @ normal) * normal)  # on the table top
        base = np.array(bases)  # (n, 3)
        side = 0.006 * scene.table_pose[:3, 0]  # before and after side by side
        before = np.array([c.before[0] for c in self._contacts])
        after = np.array([c.after[0] for c in self._contacts])
        noise = float((self._artefact.record.report.get("noise") or {}).get("contact", {}).get("z_mm", 1.0)) * 1e-3

        def arrows(name: str, height: FloatArray, offset: FloatArray, rgb: np.ndarray) -> viser.ArrowsHandle:
            tips = base + offset + ARROW_GAIN * height[:, None] * normal
            points = np.stack([base + offset, tips], axis=1)  # (n, 2, 3)
            return server.scene.add_arrows(name, points, rgb, shaft_radius=0.002, head_radius=0.005, head_length=0.008)

        return (
            arrows("/residuals/before", before, -side, np.tile(np.array(BEFORE_RGB, dtype=np.uint8), (len(base), 1))),
            arrows("/residuals/after", after, side, residual_rgb(after, noise)),
        )

    @property
    def steps(self) -> int:
        """Number of contacts."""
        return len(self._contacts)

    def show(self, k: int) -> None:
        """Both robots at contact ``k``, and its residuals."""
        contact = self._contacts[k]
        self._ghost.pose(self._artefact.nominal.configuration(contact.joints))
        self._robot.pose(self._artefact.calibrated.configuration(contact.joints))
        self._label.text = self.describe(k)

    def describe(self, k: int) -> str:
        """Contact ``k`` and its residuals in words."""
        return describe(self._contacts[k], k, self.steps)

    def add_controls(self) -> None:
        """The contact slider, toggles for the arrows and the parameter table, for the live viewer."""
        super().add_controls()
        gui = self._server.gui
        before, after = (gui.add_checkbox(f"residuals {w}", initial_value=True) for w in ("before", "after"))
        before.on_update(lambda _: setattr(self.arrows[0], "visible", before.value))
        after.on_update(lambda _: setattr(self.arrows[1], "visible", after.value))
        with gui.add_folder("identified parameters", expand_by_default=False):
            gui.add_markdown(parameter_markdown(self._artefact.record.report.get("parameters") or []))


def displayed(row: dict[str, Any]) -> tuple[float, float, str]:
    """A parameter-table row's deviation from the URDF and posterior std, and their unit (mm, deg or rad/kNm)."""
    return float(row.get("deviation", 0.0)), float(row.get("std", 0.0)), str(row.get("unit", ""))


def parameter_markdown(rows: list[dict[str, Any]]) -> str:
    """The report's parameter table as Markdown: deviation and posterior std in mm or deg."""
    lines = ["| parameter | deviation | std |", "|---|---|---|"]
    for row in rows:
        deviation, std, unit = displayed(row)
        lines.append(f"| {row.get('name')} | {deviation:+.3f} {unit} | {std:.3f} {unit} |")
    return "\n".join(lines)
