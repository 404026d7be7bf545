"""Stability analysis against sympy.physics.mechanics: time to the stability boundary, and its accuracy.

Two nonholonomic problems with known boundaries, each analysed by mbcomp and by a sympy peer
written the way a sympy/PyDy user writes it (``KanesMethod`` with the no-slip constraints,
``KanesMethod.linearize`` about the steady motion, ``lambdify`` of the state matrix):

* **rolling disk** (``models/rolling_disk.py``; peer ``bench/peers/sympy_rolling_disk.py``):
  upright rolling of a thin disk is stable exactly for spin ``W > sqrt(g / (3 r))``;
* **Whipple bicycle** (``models/bicycle.py``; peer ``bench/peers/sympy_bicycle.py``): the
  self-stable speed range of the Meijaard et al. (2007) benchmark, weave 4.292382445956 m/s
  and capsize 6.024262015827 m/s as printed; the printed matrices' own weave root is at
  4.2923825363 m/s (their real part at the printed speed is +1.2e-7 1/s), so the error of the
  weave speed is measured against that root.

Measured, in one run on one machine (wall-clock, ``time.perf_counter``):

* mbcomp: ``first`` = build + linearize at one parameter value (everything a first answer
  costs; mbcomp has no derivation step), ``per point`` = mean cost of one further
  linearization in a 101-point grid, ``boundary`` = :func:`mbcomp.sweep` on an 11-point grid
  with the changes located by root finding;
* sympy: ``derive`` (model + ``kanes_equations``), ``linearize`` (symbolic, op point
  substituted), ``lambdify``, ``per point`` (evaluate ``A`` + ``eigvals``), ``boundary`` =
  derivation + linearization + lambdify + Brent's method on the lambdified matrix.

Prints a table with the ratios sympy/mbcomp, writes ``bench/stability.csv`` and
``bench/stability.png`` (left: time to the boundary, log scale; right: the bicycle's real parts
against speed from both tools on one axis).

Run: python bench/stability.py [--no-sympy] [--only disk|bicycle] [--derivatives exact|differences]
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small matrices; threads only cost on a shared machine

import argparse  # noqa: E402
import csv  # noqa: E402
import pathlib  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy.optimize import brentq  # noqa: E402

import mbcomp  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

G, R_DISK = 9.81, 0.3
DISK_CRIT = np.sqrt(G / (3 * R_DISK))
WEAVE_PRINTED, CAPSIZE_PRINTED = 4.292382445956, 6.024262015827  # m/s, Meijaard et al. (2007)
PRINTED = dict(  # the paper's printed coefficient matrices, q = [roll, steer]
    M=np.array([[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]]),
    C1=np.array([[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]]),
    K0=np.array([[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]]),
    K2=np.array([[0.0, 76.59734589573222], [0.0, 2.65431523794604]]),
)


def printed_A(v):
    """State matrix of ``M q'' + v C1 q' + (g K0 + v^2 K2) q = 0`` in (roll, steer, rates)."""
    Minv = np.linalg.inv(PRINTED["M"])
    return np.block([[np.zeros((2, 2)), np.eye(2)],
                     [-Minv @ (G * PRINTED["K0"] + v * v * PRINTED["K2"]), -v * Minv @ PRINTED["C1"]]])


def max_real(A):
    return float(np.linalg.eigvals(A).real.max())


def reference_speeds():
    """Weave and capsize roots of the printed matrices (the reference for both tools)."""
    f = lambda v: max_real(printed_A(v))  # noqa: E731
    return brentq(f, 4.0, 5.0, xtol=1e-14, rtol=1e-15), brentq(f, 5.5, 6.5, xtol=1e-14, rtol=1e-15)


def timed(fn, *args, **kw):
    t0 = time.perf_counter()
    out = fn(*args, **kw)
    return out, time.perf_counter() - t0


# ------------------------------------------------------------------------------------------
# mbcomp
# ------------------------------------------------------------------------------------------
def mbcomp_case(name, derivatives="auto"):
    """``dict`` of timings, boundary values and a 101-point root locus for one problem
    (``derivatives``: as for :func:`mbcomp.linearize`)."""
    if name == "disk":
        mod, par, grid, probe = mbcomp.load_model_file(ROOT / "models/rolling_disk.py"), "spin", (1.0, 5.0), 6.0
        build = lambda x: mod.build(spin=x)  # noqa: E731
    else:
        mod, par, grid, probe = mbcomp.load_model_file(ROOT / "models/bicycle.py"), "v", (0.0, 10.0), 5.0
        build = lambda x: mod.build(v=x)  # noqa: E731
    lin = lambda model: mbcomp.linearize(model, derivatives=derivatives)  # noqa: E731
    first_lin, t_first = timed(lambda: lin(build(probe)))
    values = np.linspace(*grid, 101)
    locus, t_locus = timed(lambda: [lin(build(x)).eigenvalues for x in values])
    sw, t_sweep = timed(mbcomp.sweep, build, par, np.linspace(*grid, 11), analyze=lin)
    return dict(tool="mbcomp", first=t_first, per_point=t_locus / len(values), boundary=t_sweep,
                changes=[c["value"] for c in sw.changes], values=values,
                max_real=np.array([e.real.max() for e in locus]), eig_probe=first_lin.eigenvalues)


# ------------------------------------------------------------------------------------------
# sympy peers
# ------------------------------------------------------------------------------------------
def sympy_case(name):
    if name == "disk":
        from peers import sympy_rolling_disk as peer

        d, t_all = timed(peer.derive)
        changes, t_root = timed(peer.critical_spin, d)
        changes, grid, probe = [changes], (1.0, 5.0), 6.0
    else:
        from peers import sympy_bicycle as peer

        d, t_all = timed(peer.derive)
        changes, t_root = timed(peer.speeds, d)
        changes, grid, probe = list(changes), (0.0, 10.0), 5.0
    values = np.linspace(*grid, 101)
    locus, t_locus = timed(lambda: [np.linalg.eigvals(np.asarray(d.A(x), float)) for x in values])
    eig_probe = np.linalg.eigvals(np.asarray(d.A(probe), float))
    return dict(tool="sympy", derive=d.t_derive, linearize=d.t_linearize, lambdify=d.t_lambdify,
                first=t_all + t_locus / len(values), per_point=t_locus / len(values), boundary=t_all + t_root,
                changes=changes, values=values, max_real=np.array([e.real.max() for e in locus]),
                eig_probe=eig_probe)


# ------------------------------------------------------------------------------------------
# report
# ------------------------------------------------------------------------------------------
def errors(name, changes):
    if name == "disk":
        return [abs(changes[0] - DISK_CRIT)] if changes else [np.nan]
    ref = reference_speeds()
    return [abs(c - r) for c, r in zip(changes, ref)] if len(changes) == 2 else [np.nan, np.nan]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-sympy", action="store_true", help="mbcomp only")
    ap.add_argument("--only", choices=("disk", "bicycle"), help="one problem")
    ap.add_argument("--derivatives", choices=("auto", "exact", "differences"), default="auto",
                    help="how mbcomp.linearize differentiates (default: exact where a program exists)")
    args = ap.parse_args(argv)
    names = [args.only] if args.only else ["disk", "bicycle"]

    rows, runs = [], {}
    for name in names:
        tools = [mbcomp_case(name, args.derivatives)]
        if not args.no_sympy:
            tools.append(sympy_case(name))
        runs[name] = tools
        for r in tools:
            err = errors(name, r["changes"])
            rows.append(dict(problem=name, tool=r["tool"], derive_s=r.get("derive", 0.0),
                             linearize_s=r.get("linearize", 0.0), lambdify_s=r.get("lambdify", 0.0),
                             first_answer_s=r["first"], per_point_s=r["per_point"], boundary_s=r["boundary"],
                             boundary=" ".join(f"{c:.15g}" for c in r["changes"]),
                             boundary_error=" ".join(f"{e:.2g}" for e in err)))

    print(f"{'problem':8s} {'tool':7s} {'derive':>8s} {'linearize':>9s} {'lambdify':>8s} {'first':>8s} "
          f"{'per pt':>9s} {'boundary':>9s}   boundary values (error)")
    for r in rows:
        print(f"{r['problem']:8s} {r['tool']:7s} {r['derive_s']:8.3f} {r['linearize_s']:9.3f} {r['lambdify_s']:8.3f} "
              f"{r['first_answer_s']:8.3f} {r['per_point_s']:9.2e} {r['boundary_s']:9.3f}   "
              f"{r['boundary']} ({r['boundary_error']})")
    print("(s, wall; disk error against sqrt(g/3r); bicycle errors against the printed matrices' roots "
          f"{reference_speeds()[0]:.13g}, {reference_speeds()[1]:.13g})")
    for name, tools in runs.items():
        if len(tools) == 2:
            mb, sy = tools
            print(f"{name}: sympy/mbcomp time to first eigenvalues {sy['first'] / mb['first']:.1f}x, "
                  f"to the boundary {sy['boundary'] / mb['boundary']:.1f}x, per further point "
                  f"{sy['per_point'] / mb['per_point']:.2g}x; root loci agree to "
                  f"{np.nanmax(np.abs(sy['max_real'] - mb['max_real'])):.1e} 1/s (largest real part)")

    with open(HERE / "stability.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    plot(runs, HERE / "stability.png")
    print(f"wrote {HERE / 'stability.csv'} and {HERE / 'stability.png'}")


def plot(runs, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.2))
    labels, xs = [], 0
    for name, tools in runs.items():
        for r in tools:
            color = "tab:blue" if r["tool"] == "mbcomp" else "tab:orange"
            ax0.bar(xs, r["boundary"], color=color)
            ax0.annotate(f"{r['boundary']:.3g} s", (xs, r["boundary"]), ha="center", va="bottom", fontsize=8)
            labels.append(f"{name}\n{r['tool']}")
            xs += 1
    ax0.set_xticks(range(xs), labels, fontsize=8)
    ax0.set_yscale("log")
    ax0.set_ylabel("time to the stability boundary (s, wall)")
    ax0.set_title("from nothing to the located boundary")
    if "bicycle" in runs:
        for r in runs["bicycle"]:
            style = dict(marker=".", ls="none", ms=5) if r["tool"] == "mbcomp" else dict(ls="-", lw=1)
            ax1.plot(r["values"], r["max_real"], label=r["tool"], **style)
        for v in reference_speeds():
            ax1.axvline(v, color="0.6", lw=0.6)
        ax1.axhline(0, color="0.5", lw=0.5)
        ax1.set_ylim(-3, 4)
        ax1.set_xlabel("forward speed v (m/s)")
        ax1.set_ylabel("largest real part of the eigenvalues (1/s)")
        ax1.set_title("Whipple bicycle: self-stable between the grey lines")
        ax1.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
