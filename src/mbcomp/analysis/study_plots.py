"""Charts of a study's table: a metric against a parameter, and a heat map over a 2-D grid.

Examples
--------
>>> import numpy as np
>>> from mbcomp.analysis.study import StudyResult
>>> rows = [dict(a=a, b=b, z=a * b, status="success", message="", cpu_time=0.0) for a in (1, 2) for b in (1, 2, 3)]
>>> s = StudyResult(["a", "b"], ["z"], rows, [{"a": r["a"], "b": r["b"]} for r in rows], None, {})
>>> fig = s.heatmap("a", "b", "z")
>>> fig.axes[0].get_xlabel(), fig.axes[0].get_ylabel()
('a', 'b')
"""
from __future__ import annotations

import numpy as np

__all__ = ["line_plot", "heat_map"]


def _figure(path):
    import matplotlib

    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def _numbers(result, name):
    vals = result[name]
    if vals.dtype == object:
        raise ValueError(f"column {name!r} is not numeric; numeric columns: "
                         f"{', '.join(c for c in result.columns if result[c].dtype != object)}")
    return vals


def _save(plt, fig, path):
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig


def line_plot(result, x, y, path=None):
    """``y`` against ``x``; runs that did not succeed as red crosses at their ``x``."""
    plt = _figure(path)
    xs, ys = _numbers(result, x), _numbers(result, y)
    ok = np.array([s == "success" for s in result["status"]])
    order = np.argsort(xs)
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    ax.plot(xs[order][ok[order]], ys[order][ok[order]], "o-", ms=3)
    if (~ok).any():
        ax.plot(xs[~ok], np.where(np.isfinite(ys[~ok]), ys[~ok], np.nanmin(ys) if ok.any() else 0.0), "rx",
                label=f"not successful ({int((~ok).sum())})")
        ax.legend(fontsize=8)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    ax.grid(True, alpha=0.3)
    ax.set_title(f"{y} against {x} ({len(result)} runs)", fontsize=10)
    return _save(plt, fig, path)


def heat_map(result, x, y, z, path=None):
    """``z`` over the grid of the distinct values of ``x`` and ``y`` (a full factorial)."""
    plt = _figure(path)
    xs, ys, zs = _numbers(result, x), _numbers(result, y), _numbers(result, z)
    ux, uy = np.unique(xs), np.unique(ys)
    if len(ux) * len(uy) != len(result):
        raise ValueError(f"a heat map needs the full grid of {x} x {y} ({len(ux)} x {len(uy)} = "
                         f"{len(ux) * len(uy)} runs), the study has {len(result)} -> use plot() for other grids")
    Z = np.full((len(uy), len(ux)), np.nan)
    Z[np.searchsorted(uy, ys), np.searchsorted(ux, xs)] = zs
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    mesh = ax.pcolormesh(ux, uy, Z, shading="nearest")
    fig.colorbar(mesh, ax=ax, label=z)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    ax.set_title(f"{z} over {x} x {y}", fontsize=10)
    return _save(plt, fig, path)
