"""Locating a point along a step's dense output: where a function crosses zero, or is least.

A stepper's dense output ``y(t)`` between the ends of an accepted step is a polynomial
interpolant of the solution's own accuracy; a function of the state along it, ``g(t) =
f(t, y(t))``, is then a smooth scalar function of time, and Brent's methods locate on it

* a root (:func:`root`): where ``g`` changed sign between the step's ends (an event);
* a return through zero (:func:`return_root`): ``g`` left zero at the step's start (the
  event just handled) and is back across it at its end;
* a minimum (:func:`minimum`): where a monitored distance (a singular value, a joint's
  distance from its singularity) is least inside a window of steps.

Every caller locates to the same time tolerance, :func:`time_tolerance`: ``|dt| <=
min(1e-12, rtol / 1000) max(1, |t|)`` -- far below the integrator's own error in time, so
where an event falls is decided by the solution, not by the search.

Examples
--------
>>> import numpy as np
>>> from mbcomp.solvers.locate import minimum, root, time_tolerance
>>> g = lambda t: np.cos(t)                     # crosses zero at pi/2
>>> tol = time_tolerance(2.0, rtol=1e-8)
>>> tol
2e-12
>>> abs(root(g, 1.0, 2.0, tol=tol) - np.pi / 2) < tol
True
>>> t, v = minimum(lambda t: (t - 0.3) ** 2, 0.0, 1.0, tol=1e-12)
>>> round(t, 9), v < 1e-18
(0.3, True)
"""
from __future__ import annotations

import numpy as np

__all__ = ["time_tolerance", "root", "return_root", "minimum"]


def time_tolerance(t, rtol=None):
    """The location tolerance (s) at time ``t`` (s): ``min(1e-12, rtol / 1000) max(1, |t|)``
    (``1e-12 max(1, |t|)`` without ``rtol``)."""
    scale = 1e-12 if rtol is None else min(1e-12, 1e-3 * rtol)
    return scale * max(1.0, abs(t))


def root(g, t0, t1, g0=None, g1=None, *, tol):
    """The root (s) of ``g`` in ``[t0, t1]``, where it changes sign (``g0``, ``g1``: its values
    at the ends when known; an end where it is exactly zero is the root), by Brent's method
    to ``tol`` (s)."""
    from scipy.optimize import brentq  # scipy.optimize is imported on the first location, not with mbcomp

    g0 = g(t0) if g0 is None else g0
    if g0 == 0.0:
        return t0
    g1 = g(t1) if g1 is None else g1
    if g1 == 0.0:
        return t1
    return float(brentq(g, t0, t1, xtol=tol, rtol=4 * np.finfo(float).eps))


def return_root(g, t0, t1, direction, *, tol):
    """The return through zero of ``g``, which is zero at ``t0`` and on the ``direction`` side
    of zero (``direction * g(t1) > 0``) at ``t1``: Brent's root between ``g``'s extreme on the
    other side (bounded Brent minimization of ``direction * g``) and ``t1``; ``t0`` when
    ``g`` never left for the other side."""
    from scipy.optimize import brentq, minimize_scalar

    peak = minimize_scalar(lambda tt: direction * g(tt), bounds=(t0, t1), method="bounded", options=dict(xatol=tol))
    if peak.fun >= 0.0:  # direction * g >= 0 throughout: it never got off the zero
        return t0
    return float(brentq(g, float(peak.x), t1, xtol=tol, rtol=4 * np.finfo(float).eps))


def minimum(g, t0, t1, *, tol):
    """``(t, g(t))`` at the least value of ``g`` in ``[t0, t1]`` (s), by bounded Brent
    minimization to ``tol`` (s)."""
    from scipy.optimize import minimize_scalar

    r = minimize_scalar(g, bounds=(t0, t1), method="bounded", options=dict(xatol=tol))
    return float(r.x), float(r.fun)
