"""The component library reference, generated from the classes of :mod:`mbcomp.library`.

A Sphinx extension: when the build starts it writes one page per library component into
``docs/library/generated/`` (role, summary, default picture, a table of parameters with
their default, unit and meaning, a table of ports, and the class's docstring through
autodoc) and the overview table ``docs/library/generated/table.inc``. A page is written only
when its text changed, so a warm rebuild reads nothing again. The pictures come from
:mod:`component_pictures` and are cached (config value ``mbcomp_picture_cache``, default
``docs/_build/.component-pictures``); ``-D mbcomp_pictures=0`` builds without pictures (the
pages say so).

:func:`component_pages` is the generator itself (no Sphinx needed), so a test can check
every page without building the site.

Examples
--------
>>> pages = component_pages(pictures=None)
>>> "Revolute" in pages and "rad" in pages["Revolute"]
True
"""
from __future__ import annotations

import inspect
import os
import pathlib
import shutil

import numpy as np

__all__ = ["library_classes", "component_page", "component_pages", "overview", "setup"]

#: the roles in the order the overview lists them, with their heading
ROLES = {
    "ground": "Ground", "body": "Bodies", "joint": "Joints and contacts", "force": "Force elements and sensors",
    "flange_force": "Laws on an axis (flanges)", "drive": "Drives", "flange_constraint": "Transmissions",
    "flange_inertia": "Rotors", "model": "Assemblies",
}


def library_classes():
    """``{name: class}`` of every name in ``mbcomp.library.__all__`` that is a component."""
    import mbcomp
    import mbcomp.library as library

    return {n: getattr(library, n) for n in library.__all__
            if isinstance(getattr(library, n), type) and issubclass(getattr(library, n), mbcomp.Component)}


def _default(value):
    if value is None:
        return "(optional)"
    if callable(value):
        return f"``{getattr(value, '__name__', repr(value))}``"
    if isinstance(value, (list, tuple, np.ndarray)):
        arr = np.asarray(value)
        if arr.ndim == 2 and arr.shape[0] == arr.shape[1] and np.array_equal(arr, np.eye(len(arr))):
            return "identity"
        if arr.dtype.kind in "fiu":
            return f"``{tuple(arr.tolist()) if arr.ndim == 1 else arr.tolist()}``"
    return f"``{value!r}``"


def _unit(par):
    return "dimensionless" if par.unit in ("1", "") else par.unit


def _cell(text):
    """One list-table cell: a single line, ``-`` when empty."""
    text = " ".join(str(text).split())
    return text if text else "\\-"


def _summary(cls):
    """The docstring's first paragraph."""
    doc = inspect.cleandoc(cls.__dict__.get("__doc__") or "")
    return doc.split("\n\n")[0].strip()


def _table(header, rows):
    out = [".. list-table::", "   :header-rows: 1", ""]
    for row in [header] + rows:
        out.append(f"   * - {_cell(row[0])}")
        out.extend(f"     - {_cell(c)}" for c in row[1:])
    return out


def component_page(name, cls, picture=None, no_picture=None):
    """The reST page of one component: ``picture`` is the picture's path relative to the page
    (``None``: none, ``no_picture`` says why)."""
    role = getattr(cls, "role", None) or "component"
    lines = [f".. _component-{name}:", "", name, "=" * len(name), "",
             f"**{ROLES.get(role, role)}** (role ``{role}``) --- ``mbcomp.library.{name}``"
             f" (defined in ``{cls.__module__}``)", "", _summary(cls), ""]
    if picture:
        lines += [f".. image:: {picture}", f"   :alt: {name} drawn with its default shapes", "   :width: 420px", ""]
    else:
        lines += [f"*No picture: {no_picture}.*", ""]
    params = cls.params()
    lines += ["Parameters", "----------", ""]
    if params:
        lines += _table(("name", "default", "unit", "meaning"),
                        [(f"``{n}``", _default(p.default), _unit(p), p.doc) for n, p in params.items()])
    else:
        lines += ["None."]
    ports = cls.ports()
    lines += ["", "Ports", "-----", ""]
    if ports:
        lines += _table(("name", "kind", "meaning"),
                        [(f"``{n}``", type(p).__name__ + (", optional" if p.optional else ""), p.doc)
                         for n, p in ports.items()])
    else:
        lines += ["None of its own: an assembly is connected through the ports of its parts (see below)."]
    lines += ["", "Reference", "---------", "", f".. autoclass:: mbcomp.library.{name}", ""]
    return "\n".join(lines) + "\n"


def component_pages(pictures=None):
    """``{name: page text}`` of every library component; ``pictures`` maps a name to its
    picture's path relative to the page, or to ``(None, why)``; ``None``: no pictures made."""
    pages = {}
    for name, cls in library_classes().items():
        pic = (pictures or {}).get(name, (None, "not made in this build (``-D mbcomp_pictures=0``)"))
        path, why = (pic, None) if isinstance(pic, str) else pic
        pages[name] = component_page(name, cls, path, why)
    return pages


def overview():
    """The reST of the overview: one table per role, a line per component."""
    classes = library_classes()
    lines = []
    for role, heading in ROLES.items():
        names = [n for n, c in classes.items() if (getattr(c, "role", None) or "component") == role]
        if not names:
            continue
        lines += [heading, "-" * len(heading), ""]
        lines += _table(("component", "what it is"),
                        [(f":ref:`{n} <component-{n}>`", _summary(classes[n]).split(". ")[0]) for n in names])
        lines.append("")
    return "\n".join(lines)


def _write(path, text):
    """Write ``text`` only where it differs (Sphinx re-reads files by their time stamps)."""
    path = pathlib.Path(path)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def _pictures(app, out):
    from component_pictures import picture

    cache = app.config.mbcomp_picture_cache or os.path.join(app.srcdir, "_build", ".component-pictures")
    shown = {}
    (out / "pictures").mkdir(exist_ok=True)
    for name, cls in library_classes().items():
        path, why = picture(cls, cache)
        if path is None:
            shown[name] = (None, why)
            continue
        target = out / "pictures" / f"{name}.png"
        if not target.exists() or target.read_bytes() != pathlib.Path(path).read_bytes():
            shutil.copyfile(path, target)
        shown[name] = f"pictures/{name}.png"
    return shown


def generate(app):
    """``builder-inited``: write the pages (and pictures) into ``library/generated``."""
    out = pathlib.Path(app.srcdir) / "library" / "generated"
    out.mkdir(parents=True, exist_ok=True)
    pictures = _pictures(app, out) if app.config.mbcomp_pictures not in (False, 0, "0", "false", "False") else None
    pages = component_pages(pictures)
    for stale in out.glob("*.rst"):
        if stale.stem not in pages:
            stale.unlink()
    for name, text in pages.items():
        _write(out / f"{name}.rst", text)
    _write(out / "table.inc", overview())


def setup(app):
    app.add_config_value("mbcomp_picture_cache", "", "env")
    app.add_config_value("mbcomp_pictures", True, "env")
    app.connect("builder-inited", generate)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
