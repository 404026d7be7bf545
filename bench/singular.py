"""Through redundant and singular configurations: Bricard's linkage and the N-four-bar.

For every formulation x solver, prints the accuracy against an independent reference, the
CPU time, and how the kept constraint rows, the D'Alembert partition and the singular
passages went:

* **Bricard** (models/bricard.py, 10 s from rest): reference = the same linkage with joint 6
  cylindrical (no redundant row, nothing to choose) at rtol 1e-11; error = max |joint angle
  difference| (rad); energy drift (J).
* **N-four-bar** (models/n_four_bar.py, N = 2 and 40, 20 s, ``singular="pass"``): reference
  = the exact one-degree-of-freedom reduction (every crank at one angle theta) by DOP853 at
  1e-13; error = max |theta - exact| (rad); passages recorded vs flat instants of the exact
  motion.

Run: python bench/singular.py [--Ns 2,40] [--skip-slow]   (writes bench/singular.csv)
"""
import argparse
import csv
import pathlib
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

import mbcomp

ROOT = pathlib.Path(__file__).resolve().parent.parent
bricard = mbcomp.load_model_file(ROOT / "models" / "bricard.py")
nfb = mbcomp.load_model_file(ROOT / "models" / "n_four_bar.py")
TOL = dict(rtol=1e-9, atol=1e-11)

BRICARD_RUNS = {
    "Lagrange Baumgarte / dop853 (C engine)": dict(method="dop853"),
    "Lagrange projection / dop853": dict(method="dop853", stabilization="projection"),
    "Lagrange Baumgarte / LSODA": dict(method="LSODA"),
    "D'Alembert / dop853": dict(method="dop853", formulation="dalembert"),
    "D'Alembert / LSODA": dict(method="LSODA", formulation="dalembert"),
    "radau5 index 1": dict(method="radau5", index=1),
    "radau5 index 2": dict(method="radau5", index=2),
    "radau5 index 3": dict(method="radau5", index=3),
    "IDA index 2": dict(method="ida", index=2),
    "gen-alpha h=1ms": dict(method="genalpha", h=1e-3),
}
FOUR_BAR_RUNS = {
    "D'Alembert / DOP853": dict(formulation="dalembert", method="DOP853"),
    "D'Alembert / dop853": dict(formulation="dalembert", method="dop853"),
    "Lagrange projection / dop853": dict(method="dop853"),
    "Lagrange projection / DOP853": dict(method="DOP853"),
    "gen-alpha h=2ms": dict(method="genalpha", h=2e-3),
}


def timed(model, **kw):
    c0 = time.process_time()
    r = mbcomp.simulate(model, **kw)
    return r, time.process_time() - c0


def bricard_table(rows):
    ref = mbcomp.simulate(bricard.build(cylindrical=6), t_end=10.0, rtol=1e-11, atol=1e-13, n_out=201)
    names = [n for n in ref.names if n.endswith(".phi")]
    print("\n### Bricard's linkage, 10 s from rest (reference: joint 6 cylindrical, rtol 1e-11)\n")
    print("| formulation / solver | status | max angle error (rad) | energy drift (J) | CPU s | kept rows chosen again |")
    print("|---|---|---:|---:|---:|---|")
    for name, kw in BRICARD_RUNS.items():
        r, cpu = timed(bricard.build(), t_end=10.0, n_out=201, **{**TOL, **kw})
        n = len(r.time)
        err = max(float(np.max(np.abs(r[v] - ref[v][:n]))) for v in names if v in r.names)
        E = r["energy.total"]
        drift = float(np.max(np.abs(E - E[0])))
        changes = "; ".join(f"t={c['t']:.3f} s: {', '.join(c['was'])} -> {', '.join(c['dropped'])} "
                            f"(sigma {c['sigma_before']:.2g} -> {c['sigma_after']:.2g})"
                            for c in r.stats.get("row_changes", []))
        print(f"| {name} | {r.status} | {err:.1e} | {drift:.1e} | {cpu:.2f} | {changes or 'none'} |")
        rows.append(dict(case="bricard", N="", who=name, status=r.status, error=err, drift=drift, cpu_s=cpu,
                         changes=len(r.stats.get("row_changes", [])), passages="", repartitions=r.stats.get("repartitions", "")))


def exact_four_bar(N, ts):
    J = (N + 1) / 3 + N
    k = 9.81 * ((N + 1) / 2 + N)
    sol = solve_ivp(lambda t, y: [y[1], -k * np.cos(y[0]) / J], (ts[0], ts[-1]), [np.pi / 2, 1.0], t_eval=ts,
                    events=lambda t, y: np.sin(y[0]), rtol=1e-13, atol=1e-13, method="DOP853")
    return sol.y[0], sol.t_events[0]


def four_bar_table(N, rows, skip_slow):
    ts = np.linspace(0.0, 20.0, 401)
    theta, flats = exact_four_bar(N, ts)
    print(f"\n### N-four-bar, N = {N}, 20 s, singular='pass' (reference: exact one-DOF reduction; "
          f"{len(flats)} flat instants)\n")
    print("| formulation / solver | status | max |theta - exact| (rad) | passages recorded | CPU s | D'Alembert repartitions |")
    print("|---|---|---:|---:|---:|---:|")
    for name, kw in FOUR_BAR_RUNS.items():
        if skip_slow and N > 10 and "gen-alpha" in name:
            print(f"| {name} | skipped (--skip-slow) | | | | |")
            continue
        r, cpu = timed(nfb.build(N=N), t_end=20.0, n_out=len(ts), singular="pass", **{**dict(rtol=1e-8, atol=1e-10),
                                                                                       **kw})
        n = len(r.time)
        err = float(np.max(np.abs(r["theta"] - theta[:n])))
        npass = len(r.stats.get("singular_passages", []))
        rep = r.stats.get("repartitions", "")
        print(f"| {name} | {r.status} | {err:.1e} | {npass} of {len(flats)} | {cpu:.1f} | {rep} |")
        rows.append(dict(case="n_four_bar", N=N, who=name, status=r.status, error=err, drift="", cpu_s=cpu,
                         changes=len(r.stats.get("row_changes", [])), passages=npass, repartitions=rep))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--Ns", default="2,40", help="N-four-bar sizes")
    ap.add_argument("--skip-slow", action="store_true", help="leave out gen-alpha at N > 10 (~200 s CPU at N = 40)")
    args = ap.parse_args(argv)
    rows = []
    bricard_table(rows)
    for N in (int(x) for x in args.Ns.split(",") if x):
        four_bar_table(N, rows, args.skip_slow)
    out = pathlib.Path(__file__).with_name("singular.csv")
    with open(out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"\nwrote {out}")


if __name__ == "__main__":
    sys.exit(main())
