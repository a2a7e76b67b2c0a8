"""Headless Chromium driven through the DevTools protocol over a pipe (no extra package).

Chromium is started with ``--remote-debugging-pipe``: it reads JSON commands on file
descriptor 3 and writes replies and events on 4, each message ended by a NUL byte.
Used by the viewer's browser tests and by ``make bench`` (time to first frame).
"""

from __future__ import annotations

import base64
import contextlib
import io
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from posegen.view import ROBOT_RGB

BROWSERS = ("chromium-headless-shell", "chromium")
LOCAL_SCHEMES = ("file:", "data:", "blob:", "about:")


def find_browser() -> str | None:
    """Path of a headless-capable Chromium (``POSEGEN_CHROMIUM`` first), or None."""
    named = os.environ.get("POSEGEN_CHROMIUM")
    if named:
        return shutil.which(named) or (named if Path(named).is_file() else None)
    for name in BROWSERS:
        found = shutil.which(name)
        if found:
            return found
    return None


def robot_pixels(image: np.ndarray, rgb: tuple[int, int, int] = ROBOT_RGB, tolerance: float = 0.06) -> int:
    """Pixels of an (h, w, 3) image in the robot's colour, whatever their shading.

    A pixel counts when its chromaticity (rgb / sum) is within ``tolerance`` of the robot
    colour's and it is not near black: lighting scales a colour, it does not turn grey,
    beige, green or orange into blue.
    """
    pixels = image.reshape(-1, 3).astype(float)
    total = pixels.sum(axis=1)
    lit = total > 60
    chroma = pixels[lit] / total[lit, None]
    target = np.array(rgb, dtype=float) / sum(rgb)
    return int((np.abs(chroma - target).max(axis=1) < tolerance).sum())


class Browser:
    """One headless Chromium with one page, driven by DevTools commands.

    Args:
        executable: The browser.
        width, height: Viewport (px).
        offline: Route every network request to a closed local port and resolve no host
            name, so that a page needing the network cannot get it.

    """

    def __init__(self, executable: str, width: int = 640, height: int = 480, offline: bool = False) -> None:
        self._profile = tempfile.mkdtemp(prefix="posegen-chromium-")
        args = [
            executable,
            "--headless",
            "--remote-debugging-pipe",
            "--no-sandbox",
            "--no-first-run",
            "--disable-gpu",
            "--enable-unsafe-swiftshader",
            "--mute-audio",
            f"--user-data-dir={self._profile}",
            f"--window-size={width},{height}",
        ]
        if offline:
            args += [
                "--proxy-server=http://127.0.0.1:9",  # nothing listens there
                "--proxy-bypass-list=<-loopback>",
                "--host-resolver-rules=MAP * ~NOTFOUND",
            ]
        child_in, to_browser = os.pipe()
        from_browser, child_out = os.pipe()

        def wire() -> None:  # in the child: the pipe ends on descriptors 3 and 4
            read, write = os.dup(child_in), os.dup(child_out)
            os.dup2(read, 3)
            os.dup2(write, 4)

        self._process = subprocess.Popen(
            [*args, "about:blank"],
            preexec_fn=wire,
            close_fds=False,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(child_in)
        os.close(child_out)
        self._send_pipe = os.fdopen(to_browser, "wb", buffering=0)
        self._read_pipe = os.fdopen(from_browser, "rb", buffering=0)
        self._buffer = b""
        self._next_id = 0
        self.events: list[dict[str, Any]] = []
        target = self.command("Target.createTarget", url="about:blank")["targetId"]
        self._session = self.command("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        self.command("Page.enable", session=True)
        self.command("Network.enable", session=True)
        metrics = {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}
        self.command("Emulation.setDeviceMetricsOverride", session=True, **metrics)

    def _message(self) -> dict[str, Any]:
        while b"\0" not in self._buffer:
            chunk = self._read_pipe.read(1 << 16)
            if not chunk:
                raise RuntimeError("the browser closed its DevTools pipe")
            self._buffer += chunk
        raw, self._buffer = self._buffer.split(b"\0", 1)
        message: dict[str, Any] = json.loads(raw)
        return message

    def command(self, method: str, session: bool = False, **params: Any) -> dict[str, Any]:
        """Send a DevTools command and return its result (events seen meanwhile are kept)."""
        self._next_id += 1
        message: dict[str, Any] = {"id": self._next_id, "method": method, "params": params}
        if session:
            message["sessionId"] = self._session
        self._send_pipe.write(json.dumps(message).encode() + b"\0")
        while True:
            reply = self._message()
            if reply.get("id") == self._next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                result: dict[str, Any] = reply.get("result", {})
                return result
            self.events.append(reply)

    def open(self, url: str, timeout_s: float = 60.0) -> None:
        """Load a page and wait for its load event."""
        seen = len(self.events)
        self.command("Page.navigate", session=True, url=url)
        end = time.monotonic() + timeout_s
        while not any(e.get("method") == "Page.loadEventFired" for e in self.events[seen:]):
            if time.monotonic() > end:
                raise TimeoutError(f"{url} did not load in {timeout_s} s")
            self.events.append(self._message())

    def evaluate(self, expression: str) -> Any:
        """The value of a JavaScript expression in the page."""
        result = self.command("Runtime.evaluate", session=True, expression=expression, returnByValue=True)
        return result.get("result", {}).get("value")

    def screenshot(self) -> np.ndarray:
        """The page as an (h, w, 3) uint8 image."""
        data = self.command("Page.captureScreenshot", session=True, format="png")["data"]
        return np.asarray(Image.open(io.BytesIO(base64.b64decode(data))).convert("RGB"))

    def wait_for_robot(self, minimum: int = 500, timeout_s: float = 180.0) -> np.ndarray:
        """Screenshots until one shows at least ``minimum`` robot pixels; return it."""
        end = time.monotonic() + timeout_s
        while True:
            image = self.screenshot()
            if robot_pixels(image) >= minimum:
                return image
            if time.monotonic() > end:
                raise TimeoutError(f"no robot drawn within {timeout_s} s")
            time.sleep(0.25)

    def seek(self, seconds: float) -> None:
        """Type a time into a viser page's playback field: the page jumps there and pauses."""
        focused = self.evaluate(
            "(() => { const f = document.querySelector('input[inputmode=decimal]');"
            " if (!f) return false; f.focus(); f.select(); return true; })()"
        )
        if not focused:
            raise RuntimeError("no playback time field in the page")
        self.command("Input.insertText", session=True, text=f"{seconds:g}")
        self.evaluate("document.activeElement.blur()")

    def requests(self) -> list[str]:
        """URLs of every request the page made."""
        return [e["params"]["request"]["url"] for e in self.events if e.get("method") == "Network.requestWillBeSent"]

    def network_requests(self) -> list[str]:
        """Requests that would leave the machine (anything but file, data, blob and about URLs)."""
        return [url for url in self.requests() if not url.startswith(LOCAL_SCHEMES)]

    def close(self) -> None:
        """Stop the browser."""
        with contextlib.suppress(RuntimeError, OSError):
            self.command("Browser.close")
        try:
            self._process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self._process.kill()
            self._process.wait()
        self._send_pipe.close()
        self._read_pipe.close()
        shutil.rmtree(self._profile, ignore_errors=True)

    def __enter__(self) -> Browser:
        return self

    def __exit__(self, *_: object) -> None:
        self.close()
