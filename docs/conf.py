"""Sphinx configuration: API reference from numpydoc docstrings and the
example gallery from examples/plot_*.py."""
import os
from importlib.metadata import version as _version

project = "sklearn_pnlss"
author = "sklearn_pnlss developers"
copyright = "2026, sklearn_pnlss developers"
release = _version("sklearn_pnlss")

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]
autosummary_generate = True
numpydoc_show_class_members = False
exclude_patterns = ["_build"]
html_theme = "alabaster"

sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    # Examples really run; set SPHINX_GALLERY_PLOT=0 to build the text only.
    "plot_gallery": os.environ.get("SPHINX_GALLERY_PLOT", "True"),
}
