"""Showing an artefact: as one self-contained HTML page, or live from a local server.

Both build the same viser scene. The page records it with viser's scene serializer:
every step of the view becomes a time on the page's playback bar, and the page holds
the viser client, the meshes and the animation (no server, no network). The live
viewer serves the scene on ``host:port`` and adds controls (sliders, play, toggles).
"""

from __future__ import annotations

import contextlib
import io
import socket
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import viser

from posegen.errors import InputError
from posegen.io import check_apart, check_writable, claim_output, write_atomic
from posegen.view.artefact import Artefact, CalibrationArtefact, PosturesArtefact, RouteArtefact, open_artefact
from posegen.view.calibration_view import CalibrationView
from posegen.view.postures_view import PosturesView
from posegen.view.route_view import RouteView

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8080


class View(Protocol):
    """What every view of an artefact does."""

    def frames(self) -> Iterator[float]:
        """Show each step in turn; yield the playback time (s) until the next."""
        ...

    def add_controls(self) -> None:
        """Add the live viewer's controls."""
        ...

    def close(self) -> None:
        """Stop whatever the controls started."""
        ...


@dataclass(frozen=True)
class Page:
    """An artefact's view as one self-contained HTML page."""

    html: str
    steps: int  # steps recorded (postures, frames or contacts)
    duration_s: float  # length of the page's playback
    build_s: float  # building the scene and recording every step
    serialize_s: float  # encoding and compressing the recording into the page

    @property
    def size_bytes(self) -> int:
        """Size of the page (UTF-8)."""
        return len(self.html.encode())


def _view(server: viser.ViserServer, artefact: Artefact) -> View:
    if isinstance(artefact, PosturesArtefact):
        return PosturesView(server, artefact)
    if isinstance(artefact, RouteArtefact):
        return RouteView(server, artefact)
    assert isinstance(artefact, CalibrationArtefact)
    return CalibrationView(server, artefact)


def check_host(host: str) -> None:
    """Check that the viewer can listen on ``host``: an address of this machine (viser would retry forever).

    Example:
        >>> check_host("127.0.0.1")

    Raises:
        InputError: ``host`` does not resolve, or is no address of this machine.

    """
    try:
        family, kind, proto, _, address = socket.getaddrinfo(host, 0, type=socket.SOCK_STREAM)[0]
    except (OSError, UnicodeError) as exc:
        raise InputError(f"host: cannot resolve '{host}' ({exc})", parameter="host") from exc
    with socket.socket(family, kind, proto) as probe:
        try:
            probe.bind(address)
        except OSError as exc:
            raise InputError(
                f"host: cannot listen on '{host}' ({exc.strerror}): give an address of this machine", parameter="host"
            ) from exc


@contextlib.contextmanager
def local_server(host: str = DEFAULT_HOST, port: int = 0) -> Iterator[viser.ViserServer]:
    """A viser server (port 0: any free port), its start and stop banners kept out of the caller's output."""
    with contextlib.redirect_stdout(io.StringIO()):
        server = viser.ViserServer(host=host, port=port, verbose=False)
    try:
        yield server
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()


def html_page(artefact: Artefact) -> Page:
    """The view of an artefact as one self-contained HTML page (the viser client, meshes and animation).

    Raises:
        PosegenError: The artefact cannot be drawn.

    """
    start = time.perf_counter()
    with local_server() as server:
        view = _view(server, artefact)
        serializer = server.get_scene_serializer()
        steps, duration = 0, 0.0
        with server.atomic():  # one wake-up of viser's event loop, not one per message
            for dt in view.frames():
                serializer.insert_sleep(dt)
                steps += 1
                duration += dt
        built = time.perf_counter()
        html = serializer.as_html()
    return Page(html, steps, duration, built - start, time.perf_counter() - built)


def write_html(artefact: Artefact, path: str | Path) -> Page:
    """Write an artefact's view as one self-contained HTML page (atomically, the page locked) and return it.

    Raises:
        PosegenError: The artefact cannot be drawn, or the page cannot be written.

    """
    with claim_output(path):
        page = html_page(artefact)
        write_atomic(path, page.html)
    return page


def write_html_file(artefact_path: str | Path, path: str | Path, config_path: str | None = None) -> Page:
    """``posegen view ARTEFACT --html FILE``: the page's place is checked before the artefact is read.

    Raises:
        PosegenError: The page cannot be written, or the artefact cannot be read or drawn.

    """
    check_writable(path)
    check_apart([path], [artefact_path, config_path])
    return write_html(open_artefact(artefact_path, config_path), path)


def serve(
    artefact: Artefact,
    host: str = DEFAULT_HOST,
    port: int = DEFAULT_PORT,
    ready: Callable[[str], None] | None = None,
    stop: threading.Event | None = None,
) -> None:
    """Serve an artefact's view live until ``stop`` is set (or forever).

    Args:
        artefact: What to show.
        host: Address to listen on (default: this machine only).
        port: Port; the next free one is taken if it is busy.
        ready: Told the viewer's URL once it is up.
        stop: Ends the server when set.

    Raises:
        InputError: ``host`` is no address of this machine.

    """
    check_host(host)
    with local_server(host, port) as server:
        view = _view(server, artefact)
        view.add_controls()
        try:
            if ready is not None:
                ready(f"http://{host}:{server.get_port()}/")
            (stop or threading.Event()).wait()
        finally:
            view.close()
