"""Work-precision charts: every formulation x solver, against a reference, in one run.

Models: Andrews' squeezing mechanism (against the published reference at t = 0.03 s), the
slider-crank (t = 1 s) and the 10-link planar pendulum (t = 1 s), the last two against a
tight-tolerance run of a different method (see ``mbcomp.workprecision``). Peers: sympy's
KanesMethod + lambdify + scipy (Radau and DOP853) for Andrews (``bench/peers/sympy_andrews.py``)
and for the pendulum (``bench/peers/sympy_pendulum.py``); the slider-crank has none here.

For each model it writes ``bench/work_precision_<model>.csv`` and ``.png`` (error vs CPU time
and vs function evaluations) and prints, for each combination, the fastest CPU time reaching
a relative position error of 1e-6 and its ratio to the fastest sympy + scipy run.

CPU time: ``time.process_time`` around ``mbcomp.simulate`` (assembly and initialization
included, a few ms); for the peers around ``solve_ivp`` only -- their one-off derivation and
lambdify time is printed separately.

Run: python bench/work_precision.py [--models andrews,slider_crank,pendulum10] [--quick]
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small matrices; see bench/scaling.py
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import math  # noqa: E402
import pathlib  # noqa: E402
import sys  # noqa: E402

import numpy as np  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))  # bench/peers

import mbcomp  # noqa: E402
from mbcomp import workprecision as wp  # noqa: E402

TARGET = 1e-6


def andrews_peer(tols, ref_names, ref, log):
    from peers import sympy_andrews as sa

    d = sa.derive()
    log(f"  sympy Andrews: derivation {d.t_derive:.2f} s + lambdify {d.t_lambdify:.2f} s")
    rows = []
    for method in ("Radau", "DOP853"):
        for tol in tols:
            out = sa.simulate(d, rtol=tol, atol=tol * 1e-2, method=method, t_end=0.03)
            x = np.array([out["q"][n] for n in ref_names])
            err = wp._error(x, ref) if out["status"] in (0, "success") or np.all(np.isfinite(x)) else math.nan
            rows.append(dict(combo=f"sympy Kane+lambdify / scipy {method}", family="peer", setting="rtol", value=tol,
                             status="success", cpu_s=out["cpu_s"], nfev=out["nfev"], steps=out.get("nsteps", 0),
                             error=err, message=""))
            log(f"  {rows[-1]['combo']:<36} rtol={tol:<9.2g} cpu {out['cpu_s']:8.3f} s  nfev {out['nfev']:>8}  "
                f"error {err:9.2e}")
    return rows, d.t_derive + d.t_lambdify


def pendulum_peer(N, t_end, tols, ref, log):
    from peers import sympy_pendulum as spp

    d = spp.derive(N)
    log(f"  sympy pendulum N={N}: derivation {d.t_derive:.1f} s + lambdify {d.t_lambdify:.1f} s")
    rows = []
    for method in ("Radau", "DOP853"):
        for tol in tols:
            out = spp.simulate(d, 0.3, 0.0, t_end, tol, tol * 1e-2, method)
            err = wp._error(np.asarray(out["q"]), ref) if out["status"] == "success" else math.nan
            rows.append(dict(combo=f"sympy Kane+lambdify / scipy {method}", family="peer", setting="rtol", value=tol,
                             status=out["status"], cpu_s=out["cpu_s"], nfev=out["nfev"], steps=0, error=err,
                             message=str(out["message"])[:100]))
            log(f"  {rows[-1]['combo']:<36} rtol={tol:<9.2g} cpu {out['cpu_s']:8.3f} s  nfev {out['nfev']:>8}  "
                f"error {err:9.2e}")
            if out["cpu_s"] > 60:
                break
    return rows, d.t_derive + d.t_lambdify


def summarize(name, rows, setup_peer=None):
    print("\n" + wp.summary(rows, TARGET, title=name))
    if setup_peer is not None:
        print(f"(sympy's one-off derivation + lambdify: {setup_peer:.1f} s, not included above)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default="andrews,slider_crank,pendulum10")
    ap.add_argument("--quick", action="store_true", help="three tolerances only")
    ap.add_argument("--max-cpu", type=float, default=30.0)
    args = ap.parse_args(argv)
    tols = [1e-4, 1e-6, 1e-8] if args.quick else [10.0 ** -k for k in range(3, 11)]
    steps = [100, 1000] if args.quick else [30, 100, 300, 1000, 3000, 10000]
    for name in args.models.split(","):
        print(f"\n=== {name} ===", flush=True)
        setup = None
        if name == "andrews":
            mod = mbcomp.load_model_file(ROOT / "models/andrews.py")
            t_ref, values, how = wp.reference_values(mod)
            rows = wp.work_precision(mod, tols=tols, steps=steps, max_cpu=args.max_cpu,
                                     reference=(t_ref, values, how))
            names = list(values)
            peer, setup = andrews_peer(tols, names, np.array([values[n] for n in names]), print)
            rows += peer
        elif name == "slider_crank":
            mod = mbcomp.load_model_file(ROOT / "models/slider_crank.py")
            rows = wp.work_precision(mod, tols=tols, steps=steps, t_end=1.0, max_cpu=args.max_cpu)
        elif name.startswith("pendulum"):
            N = int(name[len("pendulum"):] or 10)
            mod = mbcomp.load_model_file(ROOT / "models/n_link_pendulum.py")
            ref = wp.reference_values(mod, build_kw=dict(N=N), t_end=1.0)
            rows = wp.work_precision(mod, tols=tols, steps=steps, build_kw=dict(N=N), t_end=1.0,
                                     max_cpu=args.max_cpu, reference=ref)
            peer, setup = pendulum_peer(N, 1.0, tols, np.array(list(ref[1].values())), print)
            rows += peer
        else:
            raise SystemExit(f"unknown model {name!r}")
        wp.write_csv(rows, HERE / f"work_precision_{name}.csv")
        wp.plot(rows, HERE / f"work_precision_{name}.png", title=name, target=TARGET)
        summarize(name, rows, setup)
        print(f"wrote bench/work_precision_{name}.csv and .png")


if __name__ == "__main__":
    main()
