"""The views' pages (of the shared selection and route) and a decoder of what a page plays."""

from __future__ import annotations

import base64
import re
from pathlib import Path
from typing import Any

import msgspec
import numpy as np
import pinocchio as pin
import pytest
import zstandard

from posegen.view import Page, html_page, open_artefact


def recording(html: str) -> dict[str, Any]:
    """The scene recording a viser page carries: ``durationSeconds`` and ``messages`` [(time s, message)]."""
    found = re.search(r'window\.__VISER_EMBED_DATA__="([^"]+)"', html)
    assert found, "no embedded scene"
    raw = base64.b64decode(found.group(1))
    size = int.from_bytes(raw[:8], "little")
    inner = zstandard.ZstdDecompressor().decompress(raw[8:], max_output_size=size)
    length = int.from_bytes(inner[:8], "little")
    decoded: dict[str, Any] = msgspec.msgpack.decode(inner[8 : 8 + length])
    return decoded


def messages_of(page: dict[str, Any], kind: str) -> list[tuple[float, dict[str, Any]]]:
    """The recorded messages of one type, with their times."""
    return [(t, m) for t, m in page["messages"] if m.get("type") == kind]


def labels(page: dict[str, Any]) -> list[tuple[float, str]]:
    """Every label text the page shows, with the time it appears."""
    updates = messages_of(page, "SceneNodeUpdateMessage")
    return [(t, m["updates"]["text"]) for t, m in updates if "text" in m["updates"]]


@pytest.fixture(scope="session")
def selection_page(selection_file: Path) -> Page:
    return html_page(open_artefact(selection_file))


@pytest.fixture(scope="session")
def route_page(route_file: Path) -> Page:
    return html_page(open_artefact(route_file))


def node_poses(page: dict[str, Any], until_s: float) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Every node's local pose (position, wxyz) once the page has played up to ``until_s``."""
    poses: dict[str, list[np.ndarray]] = {}
    for t, message in page["messages"]:
        if t > until_s:
            break
        name = message.get("name")
        if message["type"] == "SetPositionMessage":
            poses.setdefault(name, [np.zeros(3), np.array([1.0, 0, 0, 0])])[0] = np.array(message["position"])
        elif message["type"] == "SetOrientationMessage":
            poses.setdefault(name, [np.zeros(3), np.array([1.0, 0, 0, 0])])[1] = np.array(message["wxyz"])
    return {name: (p[0], p[1]) for name, p in poses.items()}


def world_pose(poses: dict[str, tuple[np.ndarray, np.ndarray]], name: str) -> pin.SE3:
    """A node's world pose: its ancestors' local poses composed, root first."""
    parts = name.strip("/").split("/")
    out = pin.SE3.Identity()
    for depth in range(1, len(parts) + 1):
        node = "/" + "/".join(parts[:depth])
        if node in poses:
            position, (w, x, y, z) = poses[node]
            out = out * pin.SE3(pin.Quaternion(w, x, y, z).toRotationMatrix(), position)
    return out
