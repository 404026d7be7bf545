"""radau5 against scipy's Radau, work-precision: CPU time at matched accuracy (issue 32, item 4).

Each model (the damped stiff spring chain of ``models/spring_chain.py``, N=10, c=1e6 N/m,
d=1e5 N s/m; the 4-link chain and the slider-crank of ``bench/radau_reuse.py``) runs through
``mbcomp.simulate`` over a ladder of tolerances: scipy's ``Radau`` on the Lagrange index-1 ODE,
``radau5`` as a user calls it (no index: the same index-1 ODE, ``Radau5.ode_by_default``), and
``r5-dae`` (``radau5`` with ``index=1``: the index-1 DAE ``[q, u, a, lam]``), all with the
problem's Jacobian. The error is the largest coordinate error on the output grid against a
tight reference (DOP853, Lagrange index 1 with projection, ``rtol=1e-12``; for the stiff spring
chain scipy's Radau at ``rtol=1e-11``); the time is the CPU time of the whole ``simulate`` call
(median of ``--repeat`` runs). Each radau5 row prints the ratio of its time to scipy Radau's
time at the same error, interpolated log-log on scipy's work-precision line (``< 1``: radau5
is faster; ``nan``: the error lies outside scipy's line).

Measured 2026-11-28, after radau5's stepping loop moved into C (``solvers/compiled_radau.py``,
runtime ``mbrt_radau5``: the ODE default runs in C stretches over the compiled program and its
exact Jacobian program; ``r5-dae`` is still the Python stepper). Two runs on the shared 2-core
machine, medians of 3 each; radau5 / scipy Radau at radau5's error (``nan``: radau5's error lies
outside scipy's line -- at rtol 1e-4/1e-5 on the spring chain and 1e-5/1e-6 on the slider-crank):

=================  ==================  =====================  ==========================
model              rtol                ``r5-dae`` (index=1)   ``radau5`` (the default)
=================  ==================  =====================  ==========================
spring chain N=10  1e-5 / 1e-6 / 1e-7  2.79-2.35 / 2.33-1.90  0.46-0.44 / 0.23-0.23
                                       / 2.05-2.23            (1e-6 / 1e-7)
4-link chain       1e-6 / 1e-7 / 1e-8  0.57-0.70 / 0.76-0.75  0.06 / 0.06-0.07 / 0.05-0.06
                                       / 0.85
slider-crank       1e-6 / 1e-7 / 1e-8  0.45 / 0.51-0.53 /     0.03-0.04 / 0.02 (1e-7 / 1e-8)
                                       0.54-0.57
=================  ==================  =====================  ==========================

(with the Python stepper, before: radau5 0.42-0.44, 0.42-0.48 and 0.48-0.67 on the three.) The
C stepper takes the Python stepper's steps to round-off in the reuse decisions (the same count
on the N = 2 chain, within 5 % here) at the same errors. On the N = 10 spring chain (40
variables) a step still costs ~76 us in C (116 us in Python): the 336 pairs of 40 x 40
factorizations (~42 us a pair in the runtime's LU, 62 us by LAPACK from Python) are most of it, with 184 exact
Jacobians (~7 us each) and ~4,200 right-hand sides (~1 us); at N = 2 a step is ~2 us and the
~4 ms around the stepper in ``simulate`` is the run's cost. ``--before`` runs another radau.py's
ODE default in Python (its ``from .radau_linalg import`` takes the current module).

On the spring chain the DAE form is the gap: 60 variables with the accelerations algebraic take
931 steps at rtol 1e-5 with 210 Newton failures ("too slow", rates 0.4-0.7) and a factorization
per attempt; the ODE, 40 variables, 256 steps. Hence the default.

Run: ``python bench/radau_vs_scipy.py [--before /tmp/radau_before.py] [--repeat 3] [--cases chain]``
"""
from __future__ import annotations

import argparse
import os
import pathlib
import sys

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

import mbcomp  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))

from radau_reuse import REFERENCE, coordinate_error, load_stepper, run  # noqa: E402



def _model_file(path, **params):
    return lambda: mbcomp.load_model_file(ROOT / path).build(**params)


#: (label, builder, t_end (s), radau5 rtols, scipy Radau rtols)
CASES = [
    ("spring chain N=10", _model_file("models/spring_chain.py", N=10, c=1e6, d=1e5), 1.0, (1e-4, 1e-5, 1e-6, 1e-7), (1e-6, 1e-7, 1e-8, 1e-9)),
    ("4-link chain", _model_file("models/n_link_pendulum.py", N=4), 3.0, (1e-5, 1e-6, 1e-7, 1e-8),
     (1e-6, 1e-7, 1e-8, 1e-9, 1e-10)),
    ("slider-crank", _model_file("models/slider_crank.py"), 3.0, (1e-5, 1e-6, 1e-7, 1e-8),
     (1e-6, 1e-7, 1e-8, 1e-9, 1e-10)),
]
N_OUT = 61


def timed(build, t_end, opts, repeat, stepper=None):
    """(result, median CPU s) of ``repeat`` runs of ``opts`` (``stepper``: another radau5 class)."""
    times, res = [], None
    for _ in range(repeat):
        res = run(build(), dict(t_end=t_end, **opts), "auto", stepper)
        times.append(res.stats["bench_cpu"])
    return res, float(np.median(times))


def matched(err, line):
    """scipy's CPU time at error ``err``, log-log interpolated on its (error, time) points."""
    pts = sorted((e, c) for e, c in line if np.isfinite(e) and e > 0)
    if len(pts) < 2 or not pts[0][0] <= err <= pts[-1][0]:
        return np.nan
    le = np.log([p[0] for p in pts])
    lc = np.log([p[1] for p in pts])
    return float(np.exp(np.interp(np.log(err), le, lc)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", help="path of another radau.py to compare with")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cases", help="comma-separated substrings selecting cases")
    args = ap.parse_args(argv)
    cases = CASES
    if args.cases:
        cases = [c for c in cases if any(s.strip() in c[0] for s in args.cases.split(","))]
    variants = [("r5-dae", "dae"), ("radau5", "ode")]
    variants += [("before", load_stepper(args.before))] if args.before else []
    head = f"{'model':18s} {'method':8s} {'rtol':>7s} {'steps':>6s} {'nlu':>6s} {'nfev':>7s} {'cpu s':>7s} " \
           f"{'error':>9s} {'/scipy@err':>10s}"
    print(head)
    print("-" * len(head))
    for label, build, t_end, r_rtols, s_rtols in cases:
        # the stiff chain's reference: scipy Radau at rtol 1e-11 (DOP853 would take ~1e6 steps)
        refopts = dict(method="Radau", rtol=1e-11, atol=1e-13) if "spring" in label else REFERENCE
        ref = mbcomp.simulate(build(), n_out=N_OUT, t_end=t_end, backend="auto", **refopts)
        line, rows = [], []
        for rtol in s_rtols:
            res, cpu = timed(build, t_end, dict(method="Radau", rtol=rtol, atol=rtol * 1e-2), args.repeat)
            err = coordinate_error(res, ref)
            line.append((err, cpu))
            rows.append(("Radau", rtol, res, cpu, err, np.nan))
        for name, stepper in variants:
            for rtol in r_rtols:
                if stepper == "ode":  # the default: the index-1 ODE (Radau5.ode_by_default)
                    opts = dict(method="radau5", rtol=rtol, atol=rtol * 1e-2)
                elif stepper == "dae":
                    opts = dict(method="radau5", index=1, stabilization="none", rtol=rtol, atol=rtol * 1e-2)
                else:  # another radau.py (--before), as a user calls it: the ODE default (its on_ode())
                    opts = dict(method="radau5", rtol=rtol, atol=rtol * 1e-2)
                res, cpu = timed(build, t_end, opts, args.repeat, None if isinstance(stepper, str) else stepper)
                err = coordinate_error(res, ref)
                rows.append((name, rtol, res, cpu, err, cpu / matched(err, line)))
        for name, rtol, res, cpu, err, ratio in rows:
            st = res.stats
            print(f"{label:18s} {name:8s} {rtol:7.0e} {st['steps']:6d} {st.get('nlu_integrator', st.get('nlu', 0)):6d} "
                  f"{st['nfev']:7d} {cpu:7.3f} {err:9.2e} {ratio:10.2f}", flush=True)


if __name__ == "__main__":
    main()
