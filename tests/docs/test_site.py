"""The documentation site builds with no warning, and holds a page for every public name and
every library component, with its parameters' units and its picture.

The build is the README's command (``python -m sphinx -W -b html docs ...``) run on a copy of
``docs/`` and ``examples/`` in a temporary folder (the build writes generated pages beside its
sources), without running the gallery's scripts (``-D plot_gallery=0``: they run as tests of
their own). The component pictures are drawn into a cache shared by the runs on this machine
(keyed on the classes' source, so a second run draws none; a cold run draws them all in a
few seconds). Skipped, saying which, where a package of the ``docs`` extra is missing.
"""
import importlib.util
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile

import numpy as np
import pytest

import mbcomp

ROOT = pathlib.Path(__file__).resolve().parents[2]
PACKAGES = {"sphinx": "sphinx", "numpydoc": "numpydoc", "myst_parser": "myst-parser",
            "sphinx_gallery": "sphinx-gallery", "pydata_sphinx_theme": "pydata-sphinx-theme"}
MISSING = [dist for mod, dist in PACKAGES.items() if importlib.util.find_spec(mod) is None]
pytestmark = pytest.mark.skipif(bool(MISSING), reason=f"the docs extra is not installed (no {', '.join(MISSING)}): "
                                                      "pip install -e '.[docs]'")
GENERATED = ("_build", "auto_examples", "generated", "sg_execution_times.rst", "__pycache__")


def build_site(tree):
    """``(html folder, stderr)`` of the site built from a copy of docs/ and examples/ in ``tree``."""
    for name in ("docs", "examples"):
        shutil.copytree(ROOT / name, tree / name, ignore=shutil.ignore_patterns(*GENERATED))
    cache = pathlib.Path(tempfile.gettempdir()) / f"mbcomp-docs-pictures-{os.getuid()}"
    out = tree / "html"
    cmd = [sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html", "-D", "plot_gallery=0",
           "-D", f"mbcomp_picture_cache={cache}", str(tree / "docs"), str(out)]
    env = dict(os.environ, MPLBACKEND="Agg")
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, f"the docs build failed or warned:\n{done.stderr[-4000:]}"
    return out, done.stderr


def _text(path):
    import html
    import re

    return html.unescape(re.sub(r"<[^>]+>", " ", path.read_text()))


def test_the_site_builds_with_a_page_per_public_name_and_component_and_their_pictures(tmp_path):
    """One test, so that the build runs once under ``pytest -n 2`` (tests of one file may go
    to both workers)."""
    out, stderr = build_site(tmp_path)
    check_pages(out, stderr)
    check_api_pages(out)
    check_library_pages(out)
    check_pictures(out)


def check_pages(out, stderr):
    assert "WARNING" not in stderr and "ERROR" not in stderr, stderr[-3000:]
    for page in ("index", "getting-started", "components", "concepts/formulations", "concepts/solvers",
                 "concepts/singular", "concepts/events", "concepts/fmu", "concepts/studies",
                 "concepts/derivatives", "concepts/units", "concepts/robots", "design/hybrid", "architecture",
                 "library/index", "api/index", "api/modules", "auto_examples/index",
                 "auto_examples/tutorials/plot_first_pendulum"):
        assert (out / f"{page}.html").is_file(), f"no page {page}.html"


def check_api_pages(out):
    missing = [n for n in mbcomp.__all__ if not (out / "api" / "generated" / f"mbcomp.{n}.html").is_file()]
    assert not missing, f"no API page for mbcomp.{missing}: add them to docs/api/index.rst"
    # a class's page documents its methods: Model.connect, Result.to_csv with its example
    assert 'id="mbcomp.Model.connect"' in (out / "api" / "generated" / "mbcomp.Model.html").read_text()
    result = (out / "api" / "generated" / "mbcomp.Result.html").read_text()
    assert 'id="mbcomp.Result.to_csv"' in result and "Examples" in result


def _rows(path):
    """The rows of every table of an HTML page, as lists of cell texts."""
    import re

    rows = []
    for row in re.findall(r"<tr[^>]*>(.*?)</tr>", path.read_text(), re.S):
        cells = re.findall(r"<t[dh][^>]*>(.*?)</t[dh]>", row, re.S)
        rows.append([" ".join(_text_of(c).split()) for c in cells])
    return rows


def _text_of(fragment):
    import html
    import re

    return html.unescape(re.sub(r"<[^>]+>", " ", fragment))


def _components():
    import mbcomp.library as library

    return {n: getattr(library, n) for n in library.__all__
            if isinstance(getattr(library, n), type) and issubclass(getattr(library, n), mbcomp.Component)}


def check_library_pages(out):
    components = _components()
    assert len(components) >= 45
    for name, cls in components.items():
        page = out / "library" / "generated" / f"{name}.html"
        assert page.is_file(), f"no library page for {name}"
        rows = {r[0]: r[1:] for r in _rows(page) if r}
        for pname, par in cls.params().items():
            unit = "dimensionless" if par.unit in ("1", "") else par.unit
            assert pname in rows, f"{name}: parameter {pname} has no row on its page"
            assert rows[pname][1] == unit, f"{name}.{pname}: the page says unit {rows[pname][1]!r}, the class {unit!r}"
        for port, decl in cls.ports().items():
            assert port in rows and rows[port][0].startswith(type(decl).__name__), f"{name}: port {port} is not listed"


def check_pictures(out):
    from matplotlib.image import imread

    drawn = 0
    for name, cls in _components().items():
        draws = cls.visuals is not mbcomp.Component.visuals or name in ("RollingDisk", "RollingSphere")
        text = _text(out / "library" / "generated" / f"{name}.html")
        png = out / "_images" / f"{name}.png"
        if not draws:
            assert "No picture" in text and not png.exists(), f"{name} draws nothing: its page should say so"
            continue
        assert png.is_file(), f"{name} draws shapes of its own but has no picture"
        rgb = (imread(png)[..., :3] * 255).astype(np.int64)
        # something is drawn: more colours than the white page, the grey panes and black text
        colours = np.unique(rgb[..., 0] << 16 | rgb[..., 1] << 8 | rgb[..., 2])
        assert len(colours) > 20, f"{name}'s picture is (nearly) blank"
        drawn += 1
    assert drawn >= 20
