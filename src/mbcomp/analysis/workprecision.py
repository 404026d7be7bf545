"""Work-precision studies: every applicable formulation x solver over a tolerance sweep.

:func:`work_precision` runs each :class:`Combo` of a model at a sweep of tolerances (or of
step sizes, for fixed-step methods), measures the CPU time (``time.process_time`` around the
whole ``simulate`` call, output reduced to the end point) and the function evaluations, and
the error of the positions at ``t_end`` against a reference:

* the model file's ``reference(t_end=None, **build_kw) -> dict(t_end=..., values=..., source=...)``
  (a closed form for any of its parameters and end time, e.g. the door against its stop,
  whose values after several impacts measure the event location too), or
* the model file's ``REFERENCE = dict(t_end=..., values={name: value})`` (a published
  solution, e.g. Andrews' squeezing mechanism), or
* a tight-tolerance run of a *different* method than the one measured (the D'Alembert ODE
  with DOP853, or the index-1 ODE with projection when the model is measured with the
  D'Alembert form), so that no method is judged against itself.

The error is ``max_i |x_i - r_i| / max(|r_i|, floor)`` over the compared positions (the
reference's names, or the model's joint coordinates), with ``floor = 1e-3 max |r|`` so a
coordinate that happens to be zero does not make the relative error meaningless.

Examples
--------
>>> from mbcomp.workprecision import default_combos
>>> [c.label for c in default_combos()][:3]
['ODE i1 Baumgarte / DOP853', 'ODE i1 projection / DOP853', 'ODE i1 projection / Radau']
"""
from __future__ import annotations

import csv
import math
import os
import time
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Combo", "default_combos", "work_precision", "reference_values", "fastest", "summary", "write_csv", "plot"]


@dataclass(frozen=True)
class Combo:
    """One formulation x solver pair: ``simulate`` options and what the sweep varies.

    Attributes
    ----------
    label : str
    options : dict
        Keyword arguments of :func:`mbcomp.simulate` (``formulation``, ``method``, ``index``...).
    sweep : {"tol", "h"}
        Tolerances (``rtol``; ``atol = rtol * atol_ratio``) or fixed step sizes.
    family : str
        For colouring charts: ``"ode"``, ``"dalembert"``, ``"dae"``, ``"peer"``.

    Examples
    --------
    >>> from mbcomp.workprecision import Combo
    >>> Combo("D'Alembert / DOP853", dict(formulation="dalembert", method="DOP853")).sweep
    'tol'
    """

    label: str
    options: dict = field(default_factory=dict)
    sweep: str = "tol"
    family: str = "ode"


def default_combos(fixed_step=True, backend="python"):
    """Every formulation x solver pair mbcomp offers (generalized-alpha with ``fixed_step``),
    evaluated by ``backend`` (the generated Python program by default: the same numbers as the
    numeric path, ~10x faster), plus two pairs on the numeric path to show its cost.

    Examples
    --------
    >>> from mbcomp.workprecision import default_combos
    >>> len(default_combos()) >= 12, default_combos()[0].options["backend"]
    (True, 'python')
    """
    c = [
        Combo("ODE i1 Baumgarte / DOP853", dict(method="DOP853", stabilization="baumgarte")),
        Combo("ODE i1 projection / DOP853", dict(method="DOP853", stabilization="projection")),
        Combo("ODE i1 projection / Radau", dict(method="Radau", stabilization="projection")),
        Combo("ODE i1 projection / LSODA", dict(method="LSODA", stabilization="projection")),
        Combo("D'Alembert / DOP853", dict(formulation="dalembert", method="DOP853"), family="dalembert"),
        Combo("D'Alembert / Radau", dict(formulation="dalembert", method="Radau"), family="dalembert"),
        Combo("D'Alembert / LSODA", dict(formulation="dalembert", method="LSODA"), family="dalembert"),
        Combo("D'Alembert / DOP853 / C program", dict(formulation="dalembert", method="DOP853", backend="auto"),
              family="dalembert"),
        Combo("ODE i1 projection / DOP853 / numeric", dict(method="DOP853", stabilization="projection",
                                                             backend="numeric")),
        Combo("DAE i3 / radau5 / numeric", dict(method="radau5", index=3, stabilization="none", backend="numeric"),
              family="dae"),
        Combo("DAE i1 Baumgarte / radau5", dict(method="radau5", index=1, stabilization="baumgarte"), family="dae"),
        Combo("DAE i2 GGL / radau5", dict(method="radau5", index=2, stabilization="none"), family="dae"),
        Combo("DAE i3 / radau5", dict(method="radau5", index=3, stabilization="none"), family="dae"),
        Combo("DAE i1 Baumgarte / IDA", dict(method="ida", index=1, stabilization="baumgarte"), family="dae"),
        Combo("DAE i2 GGL / IDA", dict(method="ida", index=2, stabilization="none"), family="dae"),
    ]
    if fixed_step:
        c.append(Combo("DAE i3 / gen-alpha 0.9", dict(method="genalpha", index=3, stabilization="none"),
                       sweep="h", family="dae"))
    return [Combo(x.label, {"backend": backend, **x.options}, x.sweep, x.family) for x in c]


def _positions(res, names):
    return np.array([float(res[n][-1]) for n in names])


def reference_values(module, build_kw=None, params=None, t_end=None, rtol=1e-12, atol=1e-14):
    """``(t_end, {name: value}, how)``: the model file's ``reference(...)`` closed form, its
    ``REFERENCE`` or a tight run.

    The tight run uses the D'Alembert ODE with DOP853 and is cross-checked by the index-1
    ODE with projection; ``how`` says which and how far the two agree.
    """
    from ..simulation.driver import simulate

    closed = getattr(module, "reference", None)
    if callable(closed) and not params:  # run-time parameters would change what it computes
        ref = closed(t_end=t_end, **(build_kw or {}))
        return ref["t_end"], dict(ref["values"]), ref.get("source", "closed form")
    ref = getattr(module, "REFERENCE", None)
    if ref is not None and t_end in (None, ref["t_end"]):
        return ref["t_end"], dict(ref["values"]), ref.get("source", "published reference")
    sim = dict(getattr(module, "SIMULATION", {}))
    t_end = t_end or sim.get("t_end", 1.0)
    model = module.build(**(build_kw or {}))
    a = simulate(model, t_end=t_end, params=params, formulation="dalembert", method="DOP853", rtol=rtol, atol=atol,
                 n_out=2)
    b = simulate(module.build(**(build_kw or {})), t_end=t_end, params=params, method="DOP853",
                 stabilization="projection", rtol=rtol, atol=atol, n_out=2)
    if not (a.success and b.success):
        raise RuntimeError(f"the reference runs failed: {a.message} / {b.message}")
    from ..assembly.system import assemble

    names = list(assemble(module.build(**(build_kw or {}))).q_names)
    va, vb = _positions(a, names), _positions(b, names)
    diff = _error(va, vb)
    return t_end, dict(zip(names, va)), f"D'Alembert/DOP853 rtol={rtol:g} (index-1 ODE/projection agrees to {diff:.1e})"


def _error(x, r):
    floor = 1e-3 * max(np.max(np.abs(r)), 1e-300)
    return float(np.max(np.abs(x - r) / np.maximum(np.abs(r), floor)))


def work_precision(module, combos=None, tols=None, steps=None, build_kw=None, params=None, t_end=None,
                   atol_ratio=1e-2, max_cpu=60.0, reference=None, log=print, executor=None, progress=False):
    """Run every combo over the sweep; returns a list of row dicts.

    Parameters
    ----------
    module : module or path
        A model file's module (``build(**kw) -> Model``, optional ``SIMULATION``,
        ``REFERENCE``), or the model file's path.
    combos : list of Combo, optional
        Default :func:`default_combos`.
    tols : sequence of float
        ``rtol`` values (default 1e-3 ... 1e-10); ``atol = rtol * atol_ratio``.
    steps : sequence of int
        Numbers of fixed steps over the span for ``sweep="h"`` combos (default 30 ... 10000).
    max_cpu : float
        A combo stops sweeping once one run took longer than this (s): tighter settings would
        take longer still.
    reference : tuple, optional
        ``(t_end, values, how)`` to use instead of :func:`reference_values`.
    executor : None, concurrent.futures.Executor, "dask", "tcp://host:port" or dask Client
        Where the combos' sweeps run, one task per combo
        (:func:`mbcomp.analysis.parallel.map_on`; the model travels as its file's path, so
        ``module`` must have come from a file). The rows equal the serial ones (``None``)
        but for the CPU times; each combo's lines are logged when it has finished.
    progress : bool
        A progress bar counting finished combos (with an executor).

    Returns
    -------
    list of dict
        ``combo, family, setting, value, status, cpu_s, nfev, steps, error, message``.

    Examples
    --------
    >>> from mbcomp.workprecision import default_combos, work_precision
    >>> rows = work_precision("models/slider_crank.py", default_combos()[:1], tols=[1e-4], t_end=0.1,
    ...                       reference=(0.1, {"crank_joint.phi": 0.6226207376}, "given"), log=lambda line: None)
    >>> rows[0]["combo"], rows[0]["status"], rows[0]["error"] < 1e-3
    ('ODE i1 Baumgarte / DOP853', 'success', True)
    """
    from .parallel import map_on

    source = module
    if isinstance(module, (str, os.PathLike)):
        module = _module_at(os.fspath(module))
    combos = default_combos() if combos is None else combos
    tols = tols or [10.0 ** -k for k in range(3, 11)]
    steps = steps or [30, 100, 300, 1000, 3000, 10000]
    t_ref, values, how = reference or reference_values(module, build_kw, params, t_end)
    log(f"reference at t={t_ref:g}: {how}")
    job = dict(tols=tols, steps=steps, build_kw=build_kw, params=params, t_ref=t_ref, values=values,
               atol_ratio=atol_ratio, max_cpu=max_cpu)
    if executor is None:
        return [row for c in combos for row in _combo_rows(module, c, job, log)]
    path = os.fspath(source) if isinstance(source, (str, os.PathLike)) else getattr(module, "__file__", None)
    if not path:
        raise ValueError("work_precision(executor=...) sends the model file's path to the workers, and this module "
                         "has no file -> pass the model file's path (or a module loaded from one)")
    rows = []
    for lines, combo_rows in map_on(executor, _ComboTask(os.path.abspath(path), job), combos, progress=progress):
        for line in lines:
            log(line)
        rows.extend(combo_rows)
    return rows


#: model files loaded in this process (a worker's), by path
_MODULES = {}


def _module_at(path):
    if path not in _MODULES:
        from ..modeling.loader import load_model_file

        _MODULES[path] = load_model_file(path)
    return _MODULES[path]


class _ComboTask:
    """One combo's sweep in a worker: ``(log lines, rows)`` (module-level: it pickles)."""

    def __init__(self, path, job):
        self.path, self.job = path, job

    def __call__(self, combo):
        lines = []
        rows = _combo_rows(_module_at(self.path), combo, self.job, lines.append)
        return lines, rows


def _combo_rows(module, c, job, log):
    """The rows of combo ``c`` over the sweep of ``job`` (see :func:`work_precision`)."""
    from ..simulation.driver import simulate

    t_ref, build_kw, params = job["t_ref"], job["build_kw"], job["params"]
    names = list(job["values"])
    r = np.array([job["values"][n] for n in names])
    settings = [("rtol", tol) for tol in job["tols"]] if c.sweep == "tol" else [("h", t_ref / n) for n in job["steps"]]
    rows = []
    for kind, val in settings:
        kw = dict(c.options)
        if kind == "rtol":
            kw.update(rtol=val, atol=val * job["atol_ratio"])
        else:
            kw.update(h=val, rtol=1e-8, atol=1e-10)
        t0 = time.process_time()
        try:
            res = simulate(module.build(**(build_kw or {})), t_end=t_ref, params=params, n_out=2, **kw)
            status, msg = res.status, res.message
            nfev, nst = res.stats.get("nfev", 0), res.stats.get("steps", 0)
            err = _error(_positions(res, names), r) if res.success else math.nan
        except Exception as exc:  # noqa: BLE001 - a refused combination is a row, not a crash
            status, msg, nfev, nst, err = "error", f"{type(exc).__name__}: {exc}", 0, 0, math.nan
        cpu = time.process_time() - t0
        rows.append(dict(combo=c.label, family=c.family, setting=kind, value=val, status=status, cpu_s=cpu,
                         nfev=nfev, steps=nst, error=err, message=msg[:200]))
        log(f"  {c.label:<36} {kind}={val:<9.2g} {status:<8} cpu {cpu:8.3f} s  nfev {nfev:>8}  "
            f"error {err:9.2e}" + ("" if status == "success" else f"  ({msg[:90]})"))
        if cpu > job["max_cpu"] or status == "error":
            break
    return rows


def fastest(rows, target=1e-6):
    """Per combo: the least CPU time of a run whose error is at most ``target`` (or None).

    Examples
    --------
    >>> from mbcomp.workprecision import fastest
    >>> rows = [dict(combo="a", cpu_s=2.0, error=1e-7, nfev=10), dict(combo="a", cpu_s=1.0, error=1e-5, nfev=5)]
    >>> fastest(rows)["a"]["cpu_s"]
    2.0
    """
    out = {}
    for r in rows:
        best = out.setdefault(r["combo"], None)
        if r["error"] == r["error"] and r["error"] <= target and (best is None or r["cpu_s"] < best["cpu_s"]):
            out[r["combo"]] = r
    return out


def summary(rows, target=1e-6, title=""):
    """Table (str): per combo the fastest run reaching ``target``, with its CPU-time ratio to the
    fastest ``family="peer"`` run when there is one, or why the target was not reached.

    Examples
    --------
    >>> from mbcomp.workprecision import summary
    >>> rows = [dict(combo="a", family="ode", cpu_s=2.0, error=1e-7, nfev=10, setting="rtol", value=1e-8, status="success"),
    ...         dict(combo="p", family="peer", cpu_s=1.0, error=1e-7, nfev=9, setting="rtol", value=1e-8, status="success")]
    >>> print(summary(rows).splitlines()[2].split()[:3])
    ['a', '2.000', '2.00']
    """
    best = fastest(rows, target)
    peers = [b for b in best.values() if b is not None and b.get("family") == "peer"]
    peer = min(peers, key=lambda b: b["cpu_s"]) if peers else None
    lines = [f"{title}: fastest CPU time reaching relative position error <= {target:g}"
             + (f" (ratio to {peer['combo']}, {peer['cpu_s']:.3f} s)" if peer else " (no sympy peer)"),
             f"{'combination':<40}{'cpu [s]':>9}{'ratio':>8}{'nfev':>9}{'error':>10}  setting"]
    for combo in dict.fromkeys(r["combo"] for r in rows):
        b = best.get(combo)
        if b is None:
            bad = [r for r in rows if r["combo"] == combo and r["status"] != "success"]
            why = f" ({bad[0]['message'][:60]})" if bad else ""
            lines.append(f"{combo:<40}{'-':>9}{'-':>8}{'-':>9}{'-':>10}  not reached{why}")
            continue
        ratio = f"{b['cpu_s'] / peer['cpu_s']:8.2f}" if peer else f"{'-':>8}"
        lines.append(f"{combo:<40}{b['cpu_s']:>9.3f}{ratio}{b['nfev']:>9}{b['error']:>10.1e}  "
                     f"{b['setting']}={b['value']:.2g}")
    return "\n".join(lines)


def write_csv(rows, path):
    """Write the rows (one per run) to ``path``."""
    keys = ["combo", "family", "setting", "value", "status", "cpu_s", "nfev", "steps", "error", "message"]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


def plot(rows, path, title="", target=1e-6):
    """Error versus CPU time and versus function evaluations (log-log), one curve per combo."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(13, 5.2))
    styles = {"ode": "-o", "dalembert": "-s", "dae": "-^", "peer": "--D"}
    for k, combo in enumerate(dict.fromkeys(r["combo"] for r in rows)):
        rr = [r for r in rows if r["combo"] == combo and r["error"] == r["error"] and r["error"] > 0]
        if not rr:
            continue
        st = styles.get(rr[0]["family"], "-o")
        col = f"C{k % 10}"
        a1.loglog([r["cpu_s"] for r in rr], [r["error"] for r in rr], st, color=col, ms=4, label=combo)
        a2.loglog([max(r["nfev"], 1) for r in rr], [r["error"] for r in rr], st, color=col, ms=4, label=combo)
    for a, xl in ((a1, "CPU time [s]"), (a2, "function evaluations")):
        a.axhline(target, color="k", lw=0.6, ls=":")
        a.set(xlabel=xl, ylabel="max relative position error at t_end")
        a.grid(True, which="both", alpha=0.3)
    a1.set_title(f"{title}: error vs CPU time")
    a2.set_title(f"{title}: error vs function evaluations")
    a2.legend(fontsize=6.5, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
