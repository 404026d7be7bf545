"""SUNDIALS IDA (variable-order BDF for DAEs) through scikit-sundae, as an mbcomp stepper.

IDA solves the residual form ``F(t, y, dy/dt) = E dy/dt - fun(t, y) = 0``. It is run one
internal step at a time (``method="onestep"`` with ``tstop`` at the end of the span), so the
driver sees the same step loop as with every other solver. IDA's error test is designed for
index 1; for the index-2 (GGL) form the index-2 variables are left out of the error test by
giving them an absolute tolerance of ``1e20`` (IDA's documented way to suppress algebraic
variables when it has no ``suppressalg`` option exposed). Higher index is refused by the
driver (``max_index = 2``).

Dense output is the cubic Hermite interpolant through the two step ends and their
derivatives (IDA returns ``dy/dt``), accurate to ``O(h^4)``: enough for output grids, while
the step ends themselves carry IDA's full accuracy.

The iteration matrix ``cj E - d fun/dy`` is built from the problem's ``jac`` when the problem
says it is exact (``problem.exact_jac``: the DAE forms over a generated program, see
:mod:`mbcomp.codegen.dae_jacobian`); otherwise IDA makes it by its own difference quotients.

Examples
--------
>>> import numpy as np
>>> from types import SimpleNamespace
>>> from mbcomp.solvers.ida import IDA
>>> decay = SimpleNamespace(n=1, mass=np.ones(1), index=np.ones(1, int), fun=lambda t, y: -2.0 * y)
>>> s = IDA(decay, 0.0, [1.0], 1.0, rtol=1e-10, atol=1e-12)
>>> while s.status == "running":
...     _ = s.step()
>>> round(float(s.y[0]), 8), round(float(np.exp(-2.0)), 8)
(0.13533528, 0.13533528)
"""
from __future__ import annotations

import numpy as np

from .base import StepFailure, Stepper

__all__ = ["IDA"]


class IDA(Stepper):
    """SUNDIALS IDA (BDF orders 1-5, adaptive) for ``E dy/dt = fun(t, y)``, index <= 2.

    Parameters
    ----------
    problem : SemiExplicitDAE
        ``n``, ``mass`` (diag of E), ``index`` (per variable) and ``fun(t, y)``.
    t0, y0, t_bound, rtol, atol, first_step, max_step
        As for :class:`~mbcomp.solvers.base.Stepper`. ``y0`` must be consistent; its
        derivative is taken from ``fun`` on the differential rows.
    max_order : int
        Highest BDF order (1-5).

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from mbcomp.solvers.ida import IDA
    >>> IDA.capabilities()
    {'implicit': True, 'adaptive': True, 'one_step': False, 'max_index': 2, 'problem': 'dae'}
    """

    implicit = True
    adaptive = True
    one_step = False  # variable-order BDF: its history cannot be projected
    max_index = 2
    problem = "dae"

    def __init__(self, problem, t0, y0, t_bound, rtol=1e-6, atol=1e-8, first_step=None, max_step=np.inf,
                 max_order=5):
        super().__init__(problem, t0, y0, t_bound, rtol, atol, first_step, max_step)
        try:
            from sksundae.ida import IDA as _IDA
        except ImportError as exc:  # pragma: no cover - declared dependency
            raise ImportError("method 'ida' needs scikit-sundae: pip install scikit-sundae") from exc
        E = np.asarray(problem.mass, float)
        idx = np.asarray(problem.index, int)
        if idx.max() > self.max_index:
            raise ValueError(f"IDA handles DAEs of index <= 2; this form has variables of index {idx.max()} "
                             "-> use index=1 or 2, or method='radau5'/'genalpha' for index 3")
        self._E = E
        self._fail = None
        atol_v = np.full(problem.n, float(atol))
        atol_v[idx >= 2] = 1e20  # leave index-2 variables out of the error test
        self._opts = dict(rtol=float(rtol), atol=atol_v, algebraic_idx=np.flatnonzero(E == 0.0).tolist() or None,
                          max_order=int(max_order), max_num_steps=100000)
        if getattr(problem, "exact_jac", False):  # else SUNDIALS' own difference quotients
            self._opts["jacfn"] = self._jac
        if first_step:
            self._opts["first_step"] = float(first_step)
        if np.isfinite(max_step):
            self._opts["max_step"] = float(max_step)
        self._make = _IDA
        self._njev_done = 0  # Jacobians of the SUNDIALS solvers before the last restart
        self._start()
        self._old = None

    def _start(self):
        """A fresh SUNDIALS solver at the current ``(t, y)`` (no history)."""
        self._ida = self._make(self._res, **self._opts)
        self.yp = self._derivative(self.t, self.y)
        out = self._ida.init_step(self.t, self.y, self.yp)
        if not out.success:
            raise StepFailure(f"IDA could not start at t={self.t:g}: {out.message}")

    def reset_state(self, y):
        """Continue from a projected state ``y``: BDF's history cannot be projected, so IDA
        restarts from ``y`` (at order 1) when ``y`` moved by more than the tolerance, else it
        keeps its own state."""
        if self.moved_beyond_tolerance(y):
            self.y = np.array(y, dtype=float)
            self._njev_done = self.stats["njev"]
            self._start()
            self.stats["restarts"] += 1

    def _res(self, t, y, yp, res):
        try:
            F = self.prob.fun(t, np.array(y))
        except BaseException as exc:  # noqa: BLE001 - re-raised by _step, not from inside the C code
            self._fail = self._fail or exc  # the first: later calls see the NaN residual it leaves
            res[:] = np.nan
            return
        self.stats["nfev"] += 1
        res[:] = self._E * yp - F

    def _jac(self, t, y, yp, res, cj, JJ):
        """IDA's iteration matrix ``d res/dy + cj d res/dyp = cj E - d fun/dy`` from the
        problem's (exact) ``jac``."""
        try:
            J = self.prob.jac(t, np.array(y))
        except BaseException as exc:  # noqa: BLE001 - re-raised by _step, as for the residual
            self._fail = self._fail or exc
            JJ[:, :] = np.nan
            return
        JJ[:, :] = -J
        JJ[np.diag_indices_from(JJ)] += cj * self._E

    def _derivative(self, t, y):
        """``dy/dt`` at a consistent ``y``: ``fun`` on differential rows; algebraic variables
        do not enter ``E dy/dt`` at all, so their rate only seeds IDA's first predictor (0)."""
        F = self.prob.fun(t, y)
        self.stats["nfev"] += 1
        return np.where(self._E != 0.0, F, 0.0)

    def _step(self):
        t0, y0, yp0 = self.t, self.y.copy(), self.yp.copy()
        try:
            out = self._ida.step(self.t_bound, method="onestep", tstop=self.t_bound)
        except Exception as exc:  # noqa: BLE001
            raise StepFailure(f"IDA failed at t={self.t:g}: {exc}") from None
        if self._fail is not None:  # the model's own exception (or Ctrl-C), with its traceback
            exc, self._fail = self._fail, None
            raise exc
        if not out.success:
            raise StepFailure(f"IDA failed at t={self.t:g}: {out.message} (error test or Newton failures with the "
                              "step size at its minimum: stiff or singular dynamics, an index above 2, or tolerances "
                              "too tight)")
        self.t_old = t0
        self.t = float(np.atleast_1d(out.t)[-1])
        self.y = np.array(np.atleast_2d(out.y)[-1], dtype=float)
        self.yp = np.array(np.atleast_2d(out.yp)[-1], dtype=float)
        self._old = (t0, y0, yp0)
        self.stats["nsteps"] += 1
        self.stats["njev"] = self._njev_done + int(out.njev)
        self.stats["nlu"] = self.stats["njev"]

    def dense_output(self):
        t0, y0, yp0 = self._old
        t1, y1, yp1 = self.t, self.y.copy(), self.yp.copy()
        h = t1 - t0

        def y(t):
            if h == 0.0:
                return y1.copy()
            s = (t - t0) / h
            h00, h10, h01, h11 = 2 * s ** 3 - 3 * s ** 2 + 1, s ** 3 - 2 * s ** 2 + s, -2 * s ** 3 + 3 * s ** 2, s ** 3 - s ** 2
            return h00 * y0 + h10 * h * yp0 + h01 * y1 + h11 * h * yp1

        return y
