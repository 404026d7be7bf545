"""A run's summary as HTML: what a notebook shows for a ``Result`` (``_repr_html_``).

The summary holds the status and its message, the solver's scalar statistics (folded in a
``<details>`` element), a small table
(the first and last :data:`EDGE_ROWS` output times of a few columns: those
:meth:`~mbcomp.result.Result.default_plot_names` picks, at most :data:`MAX_COLUMNS`, headed
with their units) and the first :data:`MAX_EVENTS` events. Numbers in the table are written
as Python's ``repr`` of the float (the shortest text that reads back as the same float), so
what is shown is the value, not a rounding of it. Every text is escaped.

Examples
--------
>>> import numpy as np
>>> from mbcomp.result import Result
>>> r = Result(np.array([0.0, 1.0]), {"j.phi": np.array([0.0, 0.25])}, status="success",
...            message="reached t_end", units={"j.phi": "rad"}, stats={"steps": 12})
>>> text = result_html(r)
>>> "success" in text and "j.phi [rad]" in text and "<td>0.25</td>" in text
True
"""
from __future__ import annotations

import html

import numpy as np

__all__ = ["result_html", "table_html", "number", "MAX_COLUMNS", "EDGE_ROWS", "MAX_EVENTS", "STYLE"]

#: columns the table shows at most
MAX_COLUMNS = 6
#: output times shown at each end of the table
EDGE_ROWS = 3
#: events listed at most
MAX_EVENTS = 10
#: the summary's look (scoped to its own element)
STYLE = ("<style>.mbcomp-repr table{border-collapse:collapse;margin:4px 0 8px 0;font-size:12px}"
         ".mbcomp-repr td,.mbcomp-repr th{border:1px solid #ddd;padding:2px 6px;text-align:right}"
         ".mbcomp-repr .ok{color:#1a7f37}.mbcomp-repr .bad{color:#c00}</style>")


def number(x):
    """A value as table text: a float's ``repr`` (it reads back as the same float), text as it is.

    Examples
    --------
    >>> number(0.1), number(np.float64(2.5e-17)), number(3), number("radau5")
    ('0.1', '2.5e-17', '3', 'radau5')
    """
    if isinstance(x, (bool, np.bool_)):
        return str(bool(x))
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    if isinstance(x, (float, np.floating)):
        return repr(float(x))
    return str(x)


def table_html(header, rows):
    """An HTML table: ``header`` a list of texts, ``rows`` lists of cells (escaped here).

    Examples
    --------
    >>> table_html(["a"], [[1.5], ["<b>"]])
    '<table><tr><th>a</th></tr><tr><td>1.5</td></tr><tr><td>&lt;b&gt;</td></tr></table>'
    """
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(number(c))}</td>" for c in row) + "</tr>" for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _scalar_stats(stats):
    return [[k, v] for k, v in stats.items() if isinstance(v, (int, float, str, np.integer, np.floating))
            and not isinstance(v, bool)]


def _columns(res):
    """The columns the summary's table shows."""
    try:
        names = [n for n in res.default_plot_names() if n in res]
    except (KeyError, ValueError, TypeError):  # a hand-made result without the usual columns
        names = []
    return (names or list(res.names))[:MAX_COLUMNS]


def _rows(res, names):
    """The table's rows: the first and last output times (all of them when few), with a
    ``...`` row between the two ends."""
    n = len(res.time)
    picks = list(range(n)) if n <= 2 * EDGE_ROWS else list(range(EDGE_ROWS)) + [None] + list(range(n - EDGE_ROWS, n))
    columns = [res.time] + [res[c] for c in names]
    return [["..."] * len(columns) if i is None else [col[i] for col in columns] for i in picks]


def result_html(res):
    """The HTML summary of a run (module notes).

    Parameters
    ----------
    res : Result

    Returns
    -------
    str
    """
    kind = "ok" if res.status == "success" else "bad"
    parts = [STYLE, '<div class="mbcomp-repr">',
             f'<b>mbcomp Result</b>: <span class="{kind}">{html.escape(res.status)}</span>'
             f" ({html.escape(res.message or '')})"]
    n = len(res.time)
    span = f"t = {number(res.time[0])} .. {number(res.time[-1])} s" if n else "no output rows"
    parts.append(f"<div>{n} output times, {len(res.names)} columns; {html.escape(span)}</div>")
    stats = _scalar_stats(res.stats)
    if stats:  # folded: a run's statistics are many; a click opens them
        parts.append(f"<details><summary>{len(stats)} statistics</summary>{table_html(['statistic', 'value'], stats)}"
                     "</details>")
    if n:
        names = _columns(res)
        header = ["time [s]"] + [f"{c} [{res.units[c]}]" if c in res.units else c for c in names]
        parts.append(table_html(header, _rows(res, names)))
    if res.events:
        more = f" (the first {MAX_EVENTS} of {len(res.events)})" if len(res.events) > MAX_EVENTS else ""
        parts.append(f"<div>{len(res.events)} events{more}</div>")
        parts.append(table_html(["time [s]", "component", "event", "kind"],
                                [[e.time, e.component, e.name, e.kind] for e in res.events[:MAX_EVENTS]]))
    parts.append("</div>")
    return "".join(parts)
