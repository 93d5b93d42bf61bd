"""Sphinx configuration: the model documentation, the user guide and the API reference.

Build: ``python3 -m sphinx -W --keep-going -b html docs build/docs`` (tools/test.sh does this).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

from docutils import nodes

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "python"))  # document the source tree (no build needed to import)

import csfh  # noqa: E402

project = "csfh"
author = "csfh developers"
release = version = csfh.__version__
copyright = "csfh developers"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax copied into the build: no CDN, formulas render offline
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "**/README.md"]
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]  # generated reports (docs/reports/sweep) skip heading levels
default_role = "literal"  # `name` in docstrings is code

autodoc_member_order = "bysource"
autodoc_typehints = "signature"

html_theme = "furo"
html_title = f"csfh {release}"
html_static_path: list[str] = []

_TAG = re.compile(r"\\tag\{")


def _number_equations(app: object, doctree: nodes.document) -> None:
    """Display equations carry their section-based number as \\tag{N.M}. Sphinx wraps a
    multi-line equation in a split environment, where MathJax refuses \\tag; give such equations
    their own equation environment instead (written out as is)."""
    for node in doctree.findall(nodes.math_block):
        latex = node.astext()
        if _TAG.search(latex) and not node.get("nowrap"):
            node["nowrap"] = True
            node.children = [nodes.Text(f"\\begin{{equation}}{latex}\\end{{equation}}")]


def setup(app: object) -> dict[str, object]:
    app.connect("doctree-read", _number_equations)  # type: ignore[attr-defined]
    return {"parallel_read_safe": True}
