"""Sphinx configuration: user guide, API reference from the numpydoc
docstrings, and the example gallery from examples/plot_*.py.

Build (from the repository root; ``-W`` turns warnings into errors, as the
test suite does)::

    python -m sphinx -W -b html docs docs/_build/html

``SPHINX_GALLERY_PLOT=0`` builds the gallery pages without running the
examples.
"""
import os
import sys
from importlib.metadata import version as _version

# For _gallery_order (the gallery's sort key, named by its import path).
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

project = "sklearn_pnlss"
author = "sklearn_pnlss developers"
copyright = "2026, sklearn_pnlss developers"
release = _version("sklearn_pnlss")
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]
templates_path = ["_templates"]
exclude_patterns = ["_build", "_templates"]
html_theme = "alabaster"
html_theme_options = {"description": "Nonlinear system identification with scikit-learn's API"}

# API pages: one per module, listing what its __all__ exports (see
# _templates/autosummary/module.rst), so that a new public name is documented
# as soon as it is exported.
autosummary_generate = True
autosummary_ignore_module_all = False
autosummary_imported_members = True
autodoc_default_options = {"member-order": "bysource"}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
# No intersphinx: the build must work offline (CI, the test suite), and an
# unreachable inventory is a warning, an error under -W.

sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "within_subsection_order": "_gallery_order.GalleryOrder",
    # Examples really run; set SPHINX_GALLERY_PLOT=0 to build the text only.
    "plot_gallery": os.environ.get("SPHINX_GALLERY_PLOT", "True"),
    # The per-example timing page is rewritten on every build: not a source.
    "write_computation_times": False,
    "download_all_examples": False,
}
