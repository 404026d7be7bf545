"""Sphinx configuration of mbcomp's documentation site.

Build (from the repository root; ``pip install -e ".[docs]"`` first)::

    python -m sphinx -W -b html docs docs/_build/html

``-D plot_gallery=0`` builds without running the gallery's scripts; ``-D mbcomp_pictures=0``
without drawing the component library's pictures (they are cached in
``docs/_build/.component-pictures`` either way).
"""
import os
import sys
import warnings

import matplotlib

matplotlib.use("Agg")  # the gallery's and the component pictures' figures: no display

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "_ext"))

import mbcomp  # noqa: E402  (the installed package: pip install -e .)

project = "mbcomp"
author = "the mbcomp developers"
copyright = "the mbcomp developers, MIT licence"
release = version = mbcomp.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "components",  # docs/_ext/components.py: the component library reference, generated
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "**.ipynb_checkpoints", "auto_examples/**/*.ipynb", "auto_examples/**/*.py",
                    "auto_examples/**/*.zip", "auto_examples/**/*.json", "auto_examples/**/*.md5"]
templates_path = ["_templates"]

# the Markdown pages (the modelling guide, the design notes) through MyST: `#section` links
# inside and across pages resolve to headings down to level 3
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]

# API reference: autosummary writes a stub per name (api/generated/, not kept in git);
# numpydoc renders the docstrings (mbcomp's are numpydoc throughout)
autosummary_generate = True
autosummary_imported_members = False
autodoc_typehints = "none"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks = set()

# the gallery (examples/, written as sphinx-gallery scripts: plot_*.py)
sphinx_gallery_conf = {
    "examples_dirs": ["../examples"],
    "gallery_dirs": ["auto_examples"],
    "filename_pattern": r"/plot_",
    "subsection_order": ["../examples/tutorials", "../examples/models", "*"],  # "*": any other folder
    "within_subsection_order": "FileNameSortKey",
    "image_scrapers": ("matplotlib",),
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
}

html_theme = "pydata_sphinx_theme"
html_title = "mbcomp"
html_static_path = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 7,
}
html_sidebars = {"index": [], "getting-started": []}


# A component's docstring has a "Ports" section (its frames and flanges, written by
# mbcomp.modeling.docstring); numpydoc knows no such section and would drop it with a warning.
# Ports are class attributes (``joint.frame_a``), so before numpydoc reads the docstring
# (priority 400 < numpydoc's 500) the section is renamed "Attributes", or merged into the
# Attributes section where the class writes one.
def _ports_as_attributes(app, what, name, obj, options, lines):
    if "Ports" not in lines:
        return
    i = lines.index("Ports")
    if i + 1 >= len(lines) or set(lines[i + 1]) != {"-"}:
        return
    end = i + 2
    while end < len(lines) and not (end + 1 < len(lines) and lines[end + 1] and set(lines[end + 1]) == {"-"}
                                    and lines[end] and not lines[end].startswith(" ")):
        end += 1
    entries = [ln for ln in lines[i + 2:end]]
    while entries and not entries[-1].strip():
        entries.pop()
    if "Attributes" in lines and set(lines[lines.index("Attributes") + 1] or "x") == {"-"}:
        del lines[i:end]
        j = lines.index("Attributes") + 2
        while j < len(lines) and not (j + 1 < len(lines) and lines[j + 1] and set(lines[j + 1]) == {"-"}):
            j += 1
        while j > 0 and not lines[j - 1].strip():
            j -= 1
        lines[j:j] = entries
    else:
        lines[i:i + 2] = ["Attributes", "----------"]


# numpydoc's signature hook reads the raw docstring too and says so as a Python warning (not a
# Sphinx one); the section is rendered (as above), so exactly that message is silenced.
warnings.filterwarnings("ignore", message="Unknown section Ports", category=UserWarning)


def setup(app):
    app.connect("autodoc-process-docstring", _ports_as_attributes, priority=400)
