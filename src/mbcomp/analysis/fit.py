"""Parameter identification: least squares of result columns against measured time series, with
the exact trajectory sensitivities as the Jacobian (:func:`fit`).

The problem. Measured values ``y_k(t_i)`` of result columns ``k`` (coordinates, speeds, aliases
such as ``"crank_angle"``, any column of the output program: reactions, energies, poses) at
times ``t_i``; the model's values ``x_k(t_i; p)`` from a run with the parameters ``p``. The
fit minimises ``1/2 sum_k sum_i (w_k,i (x_k(t_i; p) - y_k(t_i)))^2`` with
``scipy.optimize.least_squares`` (trust-region reflective, bounds allowed), whose Jacobian
``w_k,i dx_k(t_i)/dp`` is the run's forward sensitivities
(:meth:`mbcomp.result.Result.sensitivity`: exact derivatives of the equations of motion,
integrated with the states) -- one run per evaluation gives the residual and its Jacobian,
no differencing.

Times. Measurement times on a uniform grid from ``t_start`` (any step that divides the span,
points may be missing) are output times of the run: the model is compared exactly there.
Other times (irregular sampling) are served by a cubic spline through a fine uniform output
grid (``n_out`` points, default ``max(2001, 8 x the number of times)``), values and
sensitivities alike; on the damped slider-crank of ``bench/fit_slider_crank.py`` (1.5 s, 2001
points) the spline's error is 4e-11 rad, below the runs' own. Runs with events (impacts) are not
smooth at the event: give times on a grid there.

Standard errors. At the solution ``J`` (weighted), residual ``r``, ``m`` data points and ``n``
parameters: ``s^2 = |r|^2 / (m - n)`` and ``cov = s^2 (J^T J)^-1`` (the usual linearised
estimate; with weights ``1/sigma`` of known measurement errors ``s^2`` should come out near 1).
A parameter the data cannot see (a singular ``J^T J``) gets an infinite standard error and the
message says which.

Examples
--------
A mass on a vertical spring-damper released 0.1 m below its rest: fit the spring rate and the
damping rate from its position, starting 30 % off.

>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Prismatic, PointMass, TranslationalSpringDamper
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, 0)))
>>> s = m.add("s", Prismatic(n=(0, 0, 1), s0=-0.1)); b = m.add("b", PointMass(m=1.0))
>>> k = m.add("k", TranslationalSpringDamper(c=40.0, d=0.8))
>>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> m.connect(k.flange_a, s.support); m.connect(k.flange_b, s.axis)
>>> meas = mbcomp.simulate(m, t_end=2.0, n_out=41, backend="python", rtol=1e-11, atol=1e-13)
>>> data = {"time": meas.time, "s.s": meas["s.s"]}
>>> f = mbcomp.fit(m, data, {"k.c": 28.0, "k.d": 0.56}, backend="python")
>>> f.success, [round(float(v), 6) for v in f.values]
(True, [40.0, 0.8])
"""
from __future__ import annotations

import difflib
import json
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError, SimulationError

__all__ = ["fit", "FitResult", "LeastSquares", "read_data"]

#: the name of the time column unless ``time=`` says otherwise
TIME = "time"


@dataclass
class FitResult:
    """What :func:`fit` found.

    Attributes
    ----------
    params : list of str
        The fitted parameters, as given.
    values : ndarray (n,)
        Their fitted values (each parameter's own unit).
    std_errors : ndarray (n,)
        Standard errors ``sqrt(diag(cov))`` (the parameters' units; ``inf`` for one the data
        cannot determine).
    start : ndarray (n,)
        The values the fit started from.
    covariance : ndarray (n, n)
        ``s^2 (J^T J)^-1`` at the solution.
    residual : dict
        ``{column: model - data}`` at the measurement times, unweighted (the column's unit).
    cost : float
        ``1/2 sum (w (model - data))^2`` at the solution.
    runs : int
        Simulations the fit took (each gives the residual and its Jacobian).
    status : int
        ``scipy.optimize.least_squares``'s status (> 0: converged).
    message : str
        Its message, and what else is worth knowing (parameters the data cannot see).
    optimizer : scipy.optimize.OptimizeResult
        The optimizer's own result (``jac``, ``grad``, ``nfev``, ``njev``, ...).

    Examples
    --------
    >>> import numpy as np
    >>> from mbcomp.analysis.fit import FitResult
    >>> f = FitResult(["rod.m"], np.array([2.01]), np.array([0.02]), np.array([1.5]), np.eye(1) * 4e-4,
    ...               {"crank_angle": np.zeros(3)}, 0.0, 7, 1, "converged")
    >>> f["rod.m"], f.as_dict()["rod.m"]["std_error"], f.success
    (2.01, 0.02, True)
    """

    params: list
    values: np.ndarray
    std_errors: np.ndarray
    start: np.ndarray
    covariance: np.ndarray
    residual: dict
    cost: float
    runs: int
    status: int
    message: str
    optimizer: object = field(default=None, repr=False)

    @property
    def success(self):
        """Whether the optimizer converged (``status > 0``)."""
        return self.status > 0

    def __getitem__(self, name):
        if name not in self.params:
            raise KeyError(f"{name!r} is not one of the fitted parameters {self.params}")
        return float(self.values[self.params.index(name)])

    def as_dict(self):
        """``{param: {"value", "std_error", "start"}}`` plus nothing else (see :meth:`to_json`)."""
        return {p: {"value": float(v), "std_error": float(e), "start": float(s)}
                for p, v, e, s in zip(self.params, self.values, self.std_errors, self.start)}

    def table(self):
        """The fitted values with their standard errors, one line per parameter (text)."""
        width = max([len("parameter")] + [len(p) for p in self.params])
        lines = [f"{'parameter':<{width}}  {'start':>12}  {'fitted':>14}  {'std error':>10}  {'rel':>8}"]
        for p, v, e, s in zip(self.params, self.values, self.std_errors, self.start):
            rel = f"{e / abs(v):8.2%}" if v != 0 and np.isfinite(e) else f"{'-':>8}"
            lines.append(f"{p:<{width}}  {s:12.6g}  {v:14.8g}  {e:10.3g}  {rel}")
        return "\n".join(lines)

    def to_json(self, path=None):
        """The result as JSON text (written to ``path`` when given): parameters, cost, rms of
        each column's residual, runs, status and message."""
        doc = {"params": self.as_dict(), "cost": float(self.cost), "runs": int(self.runs),
               "status": int(self.status), "success": bool(self.success), "message": self.message,
               "rms": {c: float(np.sqrt(np.mean(r ** 2))) for c, r in self.residual.items()},
               "covariance": np.asarray(self.covariance, float).tolist()}
        text = json.dumps(doc, indent=2, allow_nan=True)
        if path is not None:
            with open(path, "w") as fh:
                fh.write(text + "\n")
        return text


def read_data(data, columns=None, time=TIME):
    """``(times, {column: values})`` of measured data, checked.

    Parameters
    ----------
    data : mapping or DataFrame
        Arrays by column name (a dict, a ``pandas.DataFrame``, an :class:`mbcomp.result.Result`),
        one of them the time column.
    columns : list of str, optional
        The columns to fit (default: every column but the time).
    time : str
        The time column's name.

    Raises
    ------
    ValueError
        Naming the column and the fix: no time column, times not increasing, a column missing,
        of another length, or holding NaN / inf (with the first bad time).

    Examples
    --------
    >>> from mbcomp.analysis.fit import read_data
    >>> t, cols = read_data({"time": [0.0, 0.1, 0.2], "crank_angle": [0.3, 0.35, 0.41]})
    >>> t.tolist(), list(cols)
    ([0.0, 0.1, 0.2], ['crank_angle'])
    >>> read_data({"t": [0.0, 0.1], "x": [1.0, 2.0]})
    Traceback (most recent call last):
    ...
    ValueError: data: no time column 'time' (columns: t, x) -> fix: name the time column 'time', or pass time='t'
    """
    names = _names(data)
    if time not in names:
        raise ValueError(f"data: no time column {time!r} (columns: {', '.join(names)}) -> fix: name the time column "
                         f"'{time}', or pass time='{names[0] if names else 't'}'")
    t = _column(data, time, "time column")
    if len(t) < 2:
        raise ValueError(f"data: the time column {time!r} holds {len(t)} value(s) -> give at least two times")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"data: the time column {time!r} holds NaN or inf at row {int(np.argmin(np.isfinite(t)))} "
                         "-> fix: drop those rows")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"data: times must increase strictly, and {time}[{i + 1}] = {t[i + 1]:g} s follows "
                         f"{time}[{i}] = {t[i]:g} s -> fix: sort the rows by time and merge repeated times")
    columns = [n for n in names if n != time] if columns is None else list(columns)
    if not columns:
        raise ValueError(f"data: nothing to fit, only the time column {time!r} -> add measured columns")
    out = {}
    for c in columns:
        if c == time:
            raise ValueError(f"data: {time!r} is the time column and cannot be fitted -> remove it from columns")
        if c not in names:
            near = difflib.get_close_matches(c, names, n=3)
            raise ValueError(f"data: no column {c!r} (columns: {', '.join(names)})"
                             + (f" -> did you mean {' or '.join(map(repr, near))}?" if near else ""))
        y = _column(data, c, "column")
        if len(y) != len(t):
            raise ValueError(f"data: column {c!r} has {len(y)} values for {len(t)} times -> give one value per time")
        finite = np.isfinite(y)
        if not finite.all():
            i = int(np.argmin(finite))
            raise ValueError(f"data: column {c!r} holds {y[i]} at t = {t[i]:g} s (row {i}) -> fix: drop the row or "
                             "fill the value; every measured value must be a finite number")
        out[c] = y
    return t, out


def _names(data):
    if hasattr(data, "columns"):  # a DataFrame
        return [str(c) for c in data.columns]
    if hasattr(data, "names") and hasattr(data, "time"):  # an mbcomp Result
        return [TIME] + list(data.names)
    if hasattr(data, "keys"):
        return [str(c) for c in data.keys()]
    raise TypeError(f"data is a {type(data).__name__}: give a dict of arrays or a DataFrame with a time column")


def _column(data, name, what):
    try:
        values = np.asarray(data[name], dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"data: {what} {name!r} is not numbers ({exc}) -> give numeric values") from None
    if values.ndim != 1:
        raise ValueError(f"data: {what} {name!r} has shape {values.shape} -> give one value per time")
    return values


class _Param:
    """One fitted parameter: the runtime value it sets (an array entry sets the whole array)."""

    def __init__(self, system, name):
        from ..codegen.sensitivity import parameter_ref

        try:
            ref = parameter_ref(system, name)
        except ValueError as exc:
            raise ValueError("fit: " + str(exc).replace("sensitivity parameter", "parameter", 1)) from None
        self.name, self.key, self.index, self.model_value = ref.name, f"{ref.path}.{ref.param}", ref.index, ref.value
        self.array = None
        if ref.index is not None:
            current = getattr(system.P[ref.path], ref.param)
            self.array = np.array(getattr(current, "value", current), dtype=float)

    def value(self, x):
        """``(key, value)`` for ``simulate(params=...)`` at the parameter value ``x``."""
        if self.array is None:
            return self.key, float(x)
        arr = self.array.copy()
        arr[self.index] = x
        return self.key, arr


class LeastSquares:
    """The residual and its exact Jacobian of a fit (what :func:`fit` hands the optimizer).

    Parameters
    ----------
    model, data, params, columns, weights, time, values, t_start, n_out, rtol, atol, method,
    backend, simulate_options
        As in :func:`fit` (``params``: a list of names).

    Attributes
    ----------
    times : ndarray
        The measurement times (s).
    columns : list of str
        The fitted columns.
    runs : int
        Simulations so far.
    exact_times : bool
        Whether the measurement times are output times of the run (else a spline).
    n_out : int
        Output points of each run.
    index : ndarray or None
        The measurement times' indices among the output times (None: a spline).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.analysis.fit import LeastSquares
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> t = np.linspace(0.0, 1.0, 5)
    >>> ls = LeastSquares(m, {"time": t, "s.s": -0.5 * 9.0 * t ** 2}, ["world.g[2]"], backend="python")
    >>> r, J = ls.evaluate([-9.81])   # free fall: d s / d g = t^2 / 2
    >>> np.allclose(r, -0.405 * t ** 2), np.allclose(J[:, 0], 0.5 * t ** 2), ls.runs
    (True, True, 1)
    """

    def __init__(self, model, data, params, *, columns=None, weights=None, time=TIME, values=None, t_start=0.0,
                 n_out=None, rtol=1e-10, atol=1e-12, method="dop853", backend="auto", simulate_options=None):
        from ..simulation.setup import system_of

        self.times, self.data = read_data(data, columns, time)
        self.columns = list(self.data)
        if self.times[0] < t_start - 1e-12 * max(1.0, abs(t_start)):
            raise ValueError(f"data: the first time {self.times[0]:g} s is before the run's start t_start = "
                             f"{t_start:g} s -> fix: pass t_start={self.times[0]:g} (the model's start values hold "
                             "there) or drop the earlier rows")
        self.weights = _weights(weights, self.columns, len(self.times))
        _check_model(model)
        self.system = system_of(model, dict(values or {}), backend)
        names = [str(p) for p in params]
        if not names:
            raise ValueError("fit: no parameters -> name at least one, e.g. params=['rod.m']")
        twice = sorted({p for p in names if names.count(p) > 1})
        if twice:
            raise ValueError(f"fit: parameter {twice[0]!r} is named twice -> name each once")
        self.params = [_Param(self.system, p) for p in names]
        clash = [p for p in names if p in (values or {})]  # an array in values= with one entry fitted is fine
        if clash:
            raise ValueError(f"fit: {clash[0]!r} is both fitted and held fixed by values= -> drop it from values= "
                             "(the fit starts from the start value you give in params)")
        self.t_start, self.t_end = float(t_start), float(self.times[-1])
        self.n_out, self.index = _grid(self.t_start, self.times, n_out)
        self.exact_times = self.index is not None
        self.options = dict(simulate_options or {}, rtol=rtol, atol=atol, method=method, backend=backend)
        self.runs = 0
        self._last = None

    @property
    def names(self):
        """The parameters' names."""
        return [p.name for p in self.params]

    def start_values(self):
        """The parameters' values in the model (after ``values=``), the default start."""
        return np.array([p.model_value for p in self.params])

    def run(self, x):
        """The :class:`~mbcomp.result.Result` at parameter values ``x``, with sensitivities."""
        from ..simulation.driver import simulate

        x = np.asarray(x, dtype=float)
        params = {}
        for p, v in zip(self.params, x):  # entries of one array (rod.I[0, 0], rod.I[2, 2]) share its value
            key, value = p.value(v)
            if key in params and p.array is not None:
                params[key][p.index] = v
            else:
                params[key] = value
        self.runs += 1
        where = ", ".join(f"{n} = {v:.10g}" for n, v in zip(self.names, x))
        try:
            res = simulate(self.system, t_end=self.t_end, t_start=self.t_start, params=params,
                           sensitivities=self.names, n_out=self.n_out, **self.options)
        except ModelError as exc:
            raise ValueError(f"fit: the model refuses the values {where}: {exc} -> fix: give bounds= keeping the "
                             "parameters where they are valid (e.g. a mass in (0, inf)), or start closer") from exc
        if res.status not in ("success", "inaccurate") or len(res.time) < self.n_out:
            end = f"t = {res.time[-1]:g} s" if len(res.time) else "the start"
            raise SimulationError(f"fit: the run at {where} ended {res.status} at {end} "
                                  f"({res.message}) -> fix: bounds= keeping the parameters in a range where the model "
                                  "runs, a better start, or looser simulation tolerances")
        return res

    def evaluate(self, x):
        """``(r, J)`` at parameter values ``x``: the weighted residual ``w (model - data)`` of
        every column, stacked column after column, and its Jacobian ``w d model / d p``
        (shape ``(len(r), len(x))``) from the run's sensitivities; one run, remembered for the
        same ``x``."""
        x = np.asarray(x, dtype=float)
        if self._last is not None and np.array_equal(self._last[0], x):
            return self._last[1], self._last[2]
        res = self.run(x)
        r, J = [], []
        for c in self.columns:
            if c not in res:
                near = difflib.get_close_matches(c, res.names, n=4)
                raise ValueError(f"data column {c!r} is no result column of the model"
                                 + (f" (similar: {', '.join(near)})" if near else "")
                                 + " -> fix: rename the data column to a result column (coordinates, speeds, "
                                 "aliases, outputs), or choose the columns to fit with columns=[...]")
            value = self._at_times(res.time, res[c])
            try:
                sens = [self._at_times(res.time, res.sensitivity(c, p)) for p in self.names]
            except KeyError as exc:
                raise ValueError(f"data column {c!r}: {exc.args[0]} -> fit another column") from None
            self._check_finite(res, c, sens)
            w = self.weights[c]
            r.append(w * (value - self.data[c]))
            J.append(w[:, None] * np.column_stack(sens))
        r, J = np.concatenate(r), np.vstack(J)
        self._last = (x.copy(), r, J)
        return r, J

    def residual(self, x):
        """The weighted residual at ``x`` (see :meth:`evaluate`)."""
        return self.evaluate(x)[0]

    def jacobian(self, x):
        """Its Jacobian at ``x`` (see :meth:`evaluate`)."""
        return self.evaluate(x)[1]

    def _check_finite(self, res, column, sens):
        """A sensitivity that ended early (NaN: a mode holding rows, see
        :meth:`mbcomp.result.Result.sensitivity`) cannot steer the fit: say where and why."""
        for p, s in zip(self.names, sens):
            if not np.all(np.isfinite(s)):
                i = int(np.argmin(np.isfinite(s)))
                why = getattr(res.sensitivities, "stopped", None)
                raise SimulationError(f"fit: d {column} / d {p} is not finite from t = {self.times[i]:g} s"
                                      + (f" ({why[1]} at t = {why[0]:g} s)" if why else "")
                                      + " -> fix: fit the data before that time (drop the later rows)")

    def _at_times(self, t_run, values):
        values = np.asarray(values, dtype=float)
        if self.index is not None:
            return values[self.index]
        from scipy.interpolate import CubicSpline

        return CubicSpline(t_run, values)(self.times)


def _check_model(model):
    from ..assembly.system import MultibodySystem
    from ..modeling.model import Model

    if not isinstance(model, (Model, MultibodySystem)):
        hint = " (a build function: call it, fit(build(...), ...))" if callable(model) else ""
        raise TypeError(f"fit: model is a {type(model).__name__}; give a Model or an assembled MultibodySystem{hint}")


def _weights(weights, columns, n):
    """``{column: array (n,)}`` of the residual weights (default 1)."""
    if weights is None:
        return {c: np.ones(n) for c in columns}
    if not isinstance(weights, dict):
        weights = {c: weights for c in columns}
    unknown = [c for c in weights if c not in columns]
    if unknown:
        raise ValueError(f"weights: {unknown[0]!r} is not a fitted column ({', '.join(columns)}) -> weight those")
    out = {}
    for c in columns:
        w = np.broadcast_to(np.asarray(weights.get(c, 1.0), dtype=float), (n,)) if np.ndim(weights.get(c, 1.0)) == 0 \
            else np.asarray(weights[c], dtype=float)
        if w.shape != (n,):
            raise ValueError(f"weights[{c!r}] has {w.size} values for {n} times -> one number, or one per time")
        if not np.all(np.isfinite(w)) or np.any(w < 0):
            raise ValueError(f"weights[{c!r}]: weights must be finite and >= 0 (1/sigma of the measurement)")
        out[c] = np.array(w)
    return out


def _grid(t_start, times, n_out):
    """``(n_out, index)``: the run's output points and the measurement times' indices among
    them when they lie on a uniform grid from ``t_start``; else a fine grid for a spline and
    ``None``."""
    span = times[-1] - t_start
    if span <= 0:
        raise ValueError(f"data: the last time {times[-1]:g} s is not after t_start = {t_start:g} s -> nothing to run")
    step = np.min(np.diff(np.concatenate([[t_start], times]) if times[0] > t_start else times))
    if step > 0 and n_out is None:
        k = int(round(span / step))
        if k <= 200_000:
            grid = t_start + span * np.arange(k + 1) / k
            index = np.rint((times - t_start) / span * k).astype(int)
            if np.all(np.abs(grid[index] - times) <= 1e-9 * step):
                return k + 1, index
    n = int(n_out or max(2001, 8 * len(times)))
    if n < 4:
        raise ValueError(f"n_out={n}: a spline through the run needs at least 4 output points -> give n_out >= 4")
    return n, None


def _bounds(bounds, names, start):
    """``(lower, upper)`` arrays from ``{name: (lo, hi)}`` (None: unbounded), checked."""
    lo, hi = np.full(len(names), -np.inf), np.full(len(names), np.inf)
    for name, pair in (bounds or {}).items():
        if name not in names:
            raise ValueError(f"bounds: {name!r} is not a fitted parameter ({', '.join(names)}) -> bound those")
        try:
            a, b = pair
        except (TypeError, ValueError):
            raise ValueError(f"bounds[{name!r}] = {pair!r}: give a pair (lo, hi), None for no bound") from None
        j = names.index(name)
        lo[j] = -np.inf if a is None else float(a)
        hi[j] = np.inf if b is None else float(b)
        if not lo[j] < hi[j]:
            raise ValueError(f"bounds[{name!r}] = ({a}, {b}): the lower bound must be below the upper one")
        if not lo[j] <= start[j] <= hi[j]:
            raise ValueError(f"fit: {name} starts at {start[j]:g}, outside its bounds ({a}, {b}) -> give a start "
                             "value inside them (params={name: value})")
    return lo, hi


def _covariance(J, r, names):
    """``(cov, note)``: ``s^2 (J^T J)^-1`` with ``s^2 = |r|^2 / (m - n)``; directions the data
    cannot see (singular values below 1e-10 of the largest) get infinite variance."""
    m, n = J.shape
    if m <= n:
        return np.full((n, n), np.inf), f"no standard errors: {m} data points for {n} parameters"
    s2 = float(r @ r) / (m - n)
    _, sv, vt = np.linalg.svd(J, full_matrices=False)
    good = sv > 1e-10 * sv[0] if sv.size and sv[0] > 0 else np.zeros(n, bool)
    inv = np.where(good, 1.0 / np.where(good, sv, 1.0) ** 2, np.inf)
    cov = (vt.T * inv) @ vt if good.all() else _singular_cov(vt, inv)
    note = ""
    if not good.all():
        blind = sorted({names[int(np.argmax(np.abs(vt[k])))] for k in np.flatnonzero(~good)})
        note = f"the data cannot determine {', '.join(blind)} (J^T J is singular): infinite standard errors"
    return s2 * cov, note


def _singular_cov(vt, inv):
    """The covariance with the unseen directions infinite (no NaN from 0 * inf)."""
    n = vt.shape[1]
    cov = np.zeros((n, n))
    for k, v in enumerate(vt):
        outer = np.outer(v, v)
        if np.isinf(inv[k]):
            cov = np.where(np.abs(outer) > 1e-14, np.inf, cov)
        else:
            cov = cov + inv[k] * outer
    return cov


def fit(model, data, params, *, columns=None, bounds=None, weights=None, time=TIME, values=None, t_start=0.0,
        n_out=None, rtol=1e-10, atol=1e-12, method="dop853", backend="auto", simulate_options=None,
        solver_options=None) -> FitResult:
    """Fit parameters of a model to measured time series by least squares with exact derivatives.

    Parameters
    ----------
    model : Model or MultibodySystem
        The model (assembled and compiled once; each run changes only the parameter values).
    data : mapping or DataFrame
        Measured columns by result-column name (``"crank_angle"``, ``"slider_joint.s"``,
        ``"pin.f.x"``) and a time column (s), one value per time; times increasing strictly,
        all values finite.
    params : list of str or dict
        The parameters to fit, ``"component.param"`` or an array entry ``"rod.I[2, 2]"``
        (kg m^2) or a start value (``"crank_joint.phi0"``); a list starts from the model's
        values, a dict ``{name: start}`` from the values given (``None``: the model's value).
    columns : list of str, optional
        The data columns to fit (default: every column but the time).
    bounds : dict, optional
        ``{name: (lo, hi)}`` (``None``: no bound on that side), in the parameter's unit; a
        parameter the model only accepts in a range (a mass > 0, an inertia obeying the
        triangle inequality) needs bounds keeping it there.
    weights : dict or float, optional
        ``{column: w}``, ``w`` a number or one per time (``1/sigma`` of the measurement, the
        column's inverse unit); default 1.
    time : str
        The time column's name (default ``"time"``).
    values : dict, optional
        Runtime values of other parameters, held fixed (``{"crank.m": 1.2}``).
    t_start : float
        Start of the runs (s): the model's start values hold there; no data before it.
    n_out : int, optional
        Output points of each run when the measurement times are irregular (the spline's grid;
        see the module notes). Times on a uniform grid are output times exactly.
    rtol, atol : float
        The runs' tolerances (tighter than :func:`mbcomp.simulate`'s default: the residual's
        error must stay well below the noise for the standard errors to hold).
    method, backend : str
        As in :func:`mbcomp.simulate`; ``simulate_options``: any of its other keywords.
    solver_options : dict, optional
        Keywords of ``scipy.optimize.least_squares`` (``x_scale``, ``loss``, ``f_scale``,
        ``max_nfev``, ``ftol``, ``xtol``, ``gtol``); default ``x_scale="jac"``, tolerances 1e-12.

    Returns
    -------
    FitResult
        Fitted values, standard errors, covariance, residual per column, cost, runs, status.

    Raises
    ------
    ValueError
        Bad data (no time column, times not increasing, NaN, a column the model does not
        have), an unknown parameter, bounds not holding the start, values the model refuses.
    SimulationError
        A run that fails at the parameter values tried (the message gives them).

    Examples
    --------
    A 1 m pendulum released from 0.5 rad: fit the gravity from its angle at three times (the
    angles of a run with ``g = 9`` m/s^2, the fit starting from 9.81).

    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
    >>> j = m.add("j", Revolute(n=(0, 0, 1), phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> t = np.array([0.0, 0.5, 1.0])
    >>> truth = mbcomp.simulate(m, t_end=1.0, n_out=3, params={"world.g": (0, -9.0, 0)}, backend="python",
    ...                         rtol=1e-11, atol=1e-13)
    >>> f = mbcomp.fit(m, {"time": t, "j.phi": truth["j.phi"]}, ["world.g[1]"], backend="python")
    >>> round(f["world.g[1]"], 6), f.runs < 10
    (-9.0, True)
    """
    from scipy.optimize import least_squares

    names = list(params)
    problem = LeastSquares(model, data, names, columns=columns, weights=weights, time=time, values=values,
                           t_start=t_start, n_out=n_out, rtol=rtol, atol=atol, method=method, backend=backend,
                           simulate_options=simulate_options)
    x0 = problem.start_values()
    if isinstance(params, dict):
        x0 = np.array([x if params[n] is None else float(params[n]) for n, x in zip(names, x0)])
    bad = [n for n, v in zip(names, x0) if not math.isfinite(v)]
    if bad:
        raise ValueError(f"fit: the start value of {bad[0]} is not finite -> give params={{'{bad[0]}': value}}")
    lo, hi = _bounds(bounds, problem.names, x0)
    options = dict(x_scale="jac", ftol=1e-12, xtol=1e-12, gtol=1e-12)
    options.update(solver_options or {})
    opt = least_squares(problem.residual, x0, jac=problem.jacobian, bounds=(lo, hi), method="trf", **options)
    r, J = problem.evaluate(opt.x)
    cov, note = _covariance(J, r, problem.names)
    with np.errstate(invalid="ignore"):
        std = np.sqrt(np.diag(cov))
    residual, k = {}, 0
    for c in problem.columns:
        n = len(problem.times)
        w = problem.weights[c]
        with np.errstate(divide="ignore", invalid="ignore"):
            residual[c] = np.where(w > 0, r[k:k + n] / np.where(w > 0, w, 1.0), np.nan)
        k += n
    message = opt.message.rstrip(".") + (f"; {note}" if note else "")
    return FitResult(problem.names, np.array(opt.x), std, x0, cov, residual, float(0.5 * r @ r), problem.runs,
                     int(opt.status), message, opt)
