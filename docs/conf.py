"""Sphinx configuration of railcontact's documentation site.

Build (warnings are errors, no network needed)::

    pip install -e ".[docs]"
    sphinx-build -W --keep-going -b html docs docs/_build/html

Pages are Markdown (myst-parser); the API reference is generated from the docstrings
(autodoc + autosummary, numpydoc sections); the theme is the PyData theme, as numpy, scipy
and xarray use.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import railcontact  # noqa: E402  (autodoc imports it; numba compiles nothing on import)

project = "railcontact"
author = "the railcontact authors"
copyright = "the railcontact authors, Apache-2.0"  # noqa: A001
version = release = railcontact.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "**/.ipynb_checkpoints", "warmstart_study.md"]

# --- Markdown --------------------------------------------------------------------------
myst_enable_extensions = ["colon_fence", "dollarmath", "deflist"]
myst_heading_anchors = 4  # [text](page.md#a-heading) links resolve to the heading

# --- API reference ---------------------------------------------------------------------
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"show-inheritance": False}
autodoc_typehints = "none"  # the signatures and the numpydoc sections say the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_attributes_as_param_list = False

# --- No network: no intersphinx, no remote assets ---------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"railcontact {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
# The guide's pages have no sub-pages: no empty "Section Navigation" beside them.
html_sidebars = {"*": [], "api/**": ["sidebar-nav-bs"]}
html_static_path: list[str] = []
html_show_sourcelink = False


def _skip_type_aliases(app, what, name, obj, skip, options):
    """Type aliases (``Bounds = tuple[float, ...]``) are not API: autodoc cannot sign them."""
    import types

    if isinstance(obj, types.GenericAlias):
        return True
    return None


def setup(app):
    app.connect("autodoc-skip-member", _skip_type_aliases)
