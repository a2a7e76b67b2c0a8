"""The documentation site covers the code: every package has its API page, every page is in the site.

``make docs`` builds it with warnings as errors (``.ci/run``); these checks run in ``make test``.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def toctree(page: Path) -> set[str]:
    blocks = re.findall(r"```\{toctree\}\n(.*?)```", page.read_text(), flags=re.S)
    return {line.strip() for block in blocks for line in block.splitlines() if line.strip() and ":" not in line}


def test_every_package_and_top_level_module_has_an_api_page():
    code = {p.parent.name for p in (ROOT / "posegen").glob("*/__init__.py")} - {"cli"}
    code |= {"errors", "extras", "resources", "api"}
    pages = {p.stem for p in (DOCS / "api").glob("*.md")}
    assert code == pages
    assert {f"api/{name}" for name in code} == toctree(DOCS / "api.md")
    for name in code:
        assert f".. automodule:: posegen.{name}\n" in (DOCS / "api" / f"{name}.md").read_text()


def test_every_page_is_in_the_site():
    pages = {p.stem for p in DOCS.glob("*.md")} - {"index"}
    assert toctree(DOCS / "index.md") == pages
    for wanted in ("getting-started", "concepts", "robots", "commands", "formats", "deploying", "benchmarks"):
        assert wanted in pages
    assert "guarantees" in pages
