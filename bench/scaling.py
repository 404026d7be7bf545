"""Scaling with model size: N-link planar pendulum and N-link 3-D chain, N = 2..100.

For each model and N, in one run on one machine:

* build time: ``mbcomp.assemble`` + consistent initialization (what every simulation pays);
* compile time of the generated program (``mbcomp.codegen``): trace + Python ``compile``, and
  trace + C compiler (a fresh cache directory, so the compiler really runs);
* one right-hand-side evaluation (``rhs(t, y)``, best of several batches) of the Lagrange
  index-1 formulation and of the D'Alembert formulation, each on the numeric system, the
  Python program and the C program;
* for the planar pendulum, sympy's ``KanesMethod`` in chained relative angles with
  ``lambdify(cse=True)`` of the mass matrix and forcing (``du/dt = solve(M, F)``), run in a
  subprocess and reported for the N whose derivation + lambdify finish within the timeout
  (60 s); its accelerations are checked against mbcomp's at the same state.

Prints a table and the ratios to sympy at N = 10, writes bench/scaling.csv and
bench/scaling.png (log-log time vs N).

Run: python bench/scaling.py [--quick] [--Ns 2,5,10,20,50,100] [--no-c] [--no-sympy]
"""
import os

# one BLAS thread: the matrices here are small, and a threaded BLAS on a shared 2-core
# machine made the same Cholesky 5x slower (oversubscription), swamping what is measured
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import csv
import json
import math
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))  # bench/peers

import mbcomp  # noqa: E402
from mbcomp import formulations  # noqa: E402
from mbcomp.codegen import CodegenError, c_compiler, compile_system  # noqa: E402
from mbcomp.initialization import initialize  # noqa: E402

L_LINK, M_LINK, G = 0.5, 1.0, 9.81
T0 = 0.1
MODELS = {"pendulum": "models/n_link_pendulum.py", "chain3d": "models/chain_3d.py"}
# D'Alembert formulation (issue 4, item 1): measured when mbcomp.formulations has it
DALEMBERT = getattr(formulations, "DAlembert", None)


# ------------------------------------------------------------------------------------------
# sympy KanesMethod worker (run in a subprocess: python bench/scaling.py --kane-worker N)
# ------------------------------------------------------------------------------------------
def kane_worker(N):
    from peers.sympy_pendulum import derive  # the sympy model of the work-precision peer

    d = derive(N, L_LINK, M_LINK, G)
    Mf, Ff, t_kane, t_lamb = d.mass, d.forcing, d.t_derive, d.t_lambdify
    qv, uv = _state(N)

    def rhs():
        return np.concatenate((uv, np.linalg.solve(Mf(qv, uv), np.asarray(Ff(qv, uv), float).ravel())))

    acc = rhs()[N:]
    print(json.dumps(dict(N=N, kane_s=t_kane, lambdify_s=t_lamb, rhs_us=1e6 * per_call(rhs), acc=acc.tolist())))


def _state(N):
    """The state at which every right-hand side is timed: relative angles 0.3, rates 0.1 k."""
    return np.full(N, 0.3), 0.1 * np.arange(1, N + 1) / N


def per_call(f, batch_time=0.02, repeats=5):
    """Seconds per call of ``f``: best over ``repeats`` batches of about ``batch_time`` s each."""
    f()
    n = 1
    while True:
        t0 = time.perf_counter()
        for _ in range(n):
            f()
        dt = time.perf_counter() - t0
        if dt >= batch_time or n >= 1 << 16:
            break
        n *= 2
    best = dt / n
    for _ in range(repeats - 1):
        t0 = time.perf_counter()
        for _ in range(n):
            f()
        best = min(best, (time.perf_counter() - t0) / n)
    return best


def run_kane(N, timeout):
    """(row dict or None, message) from a subprocess running :func:`kane_worker`."""
    cmd = [sys.executable, str(pathlib.Path(__file__).resolve()), "--kane-worker", str(N)]
    t0 = time.perf_counter()
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout + 30)
    except subprocess.TimeoutExpired:
        return None, f"sympy did not finish within {timeout:g} s"
    if out.returncode != 0:
        return None, f"sympy failed: {out.stderr.strip().splitlines()[-1] if out.stderr.strip() else out.returncode}"
    res = json.loads(out.stdout.strip().splitlines()[-1])
    if res["kane_s"] + res["lambdify_s"] > timeout:
        return None, f"sympy took {res['kane_s'] + res['lambdify_s']:.0f} s > {timeout:g} s"
    res["wall_s"] = time.perf_counter() - t0
    return res, ""


# ------------------------------------------------------------------------------------------
# mbcomp measurements
# ------------------------------------------------------------------------------------------
def build(model, N):
    mod = mbcomp.load_model_file(ROOT / MODELS[model])
    if model == "pendulum":
        q, u = _state(N)
        return mod.build(N=N, L=L_LINK, m=M_LINK, g=G, phi0=q, w0=u)
    return mod.build(N=N)


def measure_rhs(system, init):
    """Per-call seconds of the Lagrange and D'Alembert right-hand sides, and the accelerations."""
    y = np.concatenate((init.q, init.u))
    lag = formulations.LagrangeIndex1(system)
    out = dict(lagrange=per_call(lambda: lag.fun(T0, y)))
    acc = lag.fun(T0, y)[system.nq:]
    if DALEMBERT is not None:
        dal = DALEMBERT(system)
        yd = dal.initial_state(T0, init.q, init.u)
        out["dalembert"] = per_call(lambda: dal.fun(T0, yd))
    return out, acc


def measure(model, N, args, c_ok, predicted_nodes):
    row = dict(model=model, N=N)
    reps = 3 if N <= 20 else 1
    tb = math.inf
    for _ in range(reps):
        t0 = time.perf_counter()
        system = mbcomp.assemble(build(model, N))
        init = initialize(system, T0)
        tb = min(tb, time.perf_counter() - t0)
    row.update(nq=system.nq, nu=system.nu, build_s=tb)
    rhs, acc = measure_rhs(system, init)
    row.update(rhs_numeric_us=1e6 * rhs["lagrange"], dal_numeric_us=1e6 * rhs.get("dalembert", math.nan))
    row["_acc"] = acc
    notes = []
    n_ops = None
    if predicted_nodes == math.inf:
        notes.append("codegen skipped (a smaller N already exceeded --max-nodes)")
    elif predicted_nodes is not None and predicted_nodes > args.max_nodes:
        notes.append(f"codegen skipped (about {predicted_nodes / 1e6:.1f}M nodes predicted > --max-nodes)")
    else:
        try:
            t0 = time.perf_counter()
            cs = compile_system(system, "python", max_nodes=args.max_nodes, verify=False)
            row["compile_py_s"] = time.perf_counter() - t0
            st = cs.stats
            n_ops = st["n_ops"]
            row.update(n_ops=n_ops, n_nodes=st["n_nodes"], n_ops_params=st["n_ops_params"], trace_s=st["trace_time"])
            rhs_py, acc_py = measure_rhs(cs, init)
            row.update(rhs_py_us=1e6 * rhs_py["lagrange"], dal_py_us=1e6 * rhs_py.get("dalembert", math.nan))
            row["err_py"] = float(np.max(np.abs(acc_py - acc)) / (1 + np.max(np.abs(acc))))
            del cs
        except CodegenError as exc:
            notes.append(f"codegen: {str(exc)[:80]}")
    if c_ok and n_ops is not None:
        if n_ops > args.c_max_ops:
            notes.append(f"C skipped ({n_ops} ops > --c-max-ops)")
        else:
            with tempfile.TemporaryDirectory() as cache:
                t0 = time.perf_counter()
                cc = compile_system(system, "c", cache_dir=cache, max_nodes=args.max_nodes, verify=False)
                row["compile_c_s"] = time.perf_counter() - t0
                rhs_c, acc_c = measure_rhs(cc, init)
                row.update(rhs_c_us=1e6 * rhs_c["lagrange"], dal_c_us=1e6 * rhs_c.get("dalembert", math.nan))
                row["err_c"] = float(np.max(np.abs(acc_c - acc)) / (1 + np.max(np.abs(acc))))
                del cc
    row["notes"] = "; ".join(notes)
    return row


COLUMNS = ["model", "N", "nq", "nu", "build_s", "trace_s", "compile_py_s", "compile_c_s", "n_ops", "n_ops_params",
           "n_nodes", "rhs_numeric_us", "rhs_py_us", "rhs_c_us", "dal_numeric_us", "dal_py_us", "dal_c_us",
           "err_py", "err_c", "kane_s", "lambdify_s", "rhs_sympy_us", "err_sympy", "notes"]


def _f(x, fmt):
    width = int(fmt.rstrip("dfe").split(".")[0])
    return f"{'-':>{width}}" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, fmt)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N = 2, 5, 10 only")
    ap.add_argument("--Ns", default=None, help="comma-separated sizes (default 2,5,10,20,50,100)")
    ap.add_argument("--models", default="pendulum,chain3d")
    ap.add_argument("--no-c", action="store_true", help="skip the C backend")
    ap.add_argument("--no-sympy", action="store_true", help="skip sympy's KanesMethod")
    ap.add_argument("--sympy-timeout", type=float, default=60.0, help="s for KanesMethod + lambdify")
    ap.add_argument("--max-nodes", type=int, default=3_000_000, help="largest expression graph to generate")
    ap.add_argument("--c-max-ops", type=int, default=300_000, help="largest program to hand to the C compiler")
    ap.add_argument("--kane-worker", type=int, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.kane_worker is not None:
        kane_worker(args.kane_worker)
        return
    Ns = [int(x) for x in args.Ns.split(",")] if args.Ns else ([2, 5, 10] if args.quick else [2, 5, 10, 20, 50, 100])
    c_ok = (not args.no_c) and c_compiler() is not None
    if DALEMBERT is None:
        print("note: mbcomp.formulations.DAlembert not found; D'Alembert columns left empty (hook in measure_rhs)")
    rows = []
    for model in args.models.split(","):
        prev = None
        sympy_alive = model == "pendulum" and not args.no_sympy
        for N in Ns:
            pred = None
            if prev is not None and prev.get("n_nodes"):
                pred = prev["n_nodes"] * (N / prev["N"]) ** 3  # the mass matrix assembly is O(N^3)
            elif prev is not None and "codegen skipped" in prev["notes"]:
                pred = math.inf
            print(f"{model} N={N} ...", flush=True)
            row = measure(model, N, args, c_ok, pred)
            if sympy_alive:
                res, msg = run_kane(N, args.sympy_timeout)
                if res is None:
                    row["notes"] = "; ".join(x for x in (row["notes"], msg) if x)
                    sympy_alive = False  # larger N take longer still
                else:
                    row.update(kane_s=res["kane_s"], lambdify_s=res["lambdify_s"], rhs_sympy_us=res["rhs_us"])
                    acc = row["_acc"]
                    row["err_sympy"] = float(np.max(np.abs(np.array(res["acc"]) - acc)) / (1 + np.max(np.abs(acc))))
            rows.append(row)
            prev = row
    report(rows, c_ok)


def report(rows, c_ok):
    print()
    print("times: build = assemble + initialize [s]; py/C = generate + compile [s]; rhs in microseconds per call")
    hdr = (f"{'model':<9}{'N':>4}{'nu':>5}{'build':>8}{'py':>7}{'C':>7}{'ops':>9}"
           f"{'numeric':>10}{'py':>9}{'C':>8}{'dal.num':>10}{'dal.py':>9}{'dal.C':>8}"
           f"{'kane+lamb':>11}{'sympy':>8}  notes")
    print(hdr)
    print("-" * len(hdr))
    for r in rows:
        kl = (r["kane_s"] + r["lambdify_s"]) if r.get("kane_s") is not None else None
        print(f"{r['model']:<9}{r['N']:>4}{r['nu']:>5}{_f(r['build_s'], '8.3f')}{_f(r.get('compile_py_s'), '7.2f')}"
              f"{_f(r.get('compile_c_s'), '7.2f')}{_f(r.get('n_ops'), '9d')}"
              f"{_f(r['rhs_numeric_us'], '10.0f')}{_f(r.get('rhs_py_us'), '9.0f')}{_f(r.get('rhs_c_us'), '8.0f')}"
              f"{_f(r['dal_numeric_us'], '10.0f')}{_f(r.get('dal_py_us'), '9.0f')}{_f(r.get('dal_c_us'), '8.0f')}"
              f"{_f(kl, '11.1f')}{_f(r.get('rhs_sympy_us'), '8.0f')}  {r['notes']}")
    errs = [(r["model"], r["N"], k, r[k]) for r in rows for k in ("err_py", "err_c", "err_sympy") if r.get(k) is not None]
    worst = max(errs, key=lambda e: e[3]) if errs else None
    if worst:
        print(f"\naccelerations agree with the numeric path: worst relative difference {worst[3]:.1e} "
              f"({worst[2][4:]} vs numeric, {worst[0]} N={worst[1]})")
    # ratios vs sympy at N = 10
    r10 = next((r for r in rows if r["model"] == "pendulum" and r["N"] == 10), None)
    if r10 is not None and r10.get("rhs_sympy_us"):
        s = r10["rhs_sympy_us"]
        print(f"\nplanar pendulum N=10, one RHS evaluation relative to sympy KanesMethod + lambdify(cse) "
              f"({s:.0f} us; derivation {r10['kane_s']:.1f} s + lambdify {r10['lambdify_s']:.1f} s):")
        for key, label in (("rhs_numeric_us", "numeric, Lagrange"), ("rhs_py_us", "Python program, Lagrange"),
                           ("rhs_c_us", "C program, Lagrange"), ("dal_numeric_us", "numeric, D'Alembert"),
                           ("dal_py_us", "Python program, D'Alembert"), ("dal_c_us", "C program, D'Alembert")):
            v = r10.get(key)
            if v is not None and not math.isnan(v):
                print(f"  {label:<28} {v:8.0f} us   ratio {v / s:5.2f}  ({'faster' if v < s else 'slower'})")
        tot = (r10.get("compile_py_s") or 0) + r10["build_s"]
        print(f"  set-up: mbcomp build {r10['build_s']:.3f} s + Python program {r10.get('compile_py_s', 0):.2f} s "
              f"= {tot:.2f} s vs sympy {r10['kane_s'] + r10['lambdify_s']:.1f} s")
    # build-time growth
    for model in sorted({r["model"] for r in rows}):
        rr = [r for r in rows if r["model"] == model and r["N"] >= 10]
        if len(rr) >= 2:
            x, y = np.log([r["N"] for r in rr]), np.log([r["build_s"] for r in rr])
            k = np.polyfit(x, y, 1)[0]
            b = {r["N"]: r["build_s"] for r in rows if r["model"] == model}
            extra = "; ".join(f"N={n}: {b[n]:.2f} s" for n in (20, 100) if n in b)
            print(f"build time {model}: ~ N^{k:.2f} for N >= 10 ({extra})")
    with open(HERE / "scaling.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in COLUMNS})
    plot(rows)
    print(f"\nwrote {HERE / 'scaling.csv'} and {HERE / 'scaling.png'}")


def plot(rows):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.8))
    style = {"pendulum": "-", "chain3d": "--"}
    for model in ("pendulum", "chain3d"):
        rr = [r for r in rows if r["model"] == model]
        if not rr:
            continue
        ls = style[model]

        def series(key, scale=1.0):
            pts = [(r["N"], r[key] * scale) for r in rr if r.get(key) is not None and not math.isnan(r[key])]
            return ([p[0] for p in pts], [p[1] for p in pts]) if pts else ([], [])

        for key, label, c in (("build_s", "build (assemble + init)", "C0"), ("compile_py_s", "Python program", "C1"),
                              ("compile_c_s", "C program", "C2")):
            x, y = series(key)
            if x:
                a1.loglog(x, y, ls, marker="o", color=c, label=f"{model}: {label}")
        for key, label, c in (("rhs_numeric_us", "numeric", "C0"), ("rhs_py_us", "Python program", "C1"),
                              ("rhs_c_us", "C program", "C2"), ("dal_numeric_us", "numeric, D'Alembert", "C4"),
                              ("dal_c_us", "C program, D'Alembert", "C5")):
            x, y = series(key, 1e-6)
            if x:
                a2.loglog(x, y, ls, marker="o", color=c, label=f"{model}: {label}")
        if model == "pendulum":
            pts = [(r["N"], r["kane_s"] + r["lambdify_s"]) for r in rr if r.get("kane_s") is not None]
            if pts:
                a1.loglog(*zip(*pts), ":", marker="s", color="C3", label="pendulum: sympy Kane + lambdify")
            x, y = series("rhs_sympy_us", 1e-6)
            if x:
                a2.loglog(x, y, ":", marker="s", color="C3", label="pendulum: sympy lambdify")
    a1.set(xlabel="N (links)", ylabel="time [s]", title="model build / program generation")
    a2.set(xlabel="N (links)", ylabel="time per call [s]", title="one right-hand-side evaluation")
    for a in (a1, a2):
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(HERE / "scaling.png", dpi=110)


if __name__ == "__main__":
    main()
