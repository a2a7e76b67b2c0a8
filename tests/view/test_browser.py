"""The views in a real browser: headless Chromium draws the robot, steps, and needs no network.

``make test`` installs Debian's ``chromium-headless-shell`` when it is missing (as root,
with apt-get); where it cannot, these tests are skipped and say so.
"""

import threading
import time

import numpy as np
import pytest

from posegen.view import open_artefact, serve, write_html
from tests.view.chromium import Browser, find_browser, robot_pixels

BROWSER = find_browser()
pytestmark = pytest.mark.skipif(
    BROWSER is None,
    reason="no headless Chromium (chromium-headless-shell or chromium): `make test` installs it with apt-get as root",
)
MIN_ROBOT_PIXELS = 500  # of 640 x 480: the robot fills 4,000-7,000
MIN_CHANGED_PIXELS = 1000


def changed_pixels(a, b):
    return int((np.abs(a.astype(int) - b.astype(int)).sum(axis=2) > 30).sum())


def assert_robot_drawn(image):
    assert image.std() > 10, "uniform screenshot"
    assert robot_pixels(image) >= MIN_ROBOT_PIXELS


def step_through(browser, first, second, timeout_s=30.0):
    """Screenshots at two values typed into the page's number field (playback time, or a slider).

    The second is taken once the picture has changed, or after ``timeout_s``.
    """
    browser.seek(first)
    time.sleep(1.0)  # the player (or the live server) applies it on its next tick
    before = browser.screenshot()
    browser.seek(second)
    deadline = time.monotonic() + timeout_s
    while True:
        time.sleep(0.25)
        after = browser.screenshot()
        if changed_pixels(before, after) > MIN_CHANGED_PIXELS or time.monotonic() > deadline:
            return before, after


@pytest.fixture(scope="module")
def offline():
    """A browser that cannot reach any server: every request goes to a closed port."""
    assert BROWSER is not None
    with Browser(BROWSER, offline=True) as browser:
        yield browser


def test_selection_page_shows_the_robot_and_steps_through_postures(selection_file, offline, tmp_path):
    page = tmp_path / "selection.html"
    write_html(open_artefact(selection_file), page)
    offline.open(page.as_uri())
    assert_robot_drawn(offline.wait_for_robot())
    n = len(open_artefact(selection_file).postures.postures)
    first, other = step_through(offline, 0.5, n - 0.5)
    assert_robot_drawn(first)
    assert_robot_drawn(other)
    assert changed_pixels(first, other) > MIN_CHANGED_PIXELS
    assert offline.network_requests() == []


def test_route_page_shows_the_robot_moving(route_file, offline, tmp_path):
    page = tmp_path / "route.html"
    artefact = open_artefact(route_file)
    write_html(artefact, page)
    offline.open(page.as_uri())
    assert_robot_drawn(offline.wait_for_robot())
    holds = [s for s in artefact.segments if s.type.value == "hold"]
    first, other = step_through(offline, 0.0, (holds[0].start_s + holds[0].end_s) / 2)
    assert_robot_drawn(first)
    assert_robot_drawn(other)
    assert changed_pixels(first, other) > MIN_CHANGED_PIXELS
    assert offline.network_requests() == []


def test_live_viewer_moves_the_robot_when_the_slider_moves(selection_file):
    assert BROWSER is not None
    urls: list[str] = []
    stop = threading.Event()
    server = threading.Thread(
        target=serve, kwargs={"artefact": open_artefact(selection_file), "port": 0, "ready": urls.append, "stop": stop}
    )
    server.start()
    try:
        deadline = time.monotonic() + 60
        while not urls and time.monotonic() < deadline:
            time.sleep(0.1)
        assert urls and urls[0].startswith("http://127.0.0.1:")
        with Browser(BROWSER) as browser:
            browser.open(urls[0])
            assert_robot_drawn(browser.wait_for_robot())
            first, other = step_through(browser, 0, 20)  # the posture slider's number field
            assert changed_pixels(first, other) > MIN_CHANGED_PIXELS
            assert_robot_drawn(other)
    finally:
        stop.set()
        server.join(timeout=30)
    assert not server.is_alive()
