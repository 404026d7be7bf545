"""The fixed cost of ``simulate`` and the cost of one right-hand-side call, against Pinocchio.

Two tables, ratios in one run (the machine is shared: medians of repeats):

1. *Warm fixed cost*: ``simulate(build(N), t_end=1e-9, n_out=2)`` (``--n-out``) of the N-link pendulum
   (``models/n_link_pendulum.py``) on a model built anew each time, after one ``simulate(build(N))``
   with the defaults (501 outputs) has made the structure's programs -- the right-hand side and
   the output program (the structure cache of ``codegen/structure_key.py`` is warm, the compile
   cache too) -- wall ms, median of ``--repeats``; with the time of its phases (``--phases``:
   system, initialization, post-processing, the rest); and the same call with the default 501
   outputs (the fixed cost plus the output program over the grid: at N = 100, ~3,000 columns x
   501 points).
2. *One call*: ``LagrangeIndex1.fun(t, y)`` as scipy calls it (the formulation of a compiled
   system) against Pinocchio's ``aba`` called from Python and the peer's whole ``rhs``
   (``[u, aba]``, ``bench/peers/pinocchio_pendulum.py``), and the program's bare C call through
   ctypes (``mbcomp_fun`` with its buffers) and in a C loop (the function alone: what Python
   adds is ``fun`` minus that), us per call, best of 5 batches.

Run: ``python bench/fixed_cost.py`` (``--sizes 5 100 1000`` for the fixed cost; the first
run of a size compiles its program: minutes at N = 1000 with a cold compile cache).
"""
import argparse
import importlib.util
import os
import sys
import time
import timeit

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import mbcomp  # noqa: E402
from mbcomp.codegen import compile_system  # noqa: E402
from mbcomp.formulations import LagrangeIndex1  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def pendulum_module():
    spec = importlib.util.spec_from_file_location("n_link_pendulum", os.path.join(ROOT, "models", "n_link_pendulum.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def fixed_cost(mod, N, repeats, phases=False, n_out=2):
    """Median wall seconds of a warm ``simulate`` of a freshly built model, and its phases."""
    mbcomp.simulate(mod.build(N), t_end=1e-9)  # cold, the defaults: trace, print, compile both programs
    import mbcomp.simulation.driver as driver

    spent = {}
    originals = {}
    if phases:
        for name in ("system_of", "initialize_in_modes", "postprocess"):
            f = originals[name] = getattr(driver, name)

            def timed(*a, _f=f, _name=name, **k):
                t0 = time.perf_counter()
                try:
                    return _f(*a, **k)
                finally:
                    spent[_name] = spent.get(_name, 0.0) + time.perf_counter() - t0
            setattr(driver, name, timed)
    runs = []
    try:
        for _ in range(repeats):
            spent.clear()
            model = mod.build(N)
            t0 = time.perf_counter()
            res = mbcomp.simulate(model, t_end=1e-9, n_out=n_out)
            runs.append((time.perf_counter() - t0, dict(spent)))
    finally:
        for name, f in originals.items():
            setattr(driver, name, f)
    runs.sort(key=lambda r: r[0])
    total, parts = runs[len(runs) // 2]
    return total, parts, res.system.stats.get("structure_cache")


_LOOP_C = r"""
typedef int (*prog_t)(const double *, const double *, double, const double *, const double *,
                      const double *, double *, double *);
int loop(prog_t f, long n, const double *q, const double *u, const double *d, const double *h,
         const double *p, double *w, double *out) {
    int rc = 0;
    for (long k = 0; k < n; k++)
        rc |= f(q, u, 1e-9 * (double)k, d, h, p, w, out);
    return rc;
}
"""


def c_loop():
    """A C loop calling a generated program ``n`` times (ctypes), to time the C function alone."""
    import ctypes
    import subprocess
    import tempfile

    from mbcomp.codegen import c_compiler

    tmp = tempfile.mkdtemp()
    src, lib = os.path.join(tmp, "loop.c"), os.path.join(tmp, "loop.so")
    with open(src, "w") as fh:
        fh.write(_LOOP_C)
    subprocess.run([c_compiler(), "-O2", "-shared", "-fPIC", src, "-o", lib], check=True)
    fn = ctypes.CDLL(lib).loop
    fn.argtypes = [ctypes.c_void_p, ctypes.c_long] + [ctypes.c_void_p] * 7
    fn.restype = ctypes.c_int
    return fn


def best_per_call(f, number):
    return min(timeit.repeat(f, number=number, repeat=5)) / number


def one_call(mod, N, peer_module):
    system = compile_system(mbcomp.assemble(mod.build(N)), "c", lazy=True)
    form = LagrangeIndex1(system)
    rng = np.random.default_rng(N)
    y = np.concatenate((rng.uniform(-1, 1, N), rng.uniform(-1, 1, N)))
    form.fun(0.0, y)
    number = 20000
    out = dict(fun=best_per_call(lambda: form.fun(0.0, y), number))
    bound = system.evaluator.lagrange_bound()
    ptrs = bound.c_pointers()
    cfun = bound.code.dll.mbcomp_fun
    bound.run_fun(0.0, y, 10.0, 10.0)  # the gains and y in its buffers
    out["c"] = best_per_call(lambda: cfun(*ptrs), number)
    import ctypes

    loop, addr = c_loop(), ctypes.cast(cfun, ctypes.c_void_p).value
    q, u, _, d, h, p, w, o = ptrs
    reps = 200000
    out["c_alone"] = min(timeit.repeat(lambda: loop(addr, reps, q, u, d, h, p, w, o), number=1, repeat=5)) / reps
    thin = system.evaluator.lagrange_thin(10.0, 10.0)
    out["thin"] = best_per_call(lambda: thin(0.0, y), number) if thin is not None else np.nan
    if peer_module is not None:
        peer = peer_module.build(N) if hasattr(peer_module, "build") else None
        pin = peer.pin
        q, u, tau = y[:N], y[N:], np.zeros(N)
        out["aba"] = best_per_call(lambda: pin.aba(peer.model, peer.data, q, u, tau), number)
        out["rhs"] = best_per_call(lambda: peer.rhs(0.0, y), number)
        ref = peer.rhs(0.0, y)
        out["agree"] = float(np.max(np.abs(form.fun(0.0, y) - ref)))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[5, 100])
    ap.add_argument("--calls", type=int, nargs="*", default=[5, 10, 20, 40])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--phases", action="store_true", help="also time the phases of simulate")
    ap.add_argument("--n-out", type=int, default=2, help="output points of the timed calls (the output program, "
                    "made by the first run with the default grid, post-processes them)")
    args = ap.parse_args()
    mod = pendulum_module()
    try:
        from peers import pinocchio_pendulum as peer_module
        if peer_module.available() is not None:
            peer_module = None
    except ImportError:
        peer_module = None

    print(f"warm fixed cost of simulate(build(N), t_end=1e-9, n_out={args.n_out}), ms (median of {args.repeats})")
    print(f"{'N':>6} {'total':>9} {'system':>8} {'init':>8} {'post':>8} {'rest':>8}  {'n_out=501':>9}  structure cache")
    for N in args.sizes:
        total, parts, hit = fixed_cost(mod, N, args.repeats, args.phases, args.n_out)
        full = fixed_cost(mod, N, args.repeats, False, 501)[0]
        cols = [parts.get(k, np.nan) for k in ("system_of", "initialize_in_modes", "postprocess")]
        rest = total - sum(cols) if args.phases else np.nan
        print(f"{N:>6} {1e3 * total:>9.2f} " + " ".join(f"{1e3 * c:>8.2f}" for c in cols + [rest])
              + f"  {1e3 * full:>9.2f}  {hit}")
    if not args.calls:
        return
    print()
    print("one right-hand-side call, us (best of 5 batches); ratios to pinocchio's aba from Python")
    print("  fun: LagrangeIndex1.fun as scipy calls it; thin: its C call alone; ctypes: mbcomp_fun through ctypes;")
    print("  C: mbcomp_fun in a C loop (the function alone); fun-C: what Python adds; aba/rhs: pinocchio from Python")
    print(f"{'N':>4} {'fun':>7} {'thin':>7} {'ctypes':>7} {'C':>7} {'fun-C':>7} {'aba':>7} {'rhs':>7} {'fun/aba':>8} "
          f"{'fun/rhs':>8} {'|fun-rhs|':>10}")
    for N in args.calls:
        r = one_call(mod, N, peer_module)
        aba, rhs = r.get("aba", np.nan), r.get("rhs", np.nan)
        print(f"{N:>4} {1e6 * r['fun']:>7.2f} {1e6 * r['thin']:>7.2f} {1e6 * r['c']:>7.2f} {1e6 * r['c_alone']:>7.2f} "
              f"{1e6 * (r['fun'] - r['c_alone']):>7.2f} {1e6 * aba:>7.2f} {1e6 * rhs:>7.2f} {r['fun'] / aba:>8.2f} "
              f"{r['fun'] / rhs:>8.2f} {r.get('agree', np.nan):>10.2g}")


if __name__ == "__main__":
    main()
