"""What :meth:`~mbcomp.simulation.result.Result.plot` draws: columns chosen by glob patterns, or
the ones a user looks at first.

Patterns are shell-style globs matched against the column names, case-sensitive
(``"crank_joint.*"``, ``"*.tau.z"``, ``"energy.?otal"``); an exact name matches itself. The
columns come in pattern order, each once; a pattern that matches nothing is an error listing
similar names.

The default (:func:`default_names`): the model's coordinates (``stats["coordinates"]``) with
each joint's orientation quaternion (``<joint>.Q.w|x|y|z``) replaced by its angular speeds
(``<joint>.w.x|y|z``), at most :data:`MAX_COORDINATES` of them; the energy balance
(``energy.balance``, for driven or damped systems) or else the total energy; the position
residual when the model has loops and the nonholonomic residual when it has rolling contacts.

Examples
--------
>>> from mbcomp.simulation.plotting import select
>>> names = ["crank.phi", "crank.w", "crank.tau.z", "pin.tau.z", "energy.total"]
>>> select(names, ["*.tau.z", "crank.phi"])
['crank.tau.z', 'pin.tau.z', 'crank.phi']
>>> select(names, ["crnk.phi"])
Traceback (most recent call last):
...
ValueError: no column matches 'crnk.phi'; similar: crank.phi, crank.w, crank.tau.z -> fix: give a column name or a glob such as 'crank.*' (Result.names lists them)
"""
from __future__ import annotations

import difflib
import fnmatch

import numpy as np

__all__ = ["select", "default_names", "draw", "MAX_COORDINATES", "MAX_PANELS"]

#: coordinates (or the angular speeds standing in for quaternions) in the default plot at most
MAX_COORDINATES = 6
#: panels in one plot at most (one per column)
MAX_PANELS = 24


def _similar(pattern, names, n=8):
    """Names like ``pattern``, the closest first: the columns of the component named most like
    its first part, else the closest spellings of whole names."""
    plain = pattern.replace("*", "").replace("?", "")
    heads = list(dict.fromkeys(name.split(".")[0] for name in names))
    head = difflib.get_close_matches(plain.split(".")[0], heads, n=1, cutoff=0.6)
    if not head:
        return difflib.get_close_matches(plain, names, n=n, cutoff=0.5)
    own = [name for name in names if name.startswith(head[0] + ".")]
    return sorted(own, key=lambda name: -difflib.SequenceMatcher(None, plain, name).ratio())[:n]


def select(names, patterns):
    """The columns of ``names`` that the glob ``patterns`` (a string or a list) match, in pattern
    order, each once.

    Raises
    ------
    ValueError
        A pattern matches no column (the message lists similar names), or the patterns match
        more than :data:`MAX_PANELS` columns.
    """
    if isinstance(patterns, str):
        patterns = [patterns]
    chosen = []
    for pat in patterns:
        hits = [pat] if pat in names else [n for n in names if fnmatch.fnmatchcase(n, pat)]
        if not hits:
            like = _similar(pat, names)
            head = (like or names or ["crank"])[0].split(".")[0]
            raise ValueError(f"no column matches {pat!r}; similar: {', '.join(like) or 'none'} "
                             f"-> fix: give a column name or a glob such as '{head}.*' (Result.names lists them)")
        chosen += [h for h in hits if h not in chosen]
    if len(chosen) > MAX_PANELS:
        raise ValueError(f"the patterns {' '.join(patterns)} match {len(chosen)} columns, more than the {MAX_PANELS} panels "
                         f"of one plot -> fix: narrower patterns (e.g. '*.phi' rather than '*')")
    return chosen


def _nonzero(result, name):
    return name in result and len(result[name]) > 0 and bool(np.nanmax(np.abs(result[name]), initial=0.0) > 0)


def default_names(result):
    """The columns a user looks at first (see the module doc): coordinates (angular speeds for
    quaternions), the energy balance or total energy, and the residuals of constraints.

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.result import Result
    >>> cols = {n: np.zeros(2) for n in ["ball.Q.w", "ball.Q.x", "ball.Q.y", "ball.Q.z", "ball.w.x", "ball.w.y",
    ...                                  "ball.w.z", "energy.total", "residual.position"]}
    >>> default_names(Result([0, 1], cols, stats={"coordinates": ["ball.Q.w", "ball.Q.x", "ball.Q.y", "ball.Q.z"]}))
    ['ball.w.x', 'ball.w.y', 'ball.w.z', 'energy.total']
    """
    coords = []
    for q in result.stats.get("coordinates", []):
        if ".Q." in q:  # a quaternion part: its joint's angular speeds instead
            joint = q.rsplit(".Q.", 1)[0]
            coords += [f"{joint}.w.{a}" for a in "xyz" if f"{joint}.w.{a}" in result]
        elif q in result:
            coords.append(q)
    coords = list(dict.fromkeys(coords))
    if not coords:  # a result without coordinates: its first columns that are not quaternion parts
        coords = [n for n in result.names if ".Q." not in n and not n.startswith(("energy.", "residual."))]
    names = coords[:MAX_COORDINATES]
    names += [e for e in ("energy.balance", "energy.total") if e in result][:1]
    if "min_constraint_sigma" in result.stats or _nonzero(result, "residual.position"):  # loops
        names.append("residual.position")
    if _nonzero(result, "residual.nonholonomic"):
        names.append("residual.nonholonomic")
    return names


def draw(result, names, path=None, title=None):
    """One panel per column of ``names`` against time; saved to ``path`` (PNG) if given.
    Returns the matplotlib figure (closed when saved)."""
    if not names:
        raise ValueError("the result has no columns to draw -> fix: name columns to plot (Result.names)")
    import matplotlib

    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(names), 1, sharex=True, figsize=(7, 1.8 * len(names) + 0.6), squeeze=False)
    for ax, n in zip(axes[:, 0], names):
        ax.plot(result.time, result[n])
        ax.set_ylabel(n, fontsize=8)
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title or f"mbcomp ({result.status})", fontsize=10)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig
