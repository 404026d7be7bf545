"""The gallery (``examples/``) runs, and every check it shows holds.

Each sphinx-gallery script ends with ``CHECKS = {label: (error, tolerance)}`` -- its numbers
against a closed form, a published reference or an independent integration -- which it prints
and asserts; here each script runs (as sphinx-gallery runs it, in a temporary folder, matplotlib's Agg backend)
and the test asserts that it ended, that every run it left in its namespace succeeded, and that
every shown error is within its tolerance. A model
file in ``models/`` without its gallery script fails :func:`test_every_model_has_a_gallery_script`.
"""
import os
import pathlib

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
SCRIPTS = sorted(p.relative_to(EXAMPLES).as_posix() for p in EXAMPLES.rglob("plot_*.py"))


def _model_files():
    return sorted(p for p in (ROOT / "models").rglob("*.py") if p.name != "__init__.py")


def test_every_model_has_a_gallery_script():
    """``examples/models/plot_<stem>.py`` for every model file (``models/*.py``, ``models/textbook/*.py``)."""
    missing = [p.relative_to(ROOT).as_posix() for p in _model_files()
               if not (EXAMPLES / "models" / f"plot_{p.stem}.py").exists()]
    assert not missing, f"model files without a gallery script (add examples/models/plot_<name>.py): {missing}"
    extra = [s for s in SCRIPTS if s.startswith("models/")
             and s[len("models/plot_"):-3] not in {p.stem for p in _model_files()}]
    assert not extra, f"gallery scripts of models that no longer exist: {extra}"


def test_gallery_folders_hold_what_sphinx_gallery_needs():
    """Each gallery folder has its README.rst; script names are unique across folders; each
    script opens with a titled docstring."""
    names = [pathlib.PurePath(s).name for s in SCRIPTS]
    assert len(set(names)) == len(names), f"two scripts of one name break sphinx-gallery's links: {sorted(names)}"
    for folder in (EXAMPLES, EXAMPLES / "models", EXAMPLES / "tutorials"):
        assert (folder / "README.rst").exists(), folder
    assert len([s for s in SCRIPTS if s.startswith("tutorials/")]) >= 10
    for script in SCRIPTS:
        text = (EXAMPLES / script).read_text()
        lines = text.split('"""', 2)[1].strip().splitlines()
        assert text.startswith('"""') and len(lines) > 2 and set(lines[1]) == {"="}, \
            f"{script}: starts with a docstring whose first line is the title, underlined with '='"
        assert len(lines[1]) >= len(lines[0]), f"{script}: the title's underline is shorter than the title"


def _run(path):
    """Execute a script as sphinx-gallery does: its code in a fresh namespace named
    ``__main__`` (functions it defines pickle by value, for Dask's workers), with ``__file__``
    set, while ``sys.modules["__main__"]`` stays this process's (``runpy`` would make the
    script the main module, which the worker processes Dask spawns import again)."""
    ns = {"__name__": "__main__", "__file__": os.fspath(path), "__builtins__": __builtins__}
    exec(compile(path.read_text(), os.fspath(path), "exec"), ns)
    return ns


@pytest.mark.parametrize("script", SCRIPTS)
def test_gallery_script(script, tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.chdir(tmp_path)
    try:
        ns = _run(EXAMPLES / script)
    finally:
        plt.close("all")
    from mbcomp.simulation.result import Result

    for name, value in ns.items():  # a run that ended early would leave its checks on a shorter span
        if isinstance(value, Result):
            assert value.success, f"{script}: the run {name!r} ended {value.status}: {value.message}"
    checks = ns.get("CHECKS")
    assert checks, f"{script} shows no CHECKS against a closed form or reference"
    for name, (err, tol) in checks.items():
        assert np.isfinite(err) and err <= tol, f"{script}: {name} = {err:.3g} > {tol:.3g}"
