"""``Result.animate`` and ``Result.snapshot``: the scene of a result, written as the file its
suffix asks for -- a self-contained HTML player (:mod:`mbcomp.visual.html`), a GIF or MP4 film
or a picture drawn by matplotlib (:mod:`mbcomp.visual.render`).

Examples
--------
>>> suffix_kind("crank.HTML"), suffix_kind("crank.gif"), suffix_kind("t1.png")
('html', 'film', 'picture')
"""
from __future__ import annotations

import os

from .scene import build_scene

__all__ = ["animate", "snapshot", "suffix_kind"]

HTML, FILMS, PICTURES = (".html", ".htm"), (".gif", ".mp4"), (".png", ".svg", ".pdf", ".jpg", ".jpeg")


def suffix_kind(path):
    """``"html"``, ``"film"`` or ``"picture"`` by the file's suffix; a ``ValueError`` naming the
    suffixes otherwise."""
    ext = os.path.splitext(os.fspath(path))[1].lower()
    for kind, exts in (("html", HTML), ("film", FILMS), ("picture", PICTURES)):
        if ext in exts:
            return kind
    raise ValueError(f"cannot write {os.fspath(path)!r}: unknown suffix {ext or '(none)'!r} -> an animation is "
                     f"{', '.join(HTML + FILMS)}; a snapshot is {', '.join(PICTURES)}")


def animate(res, path, hide=(), trails=(), color_by=None, fps=25, speed=1.0, title=None):
    """Write ``res`` as an HTML player or a film (see :meth:`mbcomp.result.Result.animate`);
    returns ``path``."""
    kind = suffix_kind(path)
    if kind == "picture":
        raise ValueError(f"{os.fspath(path)!r} is a picture -> use res.snapshot(path, t=...) for one frame, or "
                         f"animate to {', '.join(HTML + FILMS)}")
    if not speed > 0 or not fps > 0:
        raise ValueError(f"speed={speed!r} and fps={fps!r} must be positive numbers")
    scene = build_scene(res, hide=hide, trails=trails, color_by=color_by, title=title)
    if kind == "html":
        from .html import write_html

        return write_html(scene, path, speed=speed)
    from .render import write_film

    return write_film(scene, path, fps=fps, speed=speed)


def snapshot(res, path, t=None, hide=(), trails=(), color_by=None, title=None):
    """Write the frame of ``res`` at time ``t`` (s; the last output by default) as a picture
    (see :meth:`mbcomp.result.Result.snapshot`); returns ``path``."""
    if suffix_kind(path) != "picture":
        raise ValueError(f"{os.fspath(path)!r} is no picture -> a snapshot is {', '.join(PICTURES)}; "
                         "use res.animate(path) for an animation")
    scene = build_scene(res, hide=hide, trails=trails, color_by=color_by, title=title)
    from .render import write_picture

    return write_picture(scene, path, t=t)
