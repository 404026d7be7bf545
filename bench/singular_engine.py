"""singular="pass" on the C engine? Four ways of stepping the N-four-bar through its flat positions.

The N-four-bar (models/n_four_bar.py: 20 s, rtol 1e-8, atol 1e-10, projection, 20 flat
positions) against its exact one-degree-of-freedom reduction (DOP853 at 1e-13), by

* ``python, lazy``: before -- ``LagrangeIndex1.compiled_integrator`` is None with
  ``singular="pass"``: scipy's DOP853 steps the compiled ``fun`` step by step, the rank monitor
  watching each step, and the evaluations (monitor, projections) are numeric until the lazy
  evaluator's ``LAZY_EVALUATIONS`` (200) ran out;
* ``python``: now -- the same steps, the rank monitor evaluating by the program from its start
  (:func:`mbcomp.simulation.monitors.evaluate_by_program`);
* ``C+guard``: the C engine's stretches as for ``singular="stop"``; the program's guard
  (``ROWS_PIVOT_TOL``) fails near a flat position, the stretch goes on in Python;
* ``C+handoff``: C stretches that end on the Python path three C steps before a flat position
  the samples of the stretch's dense output predict (``sigma`` extrapolated to zero), an
  experiment written here (:class:`Handoff`), not in the package.

The C strategies run with the evaluation program made at the start, as ``python``.

Table 1: the default request at N = 10 (wall time, median of --repeats, the strategies taken in
turn; evaluations x one call of ``fun`` from Python timed alone). Table 2: every strategy over N in
{2, 3, 5, 7, 10} x n_out in {301, 501, 1001, 2001} (other output grids move the steps): runs
with every passage recorded, runs whose steps collapsed next to a flat position (more than
300 evaluations on the dense solve), the largest and median |theta - exact| (rad), the largest
passage-time error (s) and energy drift (J).

Run: OPENBLAS_NUM_THREADS=1 python bench/singular_engine.py [--repeats 5] [--quick]   (~3 min; --quick ~1 min)
"""
import argparse
import pathlib
import sys
import time
from types import SimpleNamespace

import numpy as np
from scipy.integrate import solve_ivp

import mbcomp
from mbcomp.assembly.initialization import initialize
from mbcomp.codegen import compile_system
from mbcomp.simulation import monitors
from mbcomp.formulations import LagrangeIndex1

ROOT = pathlib.Path(__file__).resolve().parent.parent
nfb = mbcomp.load_model_file(ROOT / "models" / "n_four_bar.py")
TODAY = LagrangeIndex1.compiled_integrator
BY_PROGRAM = monitors.evaluate_by_program
COLLAPSE = 300  # evaluations on the dense solve in one run: steps shrank to microseconds at a flat position


def sigma(system, t, y):
    """The rank monitor's smallest relative singular value at ``y = [q, u]``."""
    ev = system.evaluate(t, y[: system.nq], y[system.nq: system.nq + system.nu], masked=False)
    sv = np.linalg.svd(ev.C, compute_uv=False)
    r = int(system.row_mask.sum())
    return float(sv[r - 1] / sv[0]) if sv.size >= r and sv[0] > 0 else 0.0


class Handoff:
    """The engine, its stretch ended on the Python path (status 1) ``LEAD`` C steps before a
    flat position the dense output's samples (``SAMPLES`` per step) predict."""

    SAMPLES, LEAD = 8, 3.0

    def __init__(self, engine, system):
        self.engine, self.system, self.h = engine, system, 0.0

    def __getattr__(self, name):
        if name in ("engine", "system", "h"):
            raise AttributeError(name)
        return getattr(self.engine, name)

    def integrate(self, order, t0, y0, t_end, t_out, rtol, atol, h0=0.0, **kw):
        h_ref = self.h or h0 or (t_end - t0) / 16.0
        grid = np.union1d(np.union1d(t_out, t0 + h_ref / self.SAMPLES * np.arange(1, 1 + int(
            (t_end - t0) / (h_ref / self.SAMPLES)))), [t_end])
        grid = grid[(grid > t0) & (grid <= t_end)]
        r = self.engine.integrate(order, t0, y0, t_end, grid, rtol, atol, h0=h0, **kw)
        if r.naccept > 1:
            self.h = max(r.h_last, (r.t_last - t0) / r.naccept)
        h = self.h or h_ref
        times, wanted = grid[: len(r.Y)], np.isin(grid[: len(r.Y)], t_out)
        guard = r.t_last + h if r.status in (1, 5) else np.inf
        t_flat = self.flat_ahead(t0, y0, times, r.Y, guard, 4 * h)
        if t_flat is None and np.isfinite(guard):
            t_flat = r.t_last + 0.5 * h
        if t_flat is None:
            return SimpleNamespace(**{**vars(r), "Y": r.Y[wanted]})
        k = np.flatnonzero((times <= t_flat - self.LEAD * h) & (times < guard))
        t_cut, y_cut, Y = (t0, y0, r.Y[:0]) if not k.size else (times[k[-1]], r.Y[k[-1]],
                                                                  r.Y[: k[-1] + 1][wanted[: k[-1] + 1]])
        return SimpleNamespace(**{**vars(r), "status": 1, "Y": Y, "t_last": float(t_cut), "y_last": np.array(y_cut),
                                  "h_last": h0 or h if not k.size else h, "declined": 0})

    def flat_ahead(self, t0, y0, times, Y, guard, horizon):
        t_zero, (t_prev, s_prev) = None, (t0, sigma(self.system, t0, y0))
        for tk, yk in zip(times, Y):
            if tk >= guard:
                break
            s = sigma(self.system, tk, yk)
            if s < s_prev:
                z = tk + s * (tk - t_prev) / (s_prev - s)
                if t_zero is not None or z - tk <= horizon:
                    t_zero = z
            elif t_zero is not None:
                break
            t_prev, s_prev = tk, s
        return t_zero


def engine_with_pass(form, wrap=None):
    """``compiled_integrator`` without the ``singular="pass"`` exclusion (``wrap``: around it)."""
    keep, form.singular = form.singular, "stop"
    try:
        engine = TODAY(form)
    finally:
        form.singular = keep
    return wrap(engine, form.system) if wrap is not None and engine is not None else engine


STRATEGIES = {
    "python, lazy": dict(lazy=True),
    "python": dict(),
    "C+guard": dict(engine=lambda form: engine_with_pass(form)),
    "C+handoff": dict(engine=lambda form: engine_with_pass(form, Handoff)),
}


def run(name, N, **kw):
    s = STRATEGIES[name]
    LagrangeIndex1.compiled_integrator = s.get("engine", TODAY)
    if s.get("lazy"):  # as before: no evaluation program until LAZY_EVALUATIONS numeric evaluations
        monitors.evaluate_by_program = lambda system: None
    try:
        t0 = time.perf_counter()
        r = mbcomp.simulate(nfb.build(N=N), **{**nfb.SIMULATION, **kw})
        return r, time.perf_counter() - t0
    finally:
        LagrangeIndex1.compiled_integrator = TODAY
        monitors.evaluate_by_program = BY_PROGRAM


def exact(N, ts):
    J = (N + 1) / 3 + N
    k = 9.81 * ((N + 1) / 2 + N)
    sol = solve_ivp(lambda t, y: [y[1], -k * np.cos(y[0]) / J], (0.0, ts[-1]), [np.pi / 2, 1.0], t_eval=ts,
                    events=lambda t, y: np.sin(y[0]), rtol=1e-13, atol=1e-13, method="DOP853")
    return sol.y[0], sol.t_events[0]


def fun_call_seconds(N):
    """One call of the Lagrange ``fun`` from Python (the thin C call), s."""
    system = compile_system(mbcomp.assemble(nfb.build(N=N)), "c")
    init = initialize(system)
    form = LagrangeIndex1(system, "projection", singular="pass")
    y = form.initial_state(0.0, init.q, init.u)
    form.fun(0.0, y)
    n = 20000
    t0 = time.perf_counter()
    for _ in range(n):
        form.fun(0.0, y)
    return (time.perf_counter() - t0) / n


def table_one(repeats):
    N = 10
    call = fun_call_seconds(N)
    print(f"\n### N = {N}, the default request (20 s, {len(exact(N, np.linspace(0, 20, 11))[1])} flat positions); "
          f"one fun call from Python {call * 1e6:.2f} us\n")
    print("| strategy | wall s (median) | status | passages | max err rad | C stretches | evaluations | "
          "fun calls s |")
    print("|---|---:|---|---:|---:|---:|---:|---:|")
    times = {name: [] for name in STRATEGIES}
    last = {}
    for name in STRATEGIES:
        run(name, N)  # warm: programs compiled and cached
    for _ in range(repeats):  # in turn: a machine's load changes during the table
        for name in STRATEGIES:
            last[name], dt = run(name, N)
            times[name].append(dt)
    for name in STRATEGIES:
        r = last[name]
        th, flats = exact(N, r.time)
        print(f"| {name} | {np.median(times[name]):.3f} | {r.status} | {len(r.stats.get('singular_passages', []))} of "
              f"{len(flats)} | {np.max(np.abs(r['theta'] - th)):.1e} | {r.stats.get('stretches', 0)} | "
              f"{r.stats['nfev']} | {r.stats['nfev'] * call:.4f} |")


def table_two(Ns, n_outs):
    print(f"\n### every strategy over N in {Ns} x n_out in {n_outs} (rtol 1e-8)\n")
    print("| strategy | runs | every passage recorded | collapsed at a flat | max err rad | median err rad | "
          "max passage error s | max energy drift J |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for name in STRATEGIES:
        rows = []
        for N in Ns:
            for n_out in n_outs:
                r, _ = run(name, N, n_out=n_out)
                th, flats = exact(N, r.time)
                P = np.array([p["t"] for p in r.stats.get("singular_passages", [])])
                E = r["energy.total"]
                rows.append((len(P) == len(flats), r.stats.get("fallbacks", 0) > COLLAPSE,
                             np.max(np.abs(r["theta"] - th)),
                             np.max(np.abs(P - flats)) if len(P) == len(flats) else np.nan, np.max(np.abs(E - E[0]))))
        ok, col, err, tp, dE = (np.array(c) for c in zip(*rows))
        print(f"| {name} | {len(rows)} | {ok.sum()} | {col.sum()} | {err.max():.1e} | {np.median(err):.1e} | "
              f"{np.nanmax(tp):.1e} | {dE.max():.1e} |")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="table 2 over N in {2, 10} x n_out in {501, 2001}")
    args = ap.parse_args(argv)
    table_one(args.repeats)
    table_two([2, 10] if args.quick else [2, 3, 5, 7, 10], [501, 2001] if args.quick else [301, 501, 1001, 2001])


if __name__ == "__main__":
    sys.exit(main())
