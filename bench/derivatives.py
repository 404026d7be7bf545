"""Exact derivatives (issue 31 item 7): the cost of mbcomp's ``df/dx`` per call against
Pinocchio's ``computeABADerivatives`` and against finite differences, as ratios in one run.

**Part A -- one Jacobian.** Two mechanisms (:data:`MECHANISMS`), each built the same way
for mbcomp (:func:`mbcomp_engines` of ``bench/peers.py``: the compiled C system
``mbcomp.simulate`` runs) and for Pinocchio, both in the joints' relative angles and rates, so
mbcomp's ``y = [q, u]`` is Pinocchio's ``(q, v)`` unchanged:

* ``planar``: ``bench/peers.py``'s ``models/n_link_pendulum.py`` (N uniform rods on hinges
  about z, its default parameters) and ``bench/peers/pinocchio_pendulum.py`` (``JointModelRZ``);
* ``3d``: ``bench/peers/chain3d.py``, N boxes on hinges about x, y, z in turn (spatial motion,
  full 3-D inertias; ``JointModelRX/RY/RZ``).

mbcomp's ODE is ``fun = [u, ddq(q, u)]``, so its ``(2N, 2N)`` Jacobian is
``[[0, I], [ddq/dq, ddq/du]]``; Pinocchio's ``computeABADerivatives(q, v, tau=0)`` gives
``ddq/dq``, ``ddq/dv`` and ``ddq/dtau = M^-1`` (which mbcomp's program does not compute:
Pinocchio does more work than is compared, an O(N^2) share of its O(N^3) total).

Before anything is timed, at a generic state (every angle and rate different) the script
asserts that mbcomp's exact Jacobian has the identity blocks exactly and that its ``ddq``
blocks agree with Pinocchio's to :data:`AGREE` relative (max abs difference / max abs entry of
the block); the central differences' distance from the exact matrix is reported.

Timed per call (CPU, ``bench/peers.py``'s ``per_call``: median of batches, one BLAS thread):

* ``pinocchio computeABADerivatives``: called from Python (with its ``(q, v, tau)`` arrays
  made once); ``pinocchio aba``: one forward-dynamics call, for scale;
* ``mbcomp C program``: :meth:`mbcomp.codegen.jacobian.BoundJacobian.run_c`, the generated C
  Jacobian program through its ctypes call, no copy, no check;
* ``mbcomp BoundJacobian``: the same plus copying the matrix out and checking it is finite
  (the wrapper's overhead is the difference);
* ``mbcomp LagrangeIndex1.jac``: what scipy's Radau/BDF/LSODA get (the evaluator's cached
  program, its statistics);
* ``mbcomp fun``: one right-hand-side call of the compiled system, for scale;
* ``forward differences (C fun)``: :meth:`mbcomp.formulations.Formulation.jac` (the
  differences mbcomp used before the exact program: ``2N + 1`` calls) on the compiled C
  right-hand side; ``central differences (C fun)``: ``4N`` calls of it (:func:`central_jacobian`);
  ``forward differences (numeric fun)``: ``Formulation.jac`` on the numeric (uncompiled) path.

The build of the Jacobian program (trace + forward-mode differentiation + C compile, in a fresh
``MBCOMP_CACHE`` so the compiler runs) is reported too: at N = 100 it dominates everything.

**Part B -- derivatives of whole runs** (:func:`part_b_sensitivities`, :func:`part_b_gradient`,
:func:`part_b_differences`): the same chain from its start state for ``B_T_END`` s at
``mbcomp.simulate``'s default tolerances, CPU time as multiples of one ``mbcomp.simulate`` of
the same run (from the Model, compiled library in the cache): forward-sensitivity runs
(``simulate(..., sensitivities=[...])``) with 1 and 10 parameters on ``--sens-N`` links (their
accuracy against a run at rtol 1e-12 is reported), the adjoint gradient (``mbcomp.gradient``) of
the first joint's angle at t_end with respect to 100 parameters on ``--grad-N`` links (checked against
central differences of tight runs), and central differences of whole runs at the accuracy the
sensitivities reach (the loosest run tolerance that gets there; two runs per parameter).
Parameters: every link's mass and every joint's start angle.

Measured (2026-11-28, session 4, idle 2-core VM, the program printed as loops over directions,
``mbcomp.codegen.direction_loops``): planar chain, the C program 0.58x / 0.46x / 0.47x / 0.68x
Pinocchio at N = 5 / 10 / 40 / 100 (the bound callable 0.82x..0.71x; ``LagrangeIndex1.jac``
0.93-1.0x at N = 5, 0.67x, 0.64x, and forward differences at N = 100, above
``jacobian.MAX_SPEEDS``), cold builds 0.7 / 2.1 / 9.7 / 23 s. The straight-line scalar program
it replaced was 0.66x / 0.78x / 2.53x / 6.68x and built in 0.35 / 1.16 / 20 / 133 s. The 3-D
chain: 1.09x / 1.23x / 4.5x at N = 5 / 10 / 40 (why: ``docs/design/derivatives.md``).

Writes bench/derivatives.csv (long format: table, N, who, quantity, value, note) and
bench/derivatives.png (per mechanism: microseconds per call and ratio to Pinocchio vs N); both are git-ignored
like every bench output.

Run: python bench/derivatives.py [--Ns 5,10,40,100] [--Ns-3d 5,10] [--quick] [--sens-N 10] [--grad-N 50] [--skip-b]
     (needs the extra: pip install -e ".[bench]"). About 2.5 minutes; the N = 100 and 3-D N = 40
     programs take 20-45 s of compiler each.
"""
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # as bench/peers.py: small matrices, shared cores
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import math  # noqa: E402
import pathlib  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent


def _load_peers_script():
    """``bench/peers.py`` as a module (its name is taken by the package ``bench/peers/``)."""
    spec = importlib.util.spec_from_file_location("bench_peers_script", HERE / "peers.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


PEERS = _load_peers_script()  # puts bench/ on sys.path: the peers package imports below

from peers import chain3d, pinocchio_pendulum  # noqa: E402
from peers.cpu_clock import cpu  # noqa: E402

import mbcomp  # noqa: E402
from mbcomp.codegen.jacobian import MAX_SPEEDS as JACOBIAN_MAX_SPEEDS, JacobianCode  # noqa: E402
from mbcomp.formulations import Formulation, LagrangeIndex1  # noqa: E402

AGREE = 1e-8     # the ddq blocks of mbcomp and Pinocchio must agree to this, relative
T0 = PEERS.T0
CENTRAL_STEP = 6e-6  # ~ eps^(1/3): central differences' best step for O(1) coordinates


def central_jacobian(fun, t, y, step=CENTRAL_STEP):
    """``d fun / dy`` by central differences (``2 n`` calls of ``fun``), column ``j`` with the
    step ``step * max(|y_j|, 1)``."""
    y = np.asarray(y, float)
    cols, yj = [], y.copy()
    for j in range(y.size):
        h = step * max(abs(y[j]), 1.0)
        yj[j] = y[j] + h
        fp = np.asarray(fun(t, yj))
        yj[j] = y[j] - h
        fm = np.asarray(fun(t, yj))
        yj[j] = y[j]
        cols.append((fp - fm) / (2.0 * h))
    return np.column_stack(cols)


def rel(a, b):
    """Max abs difference of two arrays over the max abs entry of ``b``."""
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


#: the mechanisms compared: name -> (mbcomp Model of N links, Pinocchio peer of N links)
MECHANISMS = {
    "planar": (lambda N: PEERS.MOD.build(N=N, **PEERS.PHYS, phi0=PEERS.PHI0, w0=PEERS.W0),
               lambda N: pinocchio_pendulum.build(N, **PEERS.PHYS)),
    "3d": (chain3d.build_model, chain3d.build),
}


class Chain:
    """Everything built for one mechanism and N: mbcomp's compiled system, its formulations
    and bound Jacobian program, and Pinocchio's model (the builders of ``bench/peers.py`` and
    ``bench/peers/``: :data:`MECHANISMS`)."""

    def __init__(self, mech, N):
        self.mech, self.N = mech, N
        self.notes = {}
        make_model, make_peer = MECHANISMS[mech]
        with PEERS.fresh_cache() as cache:
            model = make_model(N)
            engines = PEERS.mbcomp_engines(model, cache_dir=cache, notes=self.notes)
            if "c" not in engines:
                raise RuntimeError(f"N = {N}: no compiled C system ({self.notes.get('c', '?')}); "
                                   "a C compiler is needed for this benchmark")
            self.system = engines["c"].system
            self.numeric = LagrangeIndex1(engines["numeric"].system)
            self.form = LagrangeIndex1(self.system)
            c0 = cpu()
            code = JacobianCode.build(self.system, "c", cache_dir=cache, max_speeds=None)  # past the runs' bound too
            self.jac = code.bind(self.system)
            self.jac_build = cpu() - c0
            self.n_ops = code.n_ops
        self.peer = make_peer(N)
        self.y = PEERS.generic_state(N)

    def pinocchio(self):
        pin, p, N = self.peer.pin, self.peer, self.N
        q, v, tau = self.y[:N].copy(), self.y[N:].copy(), np.zeros(N)
        return lambda: pin.computeABADerivatives(p.model, p.data, q, v, tau)

    def pinocchio_aba(self):
        pin, p, N = self.peer.pin, self.peer, self.N
        q, v, tau = self.y[:N].copy(), self.y[N:].copy(), np.zeros(N)
        return lambda: pin.aba(p.model, p.data, q, v, tau)


def cross_check(c, rows):
    """Assert mbcomp's exact Jacobian is Pinocchio's (identity blocks exact, ddq blocks to
    :data:`AGREE`); record how far the differences are from it."""
    N, y = c.N, c.y
    J = c.jac(T0, y, 0.0, 0.0)
    assert J is not None, f"N = {N}: the Jacobian program does not hold at the generic state"
    if c.system.nu <= JACOBIAN_MAX_SPEEDS:  # above it LagrangeIndex1.jac differences by design
        assert np.array_equal(J, c.form.jac(T0, y)), "LagrangeIndex1.jac is not the exact program's matrix"
    assert np.array_equal(J[:N, :N], np.zeros((N, N))) and np.array_equal(J[:N, N:], np.eye(N)), \
        f"N = {N}: d(dq/dt)/dy is not [0, I]"
    dq, dv, _ = (np.asarray(x) for x in c.pinocchio()())
    e_q, e_v = rel(J[N:, :N], dq), rel(J[N:, N:], dv)
    assert e_q <= AGREE and e_v <= AGREE, \
        f"N = {N}: mbcomp's ddq/dq, ddq/du differ from Pinocchio's by {e_q:.1e}, {e_v:.1e} > {AGREE:g}"
    e_c = rel(central_jacobian(c.form.fun, T0, y), J)
    e_f = rel(Formulation.jac(c.form, T0, y), J)
    for who, v in (("ddq/dq vs pinocchio", e_q), ("ddq/du vs pinocchio", e_v),
                   ("central differences vs exact", e_c), ("forward differences vs exact", e_f)):
        rows.append(dict(table=f"agreement {c.mech}", N=N, who=who, quantity="rel_diff", value=v))
    return e_q, e_v, e_c, e_f


def timings(c, rows, batch_time):
    """Microseconds per call of each way to get df/dx (and one rhs call, for scale)."""
    N, y, t = c.N, c.y, T0
    jac, form, numeric = c.jac, c.form, c.numeric
    ways = {
        "pinocchio computeABADerivatives": c.pinocchio(),
        "mbcomp C program": lambda: jac.run_c(t, y, 0.0, 0.0),
        "mbcomp BoundJacobian": lambda: jac(t, y, 0.0, 0.0),
        "mbcomp LagrangeIndex1.jac": lambda: form.jac(t, y),
        "forward differences (C fun)": lambda: Formulation.jac(form, t, y),
        "central differences (C fun)": lambda: central_jacobian(form.fun, t, y),
        "forward differences (numeric fun)": lambda: Formulation.jac(numeric, t, y),
        "pinocchio aba (one rhs)": c.pinocchio_aba(),
        "mbcomp fun (one rhs, C)": lambda: form.fun(t, y),
    }
    us = {who: 1e6 * PEERS.per_call(f, batch_time) for who, f in ways.items()}
    us["mbcomp wrapper overhead"] = us["mbcomp BoundJacobian"] - us["mbcomp C program"]
    base = us["pinocchio computeABADerivatives"]
    for who, v in us.items():
        rows.append(dict(table=f"per_call {c.mech}", N=N, who=who, quantity="us_per_call", value=v))
        rows.append(dict(table=f"per_call {c.mech}", N=N, who=who, quantity="ratio_to_pinocchio", value=v / base))
    rows.append(dict(table=f"build {c.mech}", N=N, who="mbcomp Jacobian program (trace + tangent + C, cold)",
                     quantity="seconds", value=c.jac_build, note=f"{c.n_ops} operations"))
    return us


# ==========================================================================================
# Part B: derivatives of whole runs, as multiples of one simulation
# ==========================================================================================
# The same chain from its start state (bench/peers.py's model defaults), t_end = B_T_END,
# at mbcomp.simulate's default tolerances: one run, a forward-sensitivity run with 1 and 10
# parameters (mbcomp.simulate(..., sensitivities=[...])), an adjoint gradient with 100
# parameters (mbcomp.gradient) and central differences of whole runs at the accuracy the
# sensitivities reach. The parameters are every link's mass and every joint's start angle
# (``link<k>.m``, ``joint<k>.phi0``, in that alternation); the quantity differentiated is
# :data:`B_COLUMN` at t_end.
B_T_END = 1.0
B_RTOL, B_ATOL = 1e-8, 1e-10   # mbcomp.simulate's defaults
#: the quantity differentiated: the first joint's angle at t_end (every parameter moves it;
#: the last joint's relative angle hardly depends on the masses, since scaling every mass
#: leaves a chain under gravity alone unchanged: its derivatives of ~1e-8 drown in the
#: differences' noise)
B_COLUMN = "joint1.phi"
B_CHECK = 1e-5  # derivatives of runs at these tolerances must be this close to tight references


def b_model(N):
    """The chain of part B (bench/peers.py's model and defaults)."""
    return PEERS.MOD.build(N=N, **PEERS.PHYS, phi0=PEERS.PHI0, w0=PEERS.W0)


def b_params(N, count):
    """``count`` parameters of the N-link chain: ``link1.m, joint1.phi0, link2.m, ...``."""
    names = [n for k in range(1, N + 1) for n in (f"link{k}.m", f"joint{k}.phi0")]
    if count > len(names):
        raise ValueError(f"the {N}-link chain has {len(names)} such parameters, not {count}: give N >= {count // 2}")
    return names[:count]


def b_value(N, param):
    """The model's value of a parameter of :func:`b_params` (bench/peers.py's defaults)."""
    comp, name = param.rsplit(".", 1)
    k = int(comp.lstrip("linkjoint")) - 1
    if name == "m":
        return float(PEERS.PHYS["m"])
    return float(np.broadcast_to(np.asarray(PEERS.PHI0, float), (N,))[k])


def timed(f, repeats=3):
    """``(result, CPU seconds)`` of ``f()`` after one untimed call (which compiles the programs
    a run needs into the cache): the median of ``repeats`` calls when one takes under 1 s."""
    f()
    c0 = cpu()
    out = f()
    times = [cpu() - c0]
    while times[0] < 1.0 and len(times) < repeats:
        c0 = cpu()
        f()
        times.append(cpu() - c0)
    return out, float(np.median(times))


def one_run(model, rtol=B_RTOL, atol=B_ATOL, **kw):
    """``mbcomp.simulate`` of the part-B run (the C engine: the library is in the cache after
    the first call); fails loudly."""
    res = mbcomp.simulate(model, t_end=B_T_END, rtol=rtol, atol=atol, n_out=2, **kw)
    if res.status != "success":
        raise RuntimeError(f"part B: the run failed: {res.status}: {res.message}")
    return res


def part_b_sensitivities(N, counts, rows):
    """Forward-sensitivity runs with ``counts`` parameters as multiples of one simulation, and
    their accuracy against a tight one (rtol 1e-12)."""
    model = b_model(N)
    _, t_sim = timed(lambda: one_run(model))
    col = B_COLUMN
    out = {"simulation": t_sim}
    for P in counts:
        params = b_params(N, P)
        res, t = timed(lambda: one_run(model, sensitivities=params))
        out[P] = (t, res)
        rows.append(dict(table="part_b", N=N, who=f"forward sensitivities, {P} parameter(s)", quantity="seconds",
                         value=t))
        rows.append(dict(table="part_b", N=N, who=f"forward sensitivities, {P} parameter(s)",
                         quantity="multiple_of_one_simulation", value=t / t_sim))
    rows.append(dict(table="part_b", N=N, who="one simulation", quantity="seconds", value=t_sim))
    tight = one_run(model, rtol=1e-12, atol=1e-14, sensitivities=b_params(N, max(counts)))
    worst = 0.0
    for P in counts:
        res = out[P][1]
        for p in b_params(N, P):
            ref = tight.sensitivity(col, p)[-1]
            worst = max(worst, abs(res.sensitivity(col, p)[-1] - ref) / max(abs(ref), 1e-300))
    rows.append(dict(table="part_b", N=N, who="forward sensitivities vs rtol 1e-12", quantity="rel_err",
                     value=worst))
    assert worst <= B_CHECK, f"part B: the forward sensitivities are {worst:.1e} from a tight run's (> {B_CHECK:g})"
    return t_sim, worst, tight


def part_b_gradient(N, P, rows):
    """The adjoint gradient of :data:`B_COLUMN` at t_end with respect to ``P``
    parameters as a multiple of one simulation at the gradient's tolerances; checked against
    central differences of two tight runs for the first two parameters."""
    model = b_model(N)
    params = b_params(N, P)
    objective = {"terminal": B_COLUMN}
    rtol, atol = B_RTOL, B_ATOL
    _, t_sim = timed(lambda: one_run(model, rtol=rtol, atol=atol))
    gr, t = timed(lambda: mbcomp.gradient(model, objective, params, t_end=B_T_END, rtol=rtol, atol=atol))
    col = B_COLUMN
    worst = 0.0
    for k, p in enumerate(params[:2]):
        fd = run_difference(N, p, col, 1e-12, 1e-5)
        worst = max(worst, abs(gr.gradient[k] - fd) / max(abs(fd), 1e-300))
    assert worst <= B_CHECK, f"part B: the adjoint gradient is {worst:.1e} from central differences (> {B_CHECK:g})"
    for who, q, v in (("one simulation", "seconds", t_sim), (f"adjoint gradient, {P} parameters", "seconds", t),
                      (f"adjoint gradient, {P} parameters", "multiple_of_one_simulation", t / t_sim),
                      *((f"adjoint gradient, {P} parameters: {k} (wall)", "seconds", gr.stats[k])
                        for k in ("setup", "forward", "backward", "initial") if k in gr.stats),
                      ("adjoint gradient vs central differences (rtol 1e-12)", "rel_err", worst)):
        rows.append(dict(table="part_b", N=N, who=who, quantity=q, value=v))
    return t_sim, t, worst


def part_b_differences(N, target, tight, counts, t_sim, rows):
    """Central differences of whole runs at the accuracy the forward sensitivities reach:
    the loosest run tolerance (decades from 1e-8, step ``rtol^(1/3)`` relative) at which the
    differences of the first two parameters are within ``target`` of the tight sensitivities
    (``tight``: a run with sensitivities at rtol 1e-12); their cost per parameter is two such
    runs, reported for ``counts`` parameters as multiples of one simulation (``t_sim``)."""
    col = B_COLUMN
    params = b_params(N, 2)
    refs = [tight.sensitivity(col, p)[-1] for p in params]
    for e in range(8, 14):
        rtol = 10.0 ** -e
        errs = [abs(run_difference(N, p, col, rtol, rtol ** (1 / 3)) - r) / max(abs(r), 1e-300)
                for p, r in zip(params, refs)]
        if max(errs) <= target:
            break
    else:
        rows.append(dict(table="part_b", N=N, who="central differences of runs", quantity="rtol", value=math.nan,
                         note=f"not within {target:.1e} at any rtol down to 1e-13"))
        return None
    model = b_model(N)
    _, t_run = timed(lambda: one_run(model, rtol=rtol, atol=rtol / 100))
    rows.append(dict(table="part_b", N=N, who="central differences of runs", quantity="rtol", value=rtol,
                     note=f"error {max(errs):.1e} <= {target:.1e}"))
    for P in counts:
        rows.append(dict(table="part_b", N=N, who=f"central differences of runs, {P} parameter(s)",
                         quantity="multiple_of_one_simulation", value=2 * P * t_run / t_sim,
                         note=f"2 x {P} runs at rtol {rtol:g}, {t_run:.3g} s each"))
    return rtol, max(errs), t_run


def run_difference(N, param, column, rtol, step):
    """``d column(t_end) / d param`` by central differences of two whole runs at ``rtol``
    (atol ``rtol / 100``), the parameter moved by ``step`` relative (absolute for a zero)."""
    value = b_value(N, param)
    h = step * max(abs(value), 1.0)
    ends = []
    for sign in (1.0, -1.0):
        res = one_run(b_model(N), rtol=rtol, atol=rtol / 100, params={param: value + sign * h})
        ends.append(res[column][-1])
    return (ends[0] - ends[1]) / (2.0 * h)


# ------------------------------------------------------------------------------------------
# report
# ------------------------------------------------------------------------------------------
JACOBIANS = ["pinocchio computeABADerivatives", "mbcomp C program", "mbcomp BoundJacobian",
             "mbcomp LagrangeIndex1.jac", "forward differences (C fun)", "central differences (C fun)",
             "forward differences (numeric fun)"]


TITLES = {"planar": "planar N-link pendulum", "3d": "3-D chain (axes x, y, z in turn)"}


def print_tables(rows, runs):
    for mech, Ns in runs.items():
        data, _ = PEERS.pivot(rows, f"per_call {mech}", "us_per_call")
        ratio, _ = PEERS.pivot(rows, f"per_call {mech}", "ratio_to_pinocchio")
        agree, _ = PEERS.pivot(rows, f"agreement {mech}", "rel_diff")
        build, _ = PEERS.pivot(rows, f"build {mech}", "seconds")
        Ns = [N for N in Ns if N in data]
        if not Ns:
            continue
        print(f"\n## {TITLES[mech]}: df/dx per call, microseconds (ratio to Pinocchio's computeABADerivatives)\n")
        whos = JACOBIANS + ["mbcomp wrapper overhead", "pinocchio aba (one rhs)", "mbcomp fun (one rhs, C)"]
        body = [[w] + [f"{data[N][w]:.3g} ({ratio[N][w]:.2f}x)" for N in Ns] for w in whos]
        print(PEERS.md_table(["way"] + [f"N = {N}" for N in Ns], body))
        print(f"\n## {TITLES[mech]}: agreement (relative max abs difference) and build\n")
        whos = list(agree[Ns[0]].keys())
        body = [[w] + [f"{agree[N][w]:.1e}" for N in Ns] for w in whos]
        body += [[w] + [f"{build[N][w]:.2f} s" for N in Ns] for w in build[Ns[0]]]
        ops = {r["N"]: r["note"] for r in rows if r["table"] == f"build {mech}"}
        body.append(["Jacobian program size"] + [ops.get(N, "") for N in Ns])
        print(PEERS.md_table(["quantity"] + [f"N = {N}" for N in Ns], body))


def plot(rows, path, mechs):
    """Per mechanism: microseconds per Jacobian vs N (log-log), ratio to Pinocchio vs N."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    mechs = [m for m in mechs if PEERS.pivot(rows, f"per_call {m}", "us_per_call")[0]]
    fig, axes = plt.subplots(max(len(mechs), 1), 2, figsize=(13, 5 * max(len(mechs), 1)), squeeze=False)
    for row, mech in zip(axes, mechs):
        data, _ = PEERS.pivot(rows, f"per_call {mech}", "us_per_call")
        ratio, _ = PEERS.pivot(rows, f"per_call {mech}", "ratio_to_pinocchio")
        Ns = sorted(data)
        for ax, d, ylabel, title in ((row[0], data, "CPU time per call [us]", "df/dx per call"),
                                     (row[1], ratio, "ratio to Pinocchio computeABADerivatives",
                                      "df/dx per call, relative to Pinocchio")):
            for w in JACOBIANS:
                pts = [(N, d[N][w]) for N in Ns if w in d[N] and not math.isnan(d[N][w])]
                if pts:
                    style = "-" if w.startswith("pinocchio") else ("--" if w.startswith("mbcomp") else ":")
                    ax.loglog([p[0] for p in pts], [p[1] for p in pts], style, marker="o", label=w)
            if d is ratio:
                ax.axhline(1.0, color="k", lw=0.8)
            ax.set_xticks(Ns, [str(N) for N in Ns])
            ax.minorticks_off()
            ax.set(xlabel="N (links)", ylabel=ylabel, title=f"{TITLES[mech]}: {title}")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def part_b(args, rows):
    """Part B (see the module's docstring): sensitivities, gradient, differences of runs."""
    counts = (1, 10) if 2 * args.sens_N >= 10 else (1, 2 * args.sens_N)
    P = min(100, 2 * args.grad_N)
    print(f"part B: forward sensitivities on {args.sens_N} links ...", flush=True)
    t_sim, err, tight = part_b_sensitivities(args.sens_N, counts, rows)
    print(f"part B: central differences of runs to {err:.1e} ...", flush=True)
    part_b_differences(args.sens_N, err, tight, counts + ((P,) if P not in counts else ()), t_sim, rows)
    print(f"part B: adjoint gradient, {P} parameters on {args.grad_N} links ...", flush=True)
    part_b_gradient(args.grad_N, P, rows)


def print_part_b(rows):
    body = [[r["N"], r["who"], r["quantity"], f"{r['value']:.3g}", r.get("note", "")]
            for r in rows if r["table"] == "part_b"]
    if body:
        print(f"\n## part B: whole runs of {B_T_END:g} s (multiples of one mbcomp.simulate of the same run)\n")
        print(PEERS.md_table(["N", "what", "quantity", "value", "note"], body))


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--Ns", default="5,10,40,100", help="link counts of the planar chain (default 5,10,40,100)")
    ap.add_argument("--Ns-3d", default="5,10", help="link counts of the 3-D chain (default 5,10; its Jacobian "
                    "program has ~1.2 million operations at 40 links: minutes of compiler)")
    ap.add_argument("--quick", action="store_true", help="N = 5,10, short timing batches, part B on 4 and 5 links")
    ap.add_argument("--sens-N", type=int, default=10, help="links of part B's forward-sensitivity runs (default 10)")
    ap.add_argument("--grad-N", type=int, default=50, help="links of part B's 100-parameter gradient (default 50)")
    ap.add_argument("--skip-b", action="store_true", help="part A only")
    args = ap.parse_args(argv)
    if args.quick and args.Ns == ap.get_default("Ns"):
        args.Ns = "5,10"
        args.Ns_3d = "5"
        args.sens_N, args.grad_N = 4, 5
    args.Ns = [int(x) for x in args.Ns.split(",") if x.strip()]
    args.Ns_3d = [int(x) for x in args.Ns_3d.split(",") if x.strip()]
    return args


def main(argv=None):
    args = parse(argv)
    why = pinocchio_pendulum.available()
    if why:
        sys.exit(f"bench/derivatives.py compares with Pinocchio: {why}")
    wall0, cpu0 = time.perf_counter(), cpu()
    head = subprocess.run(["git", "-C", str(ROOT), "describe", "--always", "--dirty"], capture_output=True, text=True)
    runs = {"planar": args.Ns, "3d": args.Ns_3d}
    print(f"mbcomp {head.stdout.strip() or '?'}; N-link pendulum {PEERS.PHYS}; Ns {runs}")
    rows = []
    for mech, Ns in runs.items():
        for N in Ns:
            print(f"{mech}, N = {N}: building ...", flush=True)
            c = Chain(mech, N)
            e_q, e_v, e_c, _ = cross_check(c, rows)
            print(f"{mech}, N = {N}: exact vs Pinocchio {max(e_q, e_v):.1e}, central differences vs exact "
                  f"{e_c:.1e}; timing ...", flush=True)
            timings(c, rows, 0.02 if args.quick else 0.05)
            del c
    if not args.skip_b:
        part_b(args, rows)
    print_tables(rows, runs)
    print_part_b(rows)
    PEERS.write_csv(rows, HERE / "derivatives.csv")
    plot(rows, HERE / "derivatives.png", list(runs))
    print(f"\nwrote {HERE / 'derivatives.csv'} and {HERE / 'derivatives.png'} "
          f"({time.perf_counter() - wall0:.0f} s wall, {cpu() - cpu0:.0f} s CPU)")


if __name__ == "__main__":
    main()
