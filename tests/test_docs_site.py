"""The built documentation site shows its equations offline (headless Chromium, network closed).

Needs the site (``make docs``): ``.ci/run`` builds it, then runs this file with
``POSEGEN_DOCS_SITE=1``, which turns a missing site or browser into a failure; in ``make
test`` (before the site is built) it is skipped.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.view.chromium import Browser, find_browser

SITE = Path(__file__).resolve().parents[1] / "docs" / "_build" / "html"
REQUIRED = os.environ.get("POSEGEN_DOCS_SITE") == "1"
PAGES = ("deploying.html", "concepts.html")  # the compensation formula; the method's equations


@pytest.fixture(scope="module")
def browser():
    executable = find_browser()
    if not SITE.is_dir() or executable is None:
        reason = "no built site (make docs)" if not SITE.is_dir() else "no headless Chromium"
        if REQUIRED:
            pytest.fail(reason)
        pytest.skip(reason)
    with Browser(executable, width=1000, height=800, offline=True) as opened:
        yield opened


@pytest.mark.parametrize("page", PAGES)
def test_equations_are_drawn_without_the_network(browser, page):
    browser.open((SITE / page).as_uri())
    drawn = browser.evaluate(
        "Array.from(document.querySelectorAll('div.math math, span.math math'))"
        ".map(m => { const r = m.getBoundingClientRect(); return [r.width, r.height]; })"
    )
    assert drawn, f"{page}: no equation in the page"
    assert all(width > 5 and height > 5 for width, height in drawn), drawn  # laid out by the browser itself
    text = browser.evaluate("document.querySelector('article').innerText")
    for raw in ("$$", "\\frac", "\\tau", "\\text{"):
        assert raw not in text, f"{page}: raw LaTeX {raw!r} shown"
    assert browser.network_requests() == []  # nothing fetched from outside: the site works offline
