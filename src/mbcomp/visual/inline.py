"""The HTML player shown inline in a notebook: ``res.animate()`` with no path.

:class:`InlinePlayer` holds the self-contained player page (:func:`mbcomp.visual.html.page`:
three.js, the player and the scene inlined). A notebook (Jupyter, VS Code, sphinx-gallery's
HTML) shows it through ``_repr_html_``: an ``<iframe srcdoc="...">`` holding the page, so its
scripts run in a document of their own (the player's import map must come before any module
script of its document, which a notebook page has long loaded; and its page-wide styles stay
out of the notebook's).
:meth:`InlinePlayer.save` writes the same page to a file, as ``res.animate("x.html")`` does.

Examples
--------
>>> p = InlinePlayer("<!DOCTYPE html><p>a & b</p>", title="demo")
>>> p._repr_html_().startswith('<iframe srcdoc="&lt;!DOCTYPE html&gt;&lt;p&gt;a &amp; b')
True
"""
from __future__ import annotations

import html
import os

__all__ = ["InlinePlayer", "inline_player"]


class InlinePlayer:
    """A player page a notebook shows inline (module notes).

    Parameters
    ----------
    page : str
        The player's HTML page (:func:`mbcomp.visual.html.page`).
    title : str, optional
        The iframe's title (for screen readers).
    height : int
        The iframe's height in CSS pixels; its width is the cell's.

    Attributes
    ----------
    page : str
        The page.

    Examples
    --------
    >>> import os, tempfile
    >>> p = InlinePlayer("<!DOCTYPE html><title>x</title>", height=300)
    >>> 'height: 300px' in p._repr_html_()
    True
    >>> open(p.save(os.path.join(tempfile.mkdtemp(), "x.html"))).read() == p.page
    True
    """

    def __init__(self, page, title=None, height=480):
        if not (isinstance(height, int) and height > 0):
            raise ValueError(f"height={height!r} must be a positive whole number of pixels")
        self.page, self.title, self.height = page, title, height

    def _repr_html_(self):
        """The player as an ``<iframe srcdoc=...>`` (the page escaped into the attribute)."""
        title = html.escape(self.title or "mbcomp animation", quote=True)
        return (f'<iframe srcdoc="{html.escape(self.page, quote=True)}" title="{title}" '
                f'style="width: 100%; height: {self.height}px; border: 1px solid #ddd;" '
                'allow="fullscreen" loading="lazy"></iframe>')

    def save(self, path):
        """Write the page to ``path`` (``.html``; its folder must exist); returns ``path``."""
        folder = os.path.dirname(os.path.abspath(os.fspath(path)))
        if not os.path.isdir(folder):
            raise FileNotFoundError(f"cannot write {os.fspath(path)!r}: its folder {folder!r} does not exist -> "
                                    "create it first (os.makedirs)")
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(self.page)
        return path

    def __repr__(self):
        return f"InlinePlayer({self.title or 'mbcomp animation'!r}, {len(self.page)} characters of HTML)"


def inline_player(res, hide=(), trails=(), color_by=None, speed=1.0, title=None, height=480):
    """The :class:`InlinePlayer` of a run (:meth:`mbcomp.result.Result.animate` with no path).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, Revolute, PointMass, FixedTranslation
    >>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute(n=(0, 0, 1), phi0=1.0))
    >>> rod = m.add("rod", FixedTranslation(r=(1, 0, 0))); bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> p = inline_player(mbcomp.simulate(m, t_end=0.5), title="pendulum")
    >>> 'id=&quot;mbcomp-scene&quot;' in p._repr_html_()
    True
    """
    from .html import page
    from .scene import build_scene

    scene = build_scene(res, hide=hide, trails=trails, color_by=color_by, title=title)
    return InlinePlayer(page(scene, speed=speed), title=title, height=height)
