"""Sphinx configuration of the rockdec documentation (build: see the README's last section)."""

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))

import rockdec  # noqa: E402

project = "rockdec"
author = "the rockdec authors"
copyright = "the rockdec authors, MIT licence"
release = rockdec.__version__
version = release

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.intersphinx",
    "numpydoc",
    "sphinxarg.ext",
    "sphinx_copybutton",
    "rockdec_docs",
]

# Pages that are only included into others (the generated study tables) are not pages of their own.
exclude_patterns = ["_build", "generated", "**/_includes", ".venv", "Thumbs.db", ".DS_Store"]
smartquotes = False  # `--theta-cr` stays two hyphens
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}

# MyST: heading anchors so that `page.md#section` links are checked by Sphinx.
myst_enable_extensions = ["colon_fence", "deflist", "dollarmath"]
myst_heading_anchors = 4

# myst-nb: execute the tutorial at every build (cheap: a short record, a cached calibration).
nb_execution_mode = "force"
nb_execution_timeout = 300
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True
# The command-line reference prints each option's default as the parser computes it; the
# calibration cache's is this variable, else the user's cache folder: say so, not this
# machine's path. The tutorial caches its calibration in docs/_build/rockdec-cache.
os.environ["ROCKDEC_CACHE"] = "$ROCKDEC_CACHE, else the user cache folder"

# API reference: one page per name of rockdec.__all__, written by docs/_ext/rockdec_docs.py.
autosummary_generate = False
autosummary_imported_members = True
autodoc_typehints = "none"
autodoc_default_options = {"members": True, "show-inheritance": False}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks = set()

intersphinx_mapping = {}  # no network at build time: external names are not cross-linked

# nitpicky (-n): every internal reference must resolve. Names of other libraries that appear
# in signatures and types are not ours to document.
# The public API's docstrings may name the modules behind it, which the site does not document
# page by page (their layers: docs/development/layout.md).
nitpick_ignore_regex = [
    (r"py:.*", r"rockdec\.(physics|rdd|record|calibrate|report|pipeline|studies|cli|io|console|sources|timeaxis|validate|api|cache|engine)(\..*)?"),
    (r"py:.*", r"(numpy|np|xarray|xr|pandas|pd|matplotlib|os|pathlib|collections|typing|dataclasses)\..*"),
    (r"py:class", r"(optional|default.*|array.*|ndarray|float|int|str|bool|dict|list|tuple|None|callable|path-like|.*-like)"),
]

html_theme = "pydata_sphinx_theme"
html_title = f"rockdec {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_static_path = []
html_last_updated_fmt = None
copybutton_prompt_text = r"\$ |>>> "
copybutton_prompt_is_regexp = True
suppress_warnings = ["mystnb.unknown_mime_type"]
