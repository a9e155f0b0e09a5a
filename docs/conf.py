"""Sphinx configuration of the maglevkit documentation site (``make docs``).

The user guide is the Markdown pages of this folder (MyST); the API reference is generated
at build time from the ``__all__`` of every public subpackage, so it always lists exactly
what the package exports; the example gallery runs the scripts in ``examples/``
(sphinx-gallery) and embeds their figures.
"""

from __future__ import annotations

import importlib
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "src"))
os.environ.setdefault("MPLBACKEND", "Agg")

import maglevkit  # noqa: E402

project = "maglevkit"
author = "the maglevkit developers"
copyright = "2026, the maglevkit developers"  # noqa: A001
release = maglevkit.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store"]
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3
# The Markdown pages link to source files of the repository (../src/..., ../benchmarks/...);
# those are not pages of the site, so unresolved relative links are not warnings here.
suppress_warnings = ["myst.xref_missing", "myst.header"]

autodoc_typehints = "none"          # numpydoc renders the documented types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_validation_checks: set[str] = set()
autosummary_generate = True

html_theme = "furo"
html_title = f"maglevkit {release}"

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "gallery",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
}

# ---------------------------------------------------------------------------------------
# API reference: one page per public subpackage, listing its ``__all__``
# ---------------------------------------------------------------------------------------
API_MODULES = ("maglevkit", "maglevkit.materials", "maglevkit.circuit", "maglevkit.magnets",
               "maglevkit.models", "maglevkit.reduction", "maglevkit.reduced",
               "maglevkit.simulation", "maglevkit.plant", "maglevkit.calibration",
               "maglevkit.design", "maglevkit.control", "maglevkit.vehicle", "maglevkit.compare",
               "maglevkit.export", "maglevkit.sweep", "maglevkit.errors")


def public_names(module_name: str) -> list[str]:
    """The names a module exports (its ``__all__``, else what it defines), dunders left out."""
    module = importlib.import_module(module_name)
    names = getattr(module, "__all__", None)
    if names is None:
        names = [n for n, obj in vars(module).items()
                 if not n.startswith("_") and getattr(obj, "__module__", None) == module_name]
    return [n for n in names if not n.startswith("__")]


def home_module(name: str) -> str:
    """The first subpackage (in :data:`API_MODULES` order) that exports ``name``."""
    for module_name in API_MODULES[1:]:
        if name in public_names(module_name):
            return module_name
    return API_MODULES[0]


def write_api_pages(out: Path) -> None:
    """Write ``api/<module>.rst`` with an autosummary table of the module's public names.

    Each object gets its page once, under the subpackage that exports it; the top-level
    page lists the package's shortcuts with links to those pages.
    """
    out.mkdir(parents=True, exist_ok=True)
    for module_name in API_MODULES:
        names = public_names(module_name)
        if module_name == API_MODULES[0]:
            # relative to the package (autosummary refuses names that repeat the current module)
            entries = [f"   ~{home_module(n).removeprefix(module_name + '.')}.{n}"
                       for n in names if home_module(n) != module_name]
            table = [".. autosummary::", "", *entries]
        else:
            table = [".. autosummary::", "   :toctree: generated", "", *[f"   {n}" for n in names]]
        title = f"``{module_name}``"
        lines = [title, "=" * len(title), "", f".. automodule:: {module_name}", "   :no-members:",
                 "", f".. currentmodule:: {module_name}", "", *table, ""]
        text = "\n".join(lines)
        page = out / f"{module_name}.rst"
        if not page.exists() or page.read_text() != text:
            page.write_text(text)


write_api_pages(HERE / "api")
