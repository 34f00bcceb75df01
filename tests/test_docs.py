"""The documentation builds without a warning, and its API reference covers
every public module.

The build runs sphinx with ``-W`` on a copy of ``docs/`` and ``examples/`` in
a temporary folder, so that the generated pages never land in the source
tree. It sets ``SPHINX_GALLERY_PLOT=0``: the gallery pages are built from the
examples' text and code without running them, because tests/test_examples.py
already runs every example as a script in this same suite (running them
twice would double the suite's longest part). A full build with the examples
run is ``python -m sphinx -W -b html docs docs/_build/html``.
"""
import importlib
import inspect
import os
import pkgutil
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import sklearn_pnlss

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
EXAMPLES = sorted((ROOT / "examples").glob("plot_*.py"))
USER_GUIDE = ["conventions", "bla", "pnlss", "decoupling", "selection", "models", "command_line", "gap"]
# Packages that are not part of the API (docs/api.rst, "Internals"): what the
# estimators are made of, and the application behind ``python -m sklearn_pnlss``.
INTERNAL = ["sklearn_pnlss.app", "sklearn_pnlss.decoupling", "sklearn_pnlss.frequency", "sklearn_pnlss.statespace",
            "sklearn_pnlss.utils"]


@pytest.fixture(scope="module")
def built_docs(tmp_path_factory):
    pytest.importorskip("sphinx", reason="the docs build needs the test extra (pip install -e '.[test]')")
    tmp = tmp_path_factory.mktemp("docs")
    shutil.copytree(DOCS, tmp / "docs",
                    ignore=shutil.ignore_patterns("_build", "generated", "auto_examples", "sg_execution_times.rst"))
    shutil.copytree(ROOT / "examples", tmp / "examples")
    env = dict(os.environ, SPHINX_GALLERY_PLOT="0", MPLBACKEND="Agg")
    result = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         "-d", str(tmp / "doctrees"), str(tmp / "docs"), str(tmp / "html")],
        cwd=tmp, env=env, capture_output=True, text=True, timeout=600,
    )
    return result, tmp / "html"


def test_docs_build_without_warnings(built_docs):
    result, html = built_docs
    assert result.returncode == 0, f"sphinx -W failed:\n{result.stderr[-5000:]}"
    assert "WARNING" not in result.stderr, result.stderr[-5000:]
    for page in ["index", "install", "api", *(f"user_guide/{name}" for name in USER_GUIDE)]:
        assert (html / f"{page}.html").is_file(), page
    # Every example has its gallery page, with its code.
    for script in EXAMPLES:
        page = html / "auto_examples" / f"{script.stem}.html"
        assert page.is_file(), script.name
    text = (html / "auto_examples" / "plot_getting_started.html").read_text()
    assert "make_bouc_wen" in text and "summary" in text


def test_api_pages_document_the_estimators_methods(built_docs):
    result, html = built_docs
    assert result.returncode == 0
    page = (html / "generated" / "sklearn_pnlss.PNLSSRegressor.html").read_text()
    for method in ("fit", "predict", "score", "summary", "to_statespace"):
        assert f"sklearn_pnlss.PNLSSRegressor.{method}" in page, method
    # The user guide's formulas reach the page as math.
    assert 'class="math' in (html / "user_guide" / "bla.html").read_text()


def _is_internal(name):
    return any(name == pkg or name.startswith(f"{pkg}.") for pkg in INTERNAL)


def _public_modules():
    """Every importable module of the package without a private component,
    outside the internal packages."""
    names = ["sklearn_pnlss"]
    for info in pkgutil.walk_packages(sklearn_pnlss.__path__, "sklearn_pnlss."):
        if not any(part.startswith("_") for part in info.name.split(".")) and not _is_internal(info.name):
            names.append(info.name)
    return names


def _documented_modules():
    """Modules listed in the autosummary tables of docs/api.rst, and the
    packages among them listed with ``:recursive:`` (whose pages list their
    submodules too)."""
    modules, recursive = [], []
    for block in (DOCS / "api.rst").read_text().split(".. autosummary::")[1:]:
        names = re.findall(r"^\s{3}(sklearn_pnlss(?:\.\w+)*)\s*$", block, flags=re.M)
        modules += names
        if re.search(r"^\s+:recursive:\s*$", block, flags=re.M):
            recursive += names
    return modules, recursive


def test_api_reference_covers_every_public_module():
    """Each public module is listed in docs/api.rst (its page then lists its
    whole ``__all__``), or is a submodule of a package listed with
    ``:recursive:``, or everything it exports is exported by a listed module
    (the re-exporting package documents it)."""
    listed, recursive = _documented_modules()
    documented = listed + [name for name in _public_modules() if any(name.startswith(f"{pkg}.") for pkg in recursive)]
    exported = set()
    for name in listed:
        module = importlib.import_module(name)
        assert hasattr(module, "__all__"), f"{name} is documented but has no __all__ to list"
        exported |= {id(getattr(module, item)) for item in module.__all__}
    missing = []
    for name in _public_modules():
        module = importlib.import_module(name)
        public = [item for item in getattr(module, "__all__", [])
                  if inspect.isclass(getattr(module, item)) or inspect.isfunction(getattr(module, item))]
        if name not in documented and any(id(getattr(module, item)) not in exported for item in public):
            missing.append(name)
    assert not missing, f"public modules missing from docs/api.rst: {missing}"


def test_internal_packages_say_so_and_are_not_published():
    """Each internal package's docstring says it may change without notice,
    the API reference names it under "Internals" and publishes no page of
    it."""
    listed, _ = _documented_modules()
    assert not [name for name in listed if _is_internal(name)]
    api = (DOCS / "api.rst").read_text()
    internals = api[api.index("\nInternals\n"):]
    for name in INTERNAL:
        assert f"``{name}``" in internals, name
        doc = " ".join((importlib.import_module(name).__doc__ or "").split())
        assert "may change without notice" in doc, name


def test_readme_documents_the_docs_command():
    """The README's documented command is the one this suite checks."""
    readme = (ROOT / "README.md").read_text()
    assert "python -m sphinx -W -b html docs docs/_build/html" in readme


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_examples_run_without_file_too(script):
    """sphinx-gallery runs an example without ``__file__`` (tests/test_examples.py
    runs them as scripts, with it): an example that needs it must fall back."""
    text = script.read_text()
    if "__file__" in text:
        assert '"__file__" in globals()' in text, f"{script.name} uses __file__ without a fallback"
