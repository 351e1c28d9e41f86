"""Sphinx configuration of dpm's documentation site.

Built with ``python -m sphinx -W --keep-going -b html docs docs/_build/html``. The pages
are Markdown (MyST), so they read the same on GitHub and on the site; the API reference
comes from the docstrings (autodoc, numpy style through napoleon).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import dpm  # noqa: E402

project = "dpm"
author = "dpm developers"
copyright = "dpm developers, MIT licence"
release = dpm.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
]

source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "render", "**/README.md"]

# MyST: anchors for the headings (the pages link to #sections), $...$ maths,
# definition lists; ``` fences without a language are plain text.
myst_heading_anchors = 4
myst_enable_extensions = ["dollarmath", "deflist"]

# autodoc: members in source order, the signature in the heading, type hints in the
# description; napoleon reads the numpy-style sections.
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "show-inheritance": True}
napoleon_numpy_docstring = True
napoleon_google_docstring = False

html_theme = "furo"
html_title = f"dpm {release}"
html_static_path: list[str] = []
