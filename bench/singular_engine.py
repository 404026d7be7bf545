"""singular="pass" in C: the N-four-bar through its flat positions, the C loop against the Python path.

The N-four-bar (models/n_four_bar.py: 20 s, rtol 1e-8, atol 1e-10, projection, 20 flat
positions at N = 10) against its exact one-degree-of-freedom reduction (DOP853 at 1e-13), by

* ``python``: before -- ``LagrangeIndex1.compiled_integrator`` None with ``singular="pass"``:
  scipy's DOP853 steps the compiled ``fun`` step by step, the rank monitor watching each step
  on its dense output, the rank monitor's evaluations by the program from the start;
* ``C``: now -- :class:`mbcomp.formulations.passing.PassingEngine`: DOP853 in C through the
  flat positions (the range-space solve where the program's guard fails), the minima of
  ``log det(C_k C_k^T)`` located on the C integrator's dense output and judged by the rank
  monitor, no restart next to them (the step holding one taken again from its start; a stretch
  of outputs ends at a natural step end and the next takes that step again);
* ``C+guard``: the plain engine's stretches as for ``singular="stop"`` (the program's guard
  hands a stretch near a flat position to the Python path): the strategy measured worse before.

Table 1: the default request at N = 10 (wall time, median of --repeats, the strategies taken in
turn; evaluations x one call of ``fun`` from Python timed alone). Table 2: every strategy over N in
{2, 3, 5, 7, 10} x n_out in {301, 501, 1001, 2001} (other output grids move the steps): runs
with every passage recorded, runs whose steps collapsed next to a flat position (more than
300 evaluations on the dense solve or the range-space solve in C), the largest and median
|theta - exact| (rad), the largest passage-time error (s) and energy drift (J), runs ending
"success" with an error above 1e-4 rad (a wrong answer called right).

Run: OPENBLAS_NUM_THREADS=1 python bench/singular_engine.py [--repeats 5] [--quick]   (~2 min; --quick ~40 s)
"""
import argparse
import pathlib
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

import mbcomp
from mbcomp.assembly.initialization import initialize
from mbcomp.codegen import compile_system
from mbcomp.formulations import LagrangeIndex1

ROOT = pathlib.Path(__file__).resolve().parent.parent
nfb = mbcomp.load_model_file(ROOT / "models" / "n_four_bar.py")
TODAY = LagrangeIndex1.compiled_integrator
COLLAPSE = 300  # evaluations on the dense solve in one run: steps shrank to microseconds at a flat position
WRONG = 1e-4  # rad: a run ending "success" farther than this from the exact motion is a wrong answer


def engine_with_guard(form):
    """The plain engine of ``singular="stop"`` for a passing run (its guard hands over)."""
    keep, form.singular = form.singular, "stop"
    try:
        return TODAY(form)
    finally:
        form.singular = keep


STRATEGIES = {
    "python": dict(engine=lambda form: None if form.singular == "pass" else TODAY(form)),
    "C": dict(),
    "C+guard": dict(engine=engine_with_guard),
}


def collapsed(r):
    """Evaluations on a dense or range-space solve in one run above :data:`COLLAPSE`."""
    return r.stats.get("fallbacks", 0) + r.stats.get("range_evaluations", 0) > COLLAPSE


def run(name, N, **kw):
    s = STRATEGIES[name]
    LagrangeIndex1.compiled_integrator = s.get("engine", TODAY)
    try:
        t0 = time.perf_counter()
        r = mbcomp.simulate(nfb.build(N=N), **{**nfb.SIMULATION, **kw})
        return r, time.perf_counter() - t0
    finally:
        LagrangeIndex1.compiled_integrator = TODAY


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
          "max passage error s | max energy drift J | wrong 'success' |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name in STRATEGIES:
        rows = []
        for N in Ns:
            for n_out in n_outs:
                r, _ = run(name, N, n_out=n_out)
                th, flats = exact(N, r.time)
                P = np.array([p["t"] for p in r.stats.get("singular_passages", [])])
                E = r["energy.total"]
                e = np.max(np.abs(r["theta"] - th))
                rows.append((len(P) == len(flats), collapsed(r), e,
                             np.max(np.abs(P - flats)) if len(P) == len(flats) else np.nan, np.max(np.abs(E - E[0])),
                             r.status == "success" and (e > WRONG or len(P) != len(flats))))
        ok, col, err, tp, dE, wrong = (np.array(c) for c in zip(*rows))
        print(f"| {name} | {len(rows)} | {ok.sum()} | {col.sum()} | {err.max():.1e} | {np.median(err):.1e} | "
              f"{np.nanmax(tp):.1e} | {dE.max():.1e} | {wrong.sum()} |")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="table 2 over N in {2, 10} x n_out in {501, 2001}")
    args = ap.parse_args(argv)
    table_one(args.repeats)
    table_two([2, 10] if args.quick else [2, 3, 5, 7, 10], [501, 2001] if args.quick else [301, 501, 1001, 2001])


if __name__ == "__main__":
    sys.exit(main())
