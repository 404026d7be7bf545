"""Radau5's Jacobian and LU reuse (Hairer's THET rule): work and accuracy, before/after.

For each mechanism and DAE index, runs ``method="radau5"`` and prints accepted steps,
Jacobians (``njev``), LU factorizations (``nlu``, real and complex each count), ``fun``
evaluations (``nfev``, the formulation's count: finite-difference Jacobians included), CPU
and wall time of the whole ``simulate`` call, and the largest coordinate error on the output
grid against a tight reference (DOP853, Lagrange index 1 with projection, ``rtol=1e-12``).

``--before PATH`` adds rows for another ``radau.py`` (e.g. the previous commit's, written
with ``git show HEAD~1:src/mbcomp/solvers/radau.py > /tmp/radau_before.py``), loaded as a
module beside the current one and put in ``mbcomp.solvers.STEPPERS["radau5"]`` for its runs.
``--thet 1e-3,1e-2,0.1`` sweeps the reuse threshold of the current ``radau.py``
(``THETA_JAC``; default: the module's own value).

Run: ``python bench/radau_reuse.py [--before /tmp/radau_before.py] [--thet 1e-3,0.1] [--quick]``
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import pathlib
import time

# one BLAS thread: the matrices are small, and process_time() adds up the CPU time of every
# thread, so idle BLAS threads spinning would be counted as work
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

import mbcomp  # noqa: E402
import mbcomp.solvers as solvers  # noqa: E402
import mbcomp.solvers.radau as radau  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]

#: (label, model file, build parameters, simulate options)
CASES = [
    ("4-link chain i1", "models/n_link_pendulum.py", dict(N=4), dict(t_end=3.0, index=1)),
    ("4-link chain i3", "models/n_link_pendulum.py", dict(N=4), dict(t_end=3.0, index=3)),
    ("four-bar gap=1e-3 i3", "models/four_bar.py", dict(gap=1e-3), dict(t_end=1.0, index=3)),
    ("four-bar gap=1e-3 i2", "models/four_bar.py", dict(gap=1e-3), dict(t_end=1.0, index=2)),
    ("slider-crank i3", "models/slider_crank.py", {}, dict(t_end=3.0, index=3)),
    ("slider-crank i1", "models/slider_crank.py", {}, dict(t_end=3.0, index=1)),
]
TOL = dict(rtol=1e-8, atol=1e-10)
N_OUT = 61
REFERENCE = dict(method="DOP853", formulation="lagrange", stabilization="projection", rtol=1e-12, atol=1e-14)


def load_stepper(path):
    """The ``Radau5`` class of another ``radau.py``, imported inside ``mbcomp.solvers``."""
    spec = importlib.util.spec_from_file_location("mbcomp.solvers._radau_other", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.Radau5


def run(model, opts, backend, stepper=None):
    """``mbcomp.simulate`` with ``stepper`` as ``radau5`` for this run."""
    saved = solvers.STEPPERS["radau5"]
    if stepper is not None:
        solvers.STEPPERS["radau5"] = stepper
    try:
        t0, w0 = time.process_time(), time.perf_counter()
        res = mbcomp.simulate(model, n_out=N_OUT, backend=backend, **opts)
        res.stats["bench_cpu"], res.stats["bench_wall"] = time.process_time() - t0, time.perf_counter() - w0
        return res
    finally:
        solvers.STEPPERS["radau5"] = saved


def coordinate_error(res, ref):
    names = ref.stats["coordinates"]
    if not res.success:
        return np.nan
    return max(float(np.max(np.abs(np.asarray(res[n]) - np.asarray(ref[n])))) for n in names)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", help="path of another radau.py to compare with")
    ap.add_argument("--thet", help="comma-separated THETA_JAC values for the current radau.py")
    ap.add_argument("--backend", default="python", help="evaluator backend (default: python)")
    ap.add_argument("--quick", action="store_true", help="only the 4-link chain and the four-bar, index 3")
    ap.add_argument("--cases", help="comma-separated substrings selecting cases")
    args = ap.parse_args(argv)
    thets = [float(x) for x in args.thet.split(",")] if args.thet else [radau.THETA_JAC]
    variants = ([("before", load_stepper(args.before), None)] if args.before else [])
    variants += [(f"THET={th:g}", None, th) for th in thets]
    cases = CASES[1:3] if args.quick else CASES
    if args.cases:
        cases = [c for c in cases if any(s.strip() in c[0] for s in args.cases.split(","))]
    head = f"{'model':22s} {'variant':12s} {'steps':>6s} {'rej':>4s} {'njev':>5s} {'nlu':>6s} {'nfev':>7s} " \
           f"{'cpu s':>7s} {'wall s':>7s} {'error':>9s}"
    print(head)
    print("-" * len(head))
    default = radau.THETA_JAC
    for label, path, params, sim in cases:
        module = mbcomp.load_model_file(ROOT / path)
        opts = dict(method="radau5", stabilization="none", **TOL, **sim)
        ref = mbcomp.simulate(module.build(**params), n_out=N_OUT, t_end=sim["t_end"], backend=args.backend,
                              **REFERENCE)
        for name, stepper, th in variants:
            radau.THETA_JAC = default if th is None else th
            try:
                res = run(module.build(**params), opts, args.backend, stepper)
            finally:
                radau.THETA_JAC = default
            st = res.stats
            status = "" if res.success else "  FAILED: " + str(res.message)[:60]
            print(f"{label:22s} {name:12s} {st['steps']:6d} {st.get('nreject', 0):4d} {st['njev']:5d} "
                  f"{st['nlu_integrator']:6d} {st['nfev']:7d} {st['bench_cpu']:7.2f} {st['bench_wall']:7.2f} "
                  f"{coordinate_error(res, ref):9.2e}{status}", flush=True)


if __name__ == "__main__":
    main()
