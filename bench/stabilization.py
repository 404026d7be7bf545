"""Slider-crank over 10 s: constraint drift and energy error for each stabilization.

Prints a table (and writes bench/stabilization.csv and bench/stabilization.png): for each
stabilization and tolerance, the maximum position and velocity residual, the maximum
energy error |E - E0| relative to the kinetic-energy scale, steps, f-evals and CPU time,
with CPU time also as a ratio to the unstabilized run at the same tolerance (same run,
same machine).

Run: python bench/stabilization.py [--t-end 10] [--method RK45]
"""
import argparse
import csv
import pathlib

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent

import mbcomp  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=10.0)
    ap.add_argument("--method", default="RK45")
    ap.add_argument("--rtols", default="1e-6,1e-8")
    args = ap.parse_args(argv)
    sc = mbcomp.load_model_file(ROOT / "models/slider_crank.py")
    rows = []
    results = {}
    for rtol in [float(x) for x in args.rtols.split(",")]:
        base_cpu = None
        for stab in ("none", "baumgarte", "projection"):
            r = mbcomp.simulate(sc.build(), t_end=args.t_end, rtol=rtol, atol=rtol * 1e-2, method=args.method,
                                stabilization=stab, n_out=1001)
            E = r["energy.total"]
            scale = np.abs(r["energy.kinetic"]).max()
            row = dict(stabilization=stab, rtol=rtol, status=r.status,
                       drift_pos=float(np.max(r["residual.position"])),
                       drift_vel=float(np.max(r["residual.velocity"])),
                       energy_err=float(np.max(np.abs(E - E[0])) / scale),
                       steps=r.stats["steps"], nfev=r.stats["nfev"], cpu=r.stats["cpu_time"])
            base_cpu = base_cpu or row["cpu"]
            row["cpu_ratio"] = row["cpu"] / base_cpu
            rows.append(row)
            results[(stab, rtol)] = r
    hdr = f"{'stabilization':<12} {'rtol':>7} {'max|Phi| [m]':>13} {'max|dPhi|':>10} {'max|dE|/T':>10} {'steps':>6} {'nfev':>6} {'cpu [s]':>8} {'cpu/none':>8}"
    print(f"slider-crank, {args.t_end:g} s, {args.method}, atol = rtol/100")
    print(hdr)
    print("-" * len(hdr))
    for r in rows:
        print(f"{r['stabilization']:<12} {r['rtol']:>7.0e} {r['drift_pos']:>13.3e} {r['drift_vel']:>10.3e} "
              f"{r['energy_err']:>10.3e} {r['steps']:>6d} {r['nfev']:>6d} {r['cpu']:>8.2f} {r['cpu_ratio']:>8.2f}")
    with open(HERE / "stabilization.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for (stab, rtol), r in results.items():
        ls = "-" if rtol == max(k[1] for k in results) else "--"
        ax[0].semilogy(r.time, np.maximum(r["residual.position"], 1e-17), ls, label=f"{stab}, rtol {rtol:g}")
        E = r["energy.total"]
        ax[1].semilogy(r.time, np.maximum(np.abs(E - E[0]), 1e-17), ls, label=f"{stab}, rtol {rtol:g}")
    ax[0].set_title("position constraint residual |Phi| [m]")
    ax[1].set_title("energy error |E - E0| [J]")
    for a in ax:
        a.set_xlabel("time [s]")
        a.grid(True, alpha=0.3)
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(HERE / "stabilization.png", dpi=110)
    print(f"wrote {HERE / 'stabilization.csv'} and {HERE / 'stabilization.png'}")


if __name__ == "__main__":
    main()
