"""The self-contained HTML player of a scene: one file that opens offline in a browser.

The file holds everything it runs: three.js (r170, MIT, from ``vendor/three``) and its orbit
controls as ``data:`` URLs in an import map, the player (``player.js``) as an inline module,
and the scene (:meth:`mbcomp.visual.scene.Scene.to_json`) as inline JSON. Nothing is fetched
from a network or from other files, so the page works from ``file://``, mailed or archived.

The page's JavaScript API (``window.mbcomp``, for tests and scripting): ``ready`` (a promise
resolved after the first frame), ``setTime(t)``, ``play()``, ``pause()``, ``time()``,
``duration()``, ``bodies()``, ``bodyPose(name)`` (``{r, q}``: the body's frame_a in the world,
m and quaternion w, x, y, z, read from the three.js scene graph) and ``pixels()`` (a digest of
the drawn canvas).

Examples
--------
>>> import os, tempfile, mbcomp
>>> from mbcomp.library import World, Revolute, PointMass, FixedTranslation
>>> from mbcomp.visual.scene import build_scene
>>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute(n=(0, 0, 1), phi0=1.0))
>>> rod = m.add("rod", FixedTranslation(r=(1, 0, 0))); bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> scene = build_scene(mbcomp.simulate(m, t_end=1.0))
>>> path = write_html(scene, os.path.join(tempfile.mkdtemp(), "pendulum.html"))
>>> text = open(path, encoding="utf-8").read()
>>> 'id="mbcomp-scene"' in text and "three.js r170" in text
True
"""
from __future__ import annotations

import base64
import html
import json
import math
import os
from functools import lru_cache
from pathlib import Path

__all__ = ["write_html", "page", "THREE_VERSION"]

HERE = Path(__file__).resolve().parent
VENDOR = HERE / "vendor" / "three"
#: the three.js release inlined in every page (npm ``three``)
THREE_VERSION = "0.170.0"
THREE_FILE = VENDOR / "build" / "three.module.min.js"
ORBIT_FILE = VENDOR / "examples" / "jsm" / "controls" / "OrbitControls.js"

STYLE = """
html, body { margin: 0; height: 100%; overflow: hidden; font: 13px system-ui, sans-serif; color: #222; }
#mbcomp-view { position: absolute; inset: 0; }
#mbcomp-title { position: absolute; top: 8px; left: 12px; font-size: 15px; font-weight: 600; }
#mbcomp-controls { position: absolute; left: 0; right: 0; bottom: 0; display: flex; gap: 10px; align-items: center;
  padding: 6px 12px; background: rgba(255, 255, 255, 0.8); }
#mbcomp-controls #slider { flex: 1; }
#mbcomp-controls #time { font-variant-numeric: tabular-nums; min-width: 14em; }
#mbcomp-legends { position: absolute; top: 8px; right: 12px; }
.legend { background: rgba(255, 255, 255, 0.8); padding: 4px 8px; margin-bottom: 6px; width: 180px; }
.legend .bar { height: 10px; margin: 3px 0; }
.legend .ends { display: flex; justify-content: space-between; font-variant-numeric: tabular-nums; }
#mbcomp-error { display: none; position: absolute; top: 40%; left: 10%; right: 10%; padding: 12px;
  background: #fee; border: 1px solid #c00; }
"""

BODY = """<div id="mbcomp-view"></div>
<div id="mbcomp-title">{title}</div>
<div id="mbcomp-legends"></div>
<div id="mbcomp-error"></div>
<div id="mbcomp-controls">
  <button id="play" type="button" title="play / pause (space)">play</button>
  <input id="slider" type="range" aria-label="time">
  <span id="time"></span>
  <label>speed <select id="speed"></select></label>
</div>"""


def _data_url(path):
    """A ``data:`` URL of a JavaScript module file."""
    return "data:text/javascript;base64," + base64.b64encode(path.read_bytes()).decode("ascii")


@lru_cache(maxsize=1)
def _vendor():
    """The import map, the three.js licence and the player's source (read once)."""
    missing = [p for p in (THREE_FILE, ORBIT_FILE, VENDOR / "LICENSE", HERE / "player.js") if not p.is_file()]
    if missing:
        raise FileNotFoundError(f"the HTML player's file {missing[0]} is missing -> reinstall mbcomp (its package "
                                "data holds three.js and player.js)")
    imports = {"three": _data_url(THREE_FILE), "three/addons/controls/OrbitControls.js": _data_url(ORBIT_FILE)}
    licence = (VENDOR / "LICENSE").read_text(encoding="utf-8").replace("--", "- -")
    return json.dumps({"imports": imports}), licence, (HERE / "player.js").read_text(encoding="utf-8")


def _script_json(data):
    """JSON safe inside a ``<script>`` element: no ``<``, ``>`` or ``&`` (written as ``\\u003c`` ...),
    so no ``</script>`` or ``<!--`` can end or change the element."""
    text = json.dumps(data, separators=(",", ":"), allow_nan=False, default=_plain)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def _plain(x):
    """numpy scalars and arrays in the scene's plain data as Python numbers and lists."""
    if hasattr(x, "tolist"):
        return x.tolist()
    raise TypeError(f"the scene holds {type(x).__name__} {x!r}, which is no JSON value")


def page(scene, speed=1.0):
    """The HTML text of the player for ``scene`` played at ``speed`` (1 = real time).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.visual.scene import Scene, Link
    >>> s = Scene(np.array([0.0, 1.0]), [Link("world", None)], [], {}, np.array([0.0, 0.0, 1.0]), 1.0, title="<a>")
    >>> text = page(s)
    >>> "<title>&lt;a&gt;</title>" in text, "<a>" in text  # the title is escaped in the JSON too
    (True, False)
    """
    if not (isinstance(speed, (int, float)) and math.isfinite(speed) and speed > 0):
        raise ValueError(f"speed={speed!r} must be a positive number (1 = real time)")
    importmap, licence, player = _vendor()
    data = dict(scene.to_json(), speed=float(speed))
    title = scene.title or "mbcomp animation"
    return "\n".join([
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{html.escape(title)}</title>",
        f"<!-- made by mbcomp; inlines three.js r{THREE_VERSION.split('.')[1]} (npm three@{THREE_VERSION}), "
        f"under its licence:\n{licence}-->",
        f"<style>{STYLE}</style>", "</head>", "<body>",
        BODY.format(title=html.escape(scene.title or "")),
        f'<script type="application/json" id="mbcomp-scene">{_script_json(data)}</script>',
        f'<script type="importmap">{importmap}</script>',
        f'<script type="module">\n{player}</script>', "</body>", "</html>", ""])


def write_html(scene, path, speed=1.0):
    """Write the self-contained HTML player of ``scene`` to ``path``.

    Parameters
    ----------
    scene : mbcomp.visual.scene.Scene
        The scene (:func:`mbcomp.visual.scene.build_scene`).
    path : str or os.PathLike
        The ``.html`` file; its folder must exist.
    speed : float
        Playback speed the page starts with (1 = real time).

    Returns
    -------
    str
        ``path``.

    Raises
    ------
    FileNotFoundError
        The folder of ``path`` does not exist (naming it).

    Examples
    --------
    >>> import os, tempfile, mbcomp
    >>> from mbcomp.library import World, Revolute, PointMass, FixedTranslation
    >>> from mbcomp.visual.scene import build_scene
    >>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute(n=(0, 0, 1)))
    >>> rod = m.add("rod", FixedTranslation(r=(1, 0, 0))); bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> out = write_html(build_scene(mbcomp.simulate(m, t_end=0.5)), os.path.join(tempfile.mkdtemp(), "a.html"))
    >>> os.path.getsize(out) < 2e6
    True
    """
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise FileNotFoundError(f"cannot write {path!r}: its folder {folder!r} does not exist -> create it first "
                                "(os.makedirs) or write to an existing folder")
    text = page(scene, speed=speed)
    try:
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
    except OSError as e:
        raise OSError(f"cannot write {path!r}: {e.strerror or e} -> choose a writable .html path") from e
    return path
