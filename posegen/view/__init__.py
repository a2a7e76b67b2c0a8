"""The 3D view of every artefact, live or as one self-contained HTML page, and the calibration report.

Above the stages (it reads the artefacts of every one of them) and below the CLI.
Pools and selections step through their postures, routes play in real time,
calibrations overlay the nominal and the calibrated robot with the residual at each
contact. Drawn with viser: its browser client ships in the Python wheel, so a page
holds the client, the meshes and the animation and opens offline.

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions.
"""

from posegen.extras import Extra, require

require(Extra.VIEW, "the viewer (3D views, the calibration report)")

from posegen.view.artefact import (
    Artefact,
    ArtefactKind,
    CalibrationArtefact,
    PosturesArtefact,
    RouteArtefact,
    open_artefact,
)
from posegen.view.report_page import REPORT_FILE, report_html, write_report, write_report_into
from posegen.view.robot_figure import MeshSource, RobotFigure, RobotMeshes, robot_meshes
from posegen.view.scenery import ROBOT_RGB, Camera, framing
from posegen.view.viewer import DEFAULT_HOST, DEFAULT_PORT, Page, html_page, serve, write_html, write_html_file

__all__ = [
    "DEFAULT_HOST",
    "DEFAULT_PORT",
    "REPORT_FILE",
    "ROBOT_RGB",
    "Artefact",
    "ArtefactKind",
    "CalibrationArtefact",
    "Camera",
    "MeshSource",
    "Page",
    "PosturesArtefact",
    "RobotFigure",
    "RobotMeshes",
    "RouteArtefact",
    "framing",
    "html_page",
    "open_artefact",
    "report_html",
    "robot_meshes",
    "serve",
    "write_html",
    "write_html_file",
    "write_report",
    "write_report_into",
]
