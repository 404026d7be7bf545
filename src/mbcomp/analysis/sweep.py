"""Stability against a parameter: eigenvalues along a grid and the values where the classification changes.

:func:`sweep` linearizes at each grid value and locates the changes between neighbours by
root finding: Brent on the largest real part where it changes sign; where a real pair meets
at zero and leaves along the imaginary axis (conservative systems), Brent on its signed
square (``+a^2`` unstable, ``-b^2`` marginally stable); else bisection on the classification.

Examples
--------
The bead on a ring (seed Example 7.1) at the bottom: unstable above ``omega^2 = g / r``.

>>> import mbcomp, numpy as np
>>> from mbcomp.library import World, Revolute, PrescribedMotion, FixedTranslation, PointMass
>>> def bead(omega):
...     m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
...     spin = m.add("spin", Revolute(n=(0, 1, 0)))
...     drive = m.add("drive", PrescribedMotion(s=lambda t: omega * t))
...     hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.0, w0=0.0))
...     rod = m.add("rod", FixedTranslation(r=(0, -0.5, 0))); b = m.add("bead", PointMass(m=0.1))
...     m.connect(w.frame_b, spin.frame_a); m.connect(drive.flange_b, spin.axis)
...     m.connect(spin.frame_b, hinge.frame_a); m.connect(hinge.frame_b, rod.frame_a)
...     m.connect(rod.frame_b, b.frame_a)
...     return m
>>> sw = mbcomp.sweep(bead, "omega", [3.0, 5.0])
>>> [(c["from"], c["to"]) for c in sw.changes]
[('marginally stable', 'unstable')]
>>> bool(abs(sw.changes[0]["value"] - np.sqrt(9.81 / 0.5)) < 1e-12)
True
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ModelError, SimulationError
from .linearization import linearize, zero_tolerance

__all__ = ["Sweep", "sweep"]


@dataclass(frozen=True)
class Sweep:
    """Eigenvalues against a parameter and the values where stability changes.

    Attributes
    ----------
    parameter : str
    values : ndarray (k,)
    eigenvalues : ndarray (k, n), complex
        Per value, sorted by decreasing real part (NaN where the analysis failed).
    classifications : list of str
    changes : list of dict
        ``{"value", "from", "to", "eigenvalue", "kind", "method"}`` for each change, found by
        root finding between grid values (``kind``: ``"oscillatory"`` when a complex pair
        crosses, ``"divergence"`` when a real root does).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.stability import Sweep
    >>> s = Sweep("v", np.array([0.0, 1.0]), np.array([[1.0 + 0j], [-1.0 + 0j]]), ["unstable", "asymptotically stable"], [])
    >>> s.ranges()  # no change located between the grid values: the segments end at them
    [(0.0, 0.0, 'unstable'), (1.0, 1.0, 'asymptotically stable')]
    """

    parameter: str
    values: np.ndarray
    eigenvalues: np.ndarray
    classifications: list
    changes: list

    def ranges(self):
        """``[(lo, hi, classification), ...]``: runs of equal classification along the sweep,
        their ends at the located changes (at the grid values where a change could not be
        located, e.g. next to a failed point)."""
        vals, cls = self.values, self.classifications
        segs, lo, cur = [], float(vals[0]), cls[0]
        for k in range(len(vals) - 1):
            if cls[k + 1] == cls[k]:
                continue
            found = [c["value"] for c in self.changes if vals[k] <= c["value"] <= vals[k + 1]
                     and c["from"] == cls[k] and c["to"] == cls[k + 1]]
            hi, nxt = (found[0], found[0]) if found else (float(vals[k]), float(vals[k + 1]))
            segs.append((lo, hi, cur))
            lo, cur = nxt, cls[k + 1]
        segs.append((lo, float(vals[-1]), cur))
        return segs

    def stable_ranges(self, include_marginal=False):
        """``[(lo, hi), ...]`` where the state is asymptotically stable (and, with
        ``include_marginal``, marginally stable)."""
        ok = ("asymptotically stable", "marginally stable") if include_marginal else ("asymptotically stable",)
        return [(a, b) for a, b, kind in self.ranges() if kind in ok]

    def to_dict(self):
        return dict(parameter=self.parameter, values=self.values.tolist(),
                    eigenvalues_real=self.eigenvalues.real.tolist(), eigenvalues_imag=self.eigenvalues.imag.tolist(),
                    classifications=self.classifications, changes=self.changes)

    def plot(self, path=None, title=None):
        """Real and imaginary parts against the parameter (like Meijaard et al. Fig. 3)."""
        import matplotlib

        if path is not None:
            matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 4.5))
        v = self.values
        for k in range(self.eigenvalues.shape[1]):
            ax.plot(v, self.eigenvalues[:, k].real, "k.", ms=3, label="Re" if k == 0 else None)
            ax.plot(v, np.abs(self.eigenvalues[:, k].imag), ".", color="tab:blue", ms=2,
                    label="|Im|" if k == 0 else None)
        for c in self.changes:
            ax.axvline(c["value"], color="tab:red", lw=0.8)
            ax.annotate(f"{c['value']:.6g}", (c["value"], 0), rotation=90, fontsize=7, color="tab:red")
        ax.axhline(0, color="0.5", lw=0.5)
        ax.set_xlabel(self.parameter)
        ax.set_ylabel("eigenvalue (1/s)")
        ax.set_title(title or f"eigenvalues against {self.parameter}")
        lim = np.nanmax(np.abs(self.eigenvalues.real)) if np.isfinite(self.eigenvalues.real).any() else 1.0
        ax.set_ylim(-min(lim, 10.0) * 1.1, min(lim, 10.0) * 1.1)
        ax.legend(fontsize=8)
        fig.tight_layout()
        if path is not None:
            fig.savefig(path, dpi=110)
            plt.close(fig)
        return fig


class _StartState:
    """The default analysis of :func:`sweep`: :func:`linearize` about the start state (a
    module-level class, so that it pickles for an executor's worker processes)."""

    def __init__(self, backend):
        self.backend = backend

    def __call__(self, mdl):
        return linearize(mdl, backend=self.backend)


class _At:
    """One grid value's linearization, ``None`` where the analysis fails (what :func:`sweep`
    sends to an executor, one task per grid value)."""

    def __init__(self, build, analyze):
        self.build, self.analyze = build, analyze

    def __call__(self, v):
        try:
            return self.analyze(self.build(float(v)))
        except (SimulationError, ModelError):
            return None


def sweep(build, parameter, values, analyze=None, backend="python", executor=None, progress=False):
    """Linearize at each value of ``parameter`` and locate the stability changes.

    Parameters
    ----------
    build : callable
        ``build(value) -> Model`` (or ``MultibodySystem``) describing the steady state at
        that parameter value through its start values.
    parameter : str
        Name for reports and plots.
    values : array_like
        Grid (sorted); changes are bracketed by neighbours and refined by root finding.
    analyze : callable, optional
        ``analyze(model) -> Linearization`` (default :func:`linearize` of the start state),
        e.g. to solve for a steady state first.
    backend : {"python", "numeric", "c", "auto"}
        What evaluates the model in the default ``analyze`` (as in :func:`linearize`).
    executor : None, concurrent.futures.Executor, "dask", "tcp://host:port" or dask Client
        Where the grid's linearizations run, one task per value
        (:func:`mbcomp.analysis.parallel.map_on`); the root finding between neighbours then
        runs here. A process pool needs ``build`` (and ``analyze``) defined at module level.
        The eigenvalues equal the serial ones (``None``, the default).
    progress : bool
        A progress bar counting the grid's finished linearizations.

    Returns
    -------
    Sweep
    """
    from .parallel import map_on

    analyze = analyze or _StartState(backend)
    values = np.asarray(values, float)

    def at(v):
        return analyze(build(float(v)))

    lins = map_on(executor, _At(build, analyze), values, progress=progress)
    n = max((len(li.eigenvalues) for li in lins if li is not None), default=0)
    E = np.full((len(values), n), np.nan + 0j)
    cls = []
    for k, li in enumerate(lins):
        if li is None:
            cls.append("failed")
            continue
        E[k, : len(li.eigenvalues)] = li.eigenvalues
        cls.append(li.classification)

    def unstable_count(li):
        tol = zero_tolerance(li.eigenvalues)
        return int(np.sum(li.eigenvalues.real > tol))

    def top_root(li):
        return li.eigenvalues[int(np.argmax(li.eigenvalues.real))]

    changes = []
    for k in range(len(values) - 1):
        la, lb = lins[k], lins[k + 1]
        if la is None or lb is None or (cls[k] == cls[k + 1] and unstable_count(la) == unstable_count(lb)):
            continue
        a, b = values[k], values[k + 1]
        try:
            x, method = _locate(at, la, lb, a, b, cls[k], unstable_count, top_root)
        except (SimulationError, ModelError) as exc:
            changes.append(dict(value=float("nan"), **{"from": cls[k], "to": cls[k + 1]}, eigenvalue=[np.nan, np.nan],
                                kind="not located", method=f"analysis failed inside [{a:g}, {b:g}]: {exc}"))
            continue
        try:
            root = top_root(at(x))
        except (SimulationError, ModelError):
            root = complex(np.nan, np.nan)
        # the kind from the root that is unstable on one side (at the crossing itself a
        # collision at zero leaves a ~1e-6 imaginary part of either sign)
        un = lins[k + 1] if unstable_count(lins[k + 1]) > unstable_count(lins[k]) else lins[k]
        ru = top_root(un)
        changes.append(dict(value=float(x), **{"from": cls[k], "to": cls[k + 1]},
                            eigenvalue=[float(root.real), float(root.imag)],
                            kind="oscillatory" if abs(ru.imag) > zero_tolerance(un.eigenvalues) else "divergence",
                            method=method))
    return Sweep(parameter, values, E, cls, changes)


class _Other(Exception):
    """A classification other than the two of a bracket's ends turned up inside it."""


def _locate(at, la, lb, a, b, cls_a, unstable_count, top_root):
    """The parameter in ``[a, b]`` where the classification changes: Brent on the largest
    real part if it changes sign clearly, Brent on the colliding pair's signed square between
    unstable and marginally stable, else bisection on the classification."""
    from scipy.optimize import brentq  # here: scipy.optimize costs ~0.5 s to import

    fa, fb = top_root(la).real, top_root(lb).real
    if fa * fb < 0 and abs(fa) > zero_tolerance(la.eigenvalues) and abs(fb) > zero_tolerance(lb.eigenvalues):
        x = brentq(lambda v: top_root(at(v)).real, a, b, xtol=1e-13, rtol=4 * np.finfo(float).eps)
        return x, "Brent's method on the largest real part"
    if {la.classification, lb.classification} == {"unstable", "marginally stable"}:
        # a conservative boundary: a real pair +-a collides at zero and leaves as +-ib. Signed
        # squares (+a^2 unstable, -b^2 stable, b the smallest nonzero frequency) are smooth
        # across it, so Brent converges in a few steps where bisection takes ~41; the sign is
        # the classification, so the root is the classification's change whatever the sizes.
        def signed(v):
            li = at(v)
            tol = zero_tolerance(li.eigenvalues)
            if li.classification == "unstable":
                return float(top_root(li).real) ** 2
            if li.classification != "marginally stable":
                raise _Other()
            freq = np.abs(li.eigenvalues.imag)
            freq = freq[freq > tol]
            return -(float(freq.min()) ** 2 if freq.size else tol ** 2)

        try:
            x = brentq(signed, a, b, xtol=1e-13, rtol=4 * np.finfo(float).eps)
            return x, "Brent's method on the signed square of the colliding roots"
        except _Other:
            pass  # a third classification inside the bracket: bisection sorts it out
    ca = (cls_a, unstable_count(la))
    for _ in range(60):
        mid = 0.5 * (a + b)
        lm = at(mid)
        if (lm.classification, unstable_count(lm)) == ca:
            a = mid
        else:
            b = mid
        if b - a <= 1e-13 * max(1.0, abs(a)):
            break
    return 0.5 * (a + b), "bisection on the classification"
