"""Cost and accuracy of one linearization: exact derivatives against differences, N = 40.

Two models, each at a steady state with an exact answer:

* ``pendulum``: the N-link planar pendulum (``models/n_link_pendulum.py``) hanging at rest,
  2N states; reference: ``A = -M_rel^-1 K_rel`` from the rods' analytic mass and gravity
  stiffness matrices in 40-digit arithmetic (mpmath);
* ``four_bar``: the N-four-bar (``models/n_four_bar.py``: 2N + 1 links, N loops, 5N rows of
  which 2N are redundant) upright at rest, 2 states; reference: the roots
  ``+-sqrt(g ((N+1)/2 + N) / (L ((N+1)/3 + N)))`` of its exact one-degree-of-freedom reduction.

Per model, derivative mode (``exact``: the tangent program of :mod:`mbcomp.codegen.eval_tangent`;
``differences``: central differences with Richardson extrapolation) and backend, in one run on
one machine (``time.perf_counter``):

* ``first``: :func:`mbcomp.linearize` of a freshly compiled system: everything a first answer
  costs (the evaluation program, for ``exact`` the derivative programs' trace and build);
* ``again``: best of 3 further linearizations of the same system (a sweep's next point:
  programs cached, nothing traced);
* ``error``: of ``A`` relative to its largest entry (pendulum), of the roots relative to the
  root (four-bar).

Writes ``bench/linearize.csv``. Run: python bench/linearize.py [--N 40] [--backends python,c]
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small matrices; threads only cost on a shared machine

import argparse  # noqa: E402
import csv  # noqa: E402
import pathlib  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import mpmath as mp  # noqa: E402
import numpy as np  # noqa: E402

import mbcomp  # noqa: E402
from mbcomp.analysis.evaluation import system_for  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "models"))
import n_four_bar  # noqa: E402
import n_link_pendulum  # noqa: E402

G, L_PEND, L_BAR = 9.81, 0.5, 1.0


def pendulum_reference(N, L=L_PEND, m=1.0):
    """``d(du/dt)/dphi`` of the hanging chain in relative angles, 40 digits, as floats."""
    mp.mp.dps = 40
    L, m, g = mp.mpf(L), mp.mpf(m), mp.mpf("9.81")
    M, K, T = mp.matrix(N, N), mp.matrix(N, N), mp.matrix(N, N)
    for i in range(1, N + 1):
        for j in range(1, N + 1):
            M[i - 1, j - 1] = m * L ** 2 * ((mp.mpf(1) / 3 + N - i) if i == j else (mp.mpf(1) / 2 + N - max(i, j)))
            T[i - 1, j - 1] = 1 if j <= i else 0
        K[i - 1, i - 1] = m * g * L * (N - i + mp.mpf(1) / 2)
    return np.array((-(T ** -1) * (M ** -1) * K * T).tolist(), float)


def pendulum_error(lin, N, ref):
    pos = [lin.state_names.index(f"joint{k}.phi") for k in range(1, N + 1)]
    vel = [lin.state_names.index(f"joint{k}.w") for k in range(1, N + 1)]
    return float(np.abs(lin.A[np.ix_(vel, pos)] - ref).max() / np.abs(ref).max())


def four_bar_error(lin, N):
    w = np.sqrt(G * ((N + 1) / 2 + N) / (L_BAR * ((N + 1) / 3 + N)))
    return float(np.abs(np.sort(lin.eigenvalues.real) - [-w, w]).max() / w)


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def run(N, backends):
    rows = []
    cases = [("pendulum", lambda: n_link_pendulum.build(N=N, L=L_PEND, phi0=0.0)),
             ("four_bar", lambda: n_four_bar.build(N=N, L=L_BAR, w0=0.0))]
    ref = pendulum_reference(N)
    for name, build in cases:
        for backend in backends:
            for mode in ("differences", "exact"):
                system = system_for(build(), None, backend)  # a fresh system: nothing cached
                lin, first = timed(lambda: mbcomp.linearize(system, derivatives=mode, backend=backend))
                again = min(timed(lambda: mbcomp.linearize(system, derivatives=mode, backend=backend))[1]
                            for _ in range(3))
                err = pendulum_error(lin, N, ref) if name == "pendulum" else four_bar_error(lin, N)
                rows.append(dict(model=name, N=N, backend=backend, derivatives=lin.derivatives, states=len(lin.A),
                                 first_s=round(first, 4), again_s=round(again, 4), error=f"{err:.2e}"))
                print(f"{name:9s} N={N} {backend:6s} {lin.derivatives:11s} states={len(lin.A):3d} "
                      f"first {first:7.3f} s  again {again:7.3f} s  error {err:.2e}", flush=True)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--N", type=int, default=40)
    ap.add_argument("--backends", default="python")
    args = ap.parse_args()
    rows = run(args.N, args.backends.split(","))
    with open(HERE / "linearize.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
