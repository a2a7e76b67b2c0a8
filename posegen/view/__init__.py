"""The 3D view of every artefact, live or as one self-contained HTML page, and the calibration report.

Above the stages (it reads the artefacts of every one of them) and below the CLI.
Pools and selections step through their postures, routes play in real time,
calibrations overlay the nominal and the calibrated robot with the residual at each
contact. Drawn with viser: its browser client ships in the Python wheel, so a page
holds the client, the meshes and the animation and opens offline.

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions. They load at first use, and
only then need ``posegen[view]``: a worker that draws the report's figures imports
:mod:`posegen.view.report_figures` (matplotlib) without viser or trimesh.
"""

from importlib import import_module
from typing import TYPE_CHECKING, Any

from posegen.extras import Extra, require

if TYPE_CHECKING:  # the names' own types for type checkers; at run time they load at first use
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

_HOMES = {  # public name -> the module that defines it (imported at first use, after the extra is checked)
    "Artefact": "posegen.view.artefact",
    "ArtefactKind": "posegen.view.artefact",
    "CalibrationArtefact": "posegen.view.artefact",
    "PosturesArtefact": "posegen.view.artefact",
    "RouteArtefact": "posegen.view.artefact",
    "open_artefact": "posegen.view.artefact",
    "REPORT_FILE": "posegen.view.report_page",
    "report_html": "posegen.view.report_page",
    "write_report": "posegen.view.report_page",
    "write_report_into": "posegen.view.report_page",
    "MeshSource": "posegen.view.robot_figure",
    "RobotFigure": "posegen.view.robot_figure",
    "RobotMeshes": "posegen.view.robot_figure",
    "robot_meshes": "posegen.view.robot_figure",
    "ROBOT_RGB": "posegen.view.scenery",
    "Camera": "posegen.view.scenery",
    "framing": "posegen.view.scenery",
    "DEFAULT_HOST": "posegen.view.viewer",
    "DEFAULT_PORT": "posegen.view.viewer",
    "Page": "posegen.view.viewer",
    "html_page": "posegen.view.viewer",
    "serve": "posegen.view.viewer",
    "write_html": "posegen.view.viewer",
    "write_html_file": "posegen.view.viewer",
}

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


def __getattr__(name: str) -> Any:
    """A public name, imported from its module at first use (PEP 562), once the viewer's packages are there.

    Raises:
        ExtraError: viser or trimesh is not installed (``posegen[view]``).

    """
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'posegen.view' has no attribute {name!r}")
    require(Extra.VIEW, "the viewer (3D views, the calibration report)")
    value = getattr(import_module(home), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_HOMES])
