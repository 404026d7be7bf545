"""What a notebook shows: ``Result._repr_html_`` (status, statistics, the first and last rows,
the events), ``Model._repr_html_`` (the topology drawing as inline SVG) and ``res.animate()``
with no path (the player page in an ``<iframe srcdoc>``), each parsed with html.parser and
checked against the run; and one real notebook executed by nbconvert, whose outputs hold the
same HTML (skipped where nbconvert or ipykernel is not installed)."""
import base64
import json
import time
from html.parser import HTMLParser

import numpy as np
import pytest
from conftest import stop_pendulum

import mbcomp
from mbcomp.visual.html import page
from mbcomp.visual.scene import build_scene


#: the model and run of every test here, and of the notebook (a pendulum falling onto its stop: impacts)
MODEL, RUN = "stop_pendulum(limits=(0.0, 3.0), e=0.5, phi0=0.8)", dict(t_end=2.0, n_out=81)


@pytest.fixture(scope="module")
def res():
    r = mbcomp.simulate(eval(MODEL), **RUN)
    assert r.success and len(r.events) >= 2
    return r


class Parsed(HTMLParser):
    """Tables (lists of rows of cell texts), the text of ``<span>`` and ``<text>`` (SVG)
    elements, and the attributes of ``<iframe>`` and ``<script>`` elements."""

    def __init__(self, text):
        super().__init__()
        self.tables, self.spans, self.svg_texts, self.iframes, self.scripts = [], [], [], [], []
        self._cell = self._span = self._text = self._script = None
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell = ""
        elif tag == "span":
            self._span = ""
        elif tag == "text":
            self._text = ""
        elif tag == "iframe":
            self.iframes.append(dict(attrs))
        elif tag == "script":
            self._script = [dict(attrs), ""]

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self.tables[-1][-1].append(self._cell)
            self._cell = None
        elif tag == "span":
            self.spans.append(self._span)
            self._span = None
        elif tag == "text":
            self.svg_texts.append(self._text)
            self._text = None
        elif tag == "script":
            self.scripts.append(tuple(self._script))
            self._script = None

    def handle_data(self, data):
        for slot in ("_cell", "_span", "_text"):
            if getattr(self, slot) is not None:
                setattr(self, slot, getattr(self, slot) + data)
        if self._script is not None:
            self._script[1] += data


def test_result_summary_shows_status_stats_rows_and_events(res):
    p = Parsed(res._repr_html_())
    assert p.spans[0] == "success"
    stats, rows, events = p.tables
    assert dict((k, v) for k, v in stats[1:])["steps"] == str(res.stats["steps"])
    head = rows[0]
    assert head[0] == "time [s]" and "hinge.phi [rad]" in head
    first, last = rows[1], rows[-1]
    assert float(first[0]) == res.time[0] and float(last[0]) == res.time[-1]
    for k, title in enumerate(head[1:], start=1):
        column = title.split(" [")[0]
        assert float(last[k]) == res[column][-1] and float(first[k]) == res[column][0], column  # exact: repr of floats
    assert ["..."] * len(head) in rows and len(rows) == 1 + 2 * 3 + 1
    assert [float(r[0]) for r in events[1:]] == [e.time for e in res.events]
    assert {tuple(r[1:]) for r in events[1:]} == {(e.component, e.name, e.kind) for e in res.events}


def test_model_shows_its_topology_inline():
    m = stop_pendulum()
    html = m._repr_html_()
    assert "<svg" in html and "<?xml" not in html
    texts = Parsed(html).svg_texts
    assert {"hinge", "world", "bob"} <= set(texts) and "1 degree of freedom" in texts
    empty = mbcomp.Model()._repr_html_()
    assert "no topology drawing" in empty and "contains no components" in empty


def test_animate_without_a_path_is_the_player_inline(res, tmp_path):
    player = res.animate(trails=["bob"], title="pendulum")
    frames = Parsed(player._repr_html_()).iframes
    assert len(frames) == 1 and frames[0]["title"] == "pendulum"
    assert frames[0]["srcdoc"] == player.page  # the attribute unescapes to the page itself
    assert player.page == page(build_scene(res, trails=["bob"], title="pendulum"))
    scene = json.loads(next(text for attrs, text in Parsed(player.page).scripts if attrs.get("id") == "mbcomp-scene"))
    times = np.frombuffer(base64.b64decode(scene["time"]), "<f8")
    assert times[0] == res.time[0] and times[-1] == res.time[-1] and scene["title"] == "pendulum"
    saved = player.save(tmp_path / "p.html")
    assert saved.read_text(encoding="utf-8") == player.page


NOTEBOOK_CELLS = [
    f"import mbcomp\nfrom conftest import stop_pendulum\nm = {MODEL}\nm",
    f"res = mbcomp.simulate(m, **{RUN!r})\nres",
    "float(res['hinge.phi'][-1]).hex()",
    "res.animate()",
]


def test_a_notebook_shows_them(res, tmp_path):
    """One notebook executed by a real kernel: its cells' HTML outputs are the reprs."""
    nbformat = pytest.importorskip("nbformat")
    pytest.importorskip("ipykernel")
    from nbconvert.preprocessors import ExecutePreprocessor

    import conftest

    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in NOTEBOOK_CELLS])
    start = time.perf_counter()
    ExecutePreprocessor(timeout=60, kernel_name="python3").preprocess(
        nb, {"metadata": {"path": str(conftest.ROOT / "tests")}})  # the kernel imports conftest from there
    elapsed = time.perf_counter() - start
    out = [c.outputs[0]["data"] for c in nb.cells]
    assert "<svg" in out[0]["text/html"] and "hinge" in Parsed(out[0]["text/html"]).svg_texts
    summary = Parsed(out[1]["text/html"])
    assert summary.spans[0] == "success"
    assert float.fromhex(out[2]["text/plain"].strip("'")) == res["hinge.phi"][-1]  # the kernel's run is this run
    assert Parsed(out[1]["text/html"]).tables[1][-1][0] == repr(float(res.time[-1]))
    assert Parsed(out[3]["text/html"]).iframes[0]["srcdoc"].startswith("<!DOCTYPE html>")
    assert elapsed < 60


def test_inline_player_plays_in_a_browser(res, tmp_path):
    """The iframe in a host page (what a notebook's page is to it): the player starts and draws the
    bob where the run has it at the end, with no console error (skipped without Chromium)."""
    import os
    import shutil

    sync = pytest.importorskip("playwright.sync_api")
    chromium = "/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else shutil.which("chromium")
    if chromium is None:
        pytest.skip("no Chromium (apt-get install chromium)")
    host = tmp_path / "notebook.html"
    host.write_text("<!DOCTYPE html><html><body><h1>a notebook</h1>" + res.animate(title="pendulum")._repr_html_()
                    + "</body></html>", encoding="utf-8")
    with sync.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=["--headless", "--no-sandbox", "--disable-gpu",
                                                                    "--no-first-run", "--disable-background-networking"])
        try:
            page = browser.new_page()
            errors = []
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.goto(host.as_uri())
            frame = page.frames[1]
            frame.wait_for_function("window.mbcomp !== undefined", timeout=20000)
            frame.evaluate("window.mbcomp.ready")
            assert frame.evaluate("window.mbcomp.duration()") == res.time[-1] - res.time[0]
            frame.evaluate(f"window.mbcomp.setTime({float(res.time[-1])!r})")
            pose = frame.evaluate("window.mbcomp.bodyPose('bob')")
        finally:
            browser.close()
    assert pose["r"] == [res["bob.r.x"][-1], res["bob.r.y"][-1], res["bob.r.z"][-1]] and errors == []
