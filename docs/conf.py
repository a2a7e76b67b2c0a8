"""Sphinx configuration of posegen's documentation (``make docs``; warnings are errors)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # document the checkout, installed or not
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import sphinxcontrib.katex as katex  # noqa: E402

from posegen import __version__  # noqa: E402

project = "posegen"
author = "posegen contributors"
copyright = "posegen contributors, BSD-3-Clause"
release = version = __version__

extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinxcontrib.katex", "myst_parser"]
source_suffix = {".md": "markdown"}
exclude_patterns = ["_build"]
myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3

autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_default_options = {"members": True}
napoleon_google_docstring = True
napoleon_numpy_docstring = False

# Math is rendered when the site is built (KaTeX, run by node), as MathML the browser draws
# itself: no script, font or stylesheet to fetch, so the equations show offline too.
katex_prerender = True
katex.KATEX_DEFAULT_OPTIONS.update({"output": "mathml", "throwOnError": True})
katex_css_path = "math.css"  # a few lines of layout; KaTeX's own stylesheet is for its HTML output, not used
html_static_path = ["_static"]

html_theme = "furo"
html_title = f"posegen {version}"
