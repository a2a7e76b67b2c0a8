"""The view of a route: the robot moving in real time, the contact frame's swept path.

The trajectory is sampled at ``fps`` frames per second of robot time (joint angles
interpolated linearly between the route's points) and played back in real time: the
HTML page's playback bar plays, pauses, scrubs and changes speed; the live viewer has
a time slider, a play button and a speed choice. The swept path of the active chain's
contact frame is drawn coloured by segment type; the current segment is named in a
label; skipped postures are marked on the table with their reason.
"""

from __future__ import annotations

import itertools
import threading
from collections.abc import Iterator

import numpy as np
import pinocchio as pin
import viser

from posegen.io import Segment, SegmentType
from posegen.robot import FloatArray
from posegen.view.artefact import RouteArtefact
from posegen.view.postures_view import contact_points
from posegen.view.robot_figure import RobotFigure, robot_meshes
from posegen.view.scenery import ROBOT_RGB, chain_colours, info_label, set_scenery

FPS = 15.0  # frames per second of robot time in the HTML page
SEGMENT_RGB = {
    SegmentType.FREE: (150, 150, 150),
    SegmentType.APPROACH: (240, 170, 40),
    SegmentType.GO_TO_CONTACT: (215, 40, 40),
    SegmentType.HOLD: (110, 20, 110),
    SegmentType.RELEASE: (40, 160, 70),
}
SKIPPED_RGB = (160, 0, 0)
SPEEDS = ("0.25", "0.5", "1", "2", "4")


def sample_times(times: FloatArray, fps: float) -> FloatArray:
    """Frame times (s) from the first to the last point of a route, ``fps`` per second. Shape (f,)."""
    frames = np.arange(times[0], times[-1], 1.0 / fps)
    return np.append(frames, times[-1])


def interpolate(times: FloatArray, positions: FloatArray, at: FloatArray) -> FloatArray:
    """Joint angles at times ``at`` by linear interpolation between route points. Shape (f, nj)."""
    k = np.clip(np.searchsorted(times, at, side="right") - 1, 0, len(times) - 2)
    span = times[k + 1] - times[k]
    alpha = np.clip((at - times[k]) / np.where(span > 0, span, 1.0), 0.0, 1.0)[:, None]
    return (1.0 - alpha) * positions[k] + alpha * positions[k + 1]


def segment_chains(segments: tuple[Segment, ...]) -> list[str | None]:
    """The chain each segment serves: its own, or (free motions) that of the posture it goes to."""
    chains: list[str | None] = []
    for i, seg in enumerate(segments):
        chain = seg.chain
        if chain is None and seg.posture is not None:
            chain = next((s.chain for s in segments[i + 1 :] if s.posture == seg.posture and s.chain), None)
        chains.append(chain)
    return chains


def describe(segment: Segment, chain: str | None) -> str:
    """One line about a route segment."""
    kind = segment.type.value.replace("_", " ")
    if segment.posture is None:
        return f"{kind} | back to the start posture | {segment.start_s:.1f}-{segment.end_s:.1f} s"
    return (
        f"{kind} | posture {segment.posture} (pool {segment.pool_id}, {chain}) | "
        f"{segment.start_s:.1f}-{segment.end_s:.1f} s"
    )


class RouteView:
    """A route drawn in a viser scene and played in real time."""

    def __init__(self, server: viser.ViserServer, artefact: RouteArtefact, fps: float = FPS) -> None:
        self._artefact = artefact
        self._server = server
        scene = artefact.scene
        set_scenery(server, scene)
        self._robot = RobotFigure(server, scene.model, robot_meshes(scene), "robot", ROBOT_RGB)
        self._chains = segment_chains(artefact.segments)
        self._starts = np.array([s.start_s for s in artefact.segments])
        self._swept_path(server)
        self._skipped(server)
        self._label = info_label(server, scene)
        self._shown_segment = -1
        self._closed = threading.Event()
        self._player: threading.Thread | None = None
        self.times = sample_times(artefact.times, fps)

    def _swept_path(self, server: viser.ViserServer) -> None:
        scene, route = self._artefact.scene, self._artefact
        data = scene.model.createData()
        frames = {c.name: scene.frame_id(c.frame(c.contact_kind)) for c in scene.chains}
        lines, colours, holds, hold_rgb = [], [], [], []
        palette = chain_colours(scene)
        for seg, chain in zip(route.segments, self._chains, strict=True):
            if chain is None:
                continue
            inside = np.flatnonzero((route.times >= seg.start_s) & (route.times <= seg.end_s))
            path = []
            for k in inside:
                pin.framesForwardKinematics(scene.model, data, scene.configuration(route.positions[k]))
                path.append(np.array(data.oMf[frames[chain]].translation))
            if seg.type == SegmentType.HOLD and path:
                holds.append(path[0])
                hold_rgb.append(palette[chain])
            for a, b in itertools.pairwise(path):
                lines.append((a, b))
                colours.append((SEGMENT_RGB[seg.type], SEGMENT_RGB[seg.type]))
        if lines:
            server.scene.add_line_segments(
                "/route/path", np.array(lines), np.array(colours, dtype=np.uint8), thickness=0.004
            )
        if holds:
            server.scene.add_point_cloud(
                "/route/contacts", np.array(holds), np.array(hold_rgb, dtype=np.uint8), point_size=0.02
            )

    def _skipped(self, server: viser.ViserServer) -> None:
        route = self._artefact
        if route.selection is None or not route.skipped:
            return
        points = contact_points(route.scene, route.selection)
        for i, entry in enumerate(route.skipped):
            k = entry.get("posture")
            if not isinstance(k, int) or not 0 <= k < len(points):
                continue
            server.scene.add_icosphere(f"/route/skipped/{i}", radius=0.02, color=SKIPPED_RGB, position=points[k])
            server.scene.add_label(
                f"/route/skipped/{i}/why",
                f"skipped posture {k}: {entry.get('reason', '')}",
                position=(0.0, 0.0, 0.03),
                font_screen_scale=0.7,
            )

    def show(self, t: float) -> None:
        """Pose the robot at time ``t`` (s) of the route and name the current segment."""
        route = self._artefact
        joints = interpolate(route.times, route.positions, np.array([t]))[0]
        self._robot.pose(route.scene.configuration(joints))
        k = int(np.clip(np.searchsorted(self._starts, t, side="right") - 1, 0, len(self._starts) - 1))
        if k != self._shown_segment:
            self._label.text = describe(route.segments[k], self._chains[k])
            self._shown_segment = k

    def frames(self) -> Iterator[float]:
        """Show each frame in turn; yield the playback time (s) until the next one."""
        for t, dt in zip(self.times, np.append(np.diff(self.times), 0.0), strict=True):
            self.show(float(t))
            yield float(dt)

    def add_controls(self) -> None:
        """Time slider, play/pause and speed, for the live viewer (a thread advances the time)."""
        gui = self._server.gui
        end = float(self.times[-1])
        slider = gui.add_slider("time (s)", min=0.0, max=end, step=0.01, initial_value=0.0)
        playing = gui.add_checkbox("play", initial_value=False)
        speed = gui.add_dropdown("speed", SPEEDS, initial_value="1")
        slider.on_update(lambda _: self.show(float(slider.value)))
        self.show(0.0)
        period = 1.0 / FPS

        def advance() -> None:
            while not self._closed.wait(period):
                if playing.value:
                    # viser's setter is not declared next to its getter, so mypy sees a read-only property
                    slider.value = (float(slider.value) + period * float(speed.value)) % end  # type: ignore[misc]

        self._player = threading.Thread(target=advance, daemon=True)
        self._player.start()

    def close(self) -> None:
        """Stop playing (the live viewer is closing)."""
        self._closed.set()
        if self._player is not None:
            self._player.join(timeout=5.0)
