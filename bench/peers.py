"""mbcomp against Pinocchio, MuJoCo, sympy/pydy and Exudyn (N-link pendulum and more), as ratios.

The mechanism is ``models/n_link_pendulum.py`` (N uniform rods of mass ``m``, length ``L``
on hinges about z, relative joint angles, gravity along -y) with its default parameters; each
peer builds the same mechanism in ``bench/peers/`` (``pinocchio_pendulum``, ``mujoco_pendulum``,
``pydy_pendulum``) and exposes ``rhs(t, y)`` with ``y = [q, u]`` in mbcomp's convention. In
one process, BLAS on one thread, CPU time (``time.process_time``; builds also count the
compiler's child processes, ``bench/peers/cpu_clock.py``), medians:

1. **cross-check**: at a generic state every peer's and engine's ``du/dt`` against mbcomp's
   numeric ``LagrangeIndex1(system).fun``, relative (max abs difference / max abs du/dt);
   one that differs by more than 1e-8 is not timed;
2. **one call**: microseconds per forward-dynamics call ``rhs(t, y)`` (median of repeated
   batches): Pinocchio's ABA from Python (and in its own C++ loop), MuJoCo's ``mj_forward``,
   pydy's generated function (Cython), and mbcomp's engines (:func:`mbcomp_engines`: the
   ``fun`` the scipy integrators call from Python, on the C and Python programs and on the
   numeric path); ratios to Pinocchio's ABA called from Python;
3. **build**: CPU seconds to build each peer (pydy: derivation + generation + Cython) and
   mbcomp: assemble + initialize alone, + trace + generate (Python), + trace + generate +
   compile (C, cold: a fresh ``MBCOMP_CACHE`` temp directory for every N, so the compiler
   really runs) and the same again with that cache warm (what a second run pays): the
   program of the Lagrange right-hand side, traced at its first use, as ``mbcomp.simulate``
   builds it (the O(N^2) evaluation program stays lazy: nothing on this path asks for it);
4. **end to end**: 10 s of motion from the model's start state to 1e-8 maximum state error on
   a 101-point grid, against one reference (DOP853 at rtol = atol = 1e-13 on Pinocchio's rhs):
   scipy LSODA and DOP853 on each peer's rhs; *mbcomp default call*
   ``mbcomp.simulate(model, t_end=10, rtol=tol, atol=tol, n_out=101)`` from the Model (warm
   cache; its cold first call is a row of its own); *mbcomp best*: the cheapest of each
   engine x method (``--methods``). Tolerances are swept (half decades) and the cheapest run
   within 1e-8 is reported, with its ratio to Pinocchio's cheapest. N where the reference
   itself moves by more than 1e-9 between rtol 1e-12 and 1e-13 are reported as not
   measurable: from N = 10 on the 10 s motion of the curled chain is chaotic (5e-4 at N = 10,
   1e2 at N = 20), so the end-to-end table has N = 2 and 5 (``--t-end`` for a shorter run).

5. **three starts** (``--cases starts``, :mod:`peers.starts`): the same end to end from three
   start states (the model's curled chain, a low irregular swing, a thrown chain) at N = 5 and
   20 (``--starts-Ns``), over the longest of 10, 5, 2, 1, 0.5 s the chain's chaos leaves
   measurable: Pinocchio + scipy LSODA / DOP853, MuJoCo + scipy DOP853, **MuJoCo + C DOP853**
   (``peers/mujoco_dop853.c``: ``mj_forward`` inside mbcomp's own C DOP853, linked against the
   wheel's libmujoco: no Python per call, the strongest construct a MuJoCo user can build), and
   mbcomp's default call warm and cold;
6. **stiff** (``peers/stiff_chain.py``): bobs on damped stiff springs, Pinocchio + scipy LSODA /
   Radau against the default call (``auto``: DOP853 in C, LSODA once the C integrator finds the
   problem stiff); **events** (``peers/stop_pendulum.py``): a pendulum onto a rigid stop,
   Pinocchio in a hand-written ``solve_ivp`` event loop against the default call; **andrews**:
   ``bench/andrews.py``'s pydy Cython + DOP853 against the default call; **exudyn**
   (``peers/exudyn_peers.py``): Exudyn's kinematic tree under its DOPRI5 (pendulum, N = 5) and
   its redundant-coordinate slider-crank under generalized-alpha; **chain3d**: end to end on
   ``peers/chain3d.py``'s 3-D chain at N = 5 and 10 against Pinocchio + LSODA / DOP853 and
   MuJoCo + C DOP853 (``peers/chain3d_mujoco.py``; all in ``peers/cases.py``). A floating
   base is not here: its quaternion (nq != nv) needs each peer's own configuration
   integration, left to the per-call comparison of ``bench/chain3d.py``;
7. **targets**: issue 32 item 8's targets, each with its ratio and met / NOT met
   (``peers/report.py``), then the other ratios of the run (cold cache, stiff, events, Exudyn).

Pinocchio is not built above 400 links (``pinocchio_pendulum.MAX_LINKS``: its ``Data`` of a
serial chain grows like N^3 in memory; N = 1000 was killed out of memory); pydy only where its
derivation is predicted under 60 s; mbcomp's code generation only where predicted under
``--codegen-limit`` s. Every skip prints its reason.

Writes bench/peers.csv (long format: table, N, who, method, quantity, value, note) and
bench/peers.png (one call, build and end to end vs N); both are git-ignored like every bench
output.

Run: python bench/peers.py [--quick] [--cases onecall,e2e,starts,stiff,events,andrews,exudyn,chain3d]
     [--Ns 2,5,10,20,40,100,1000] [--skip pydy,mujoco] [--e2e-Ns 2,5,10,20] [--starts-Ns 5,20]
     [--budget 30] [--methods dop853,...|all]
     (needs the extra: pip install -e ".[bench]"). The default run takes about 10 min of CPU.
"""
import os

# one BLAS thread, as bench/scaling.py: the matrices are small, and a threaded BLAS on a shared
# 2-core machine slows the same Cholesky 5x (oversubscription), swamping what is measured
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse  # noqa: E402
import csv  # noqa: E402
import inspect  # noqa: E402
import math  # noqa: E402
import pathlib  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))  # bench/peers (the package wins over this script's name)

import mbcomp  # noqa: E402
from mbcomp.formulations import LagrangeIndex1  # noqa: E402
from mbcomp.initialization import initialize  # noqa: E402
from peers import mujoco_pendulum, pinocchio_pendulum, pydy_pendulum  # noqa: E402
from peers.cpu_clock import cpu  # noqa: E402
from peers.report import md_table, num  # noqa: E402
from peers.timing import Try, batch_seconds, fresh_cache, per_call, sweep  # noqa: E402

MODEL_FILE = ROOT / "models" / "n_link_pendulum.py"
PEERS = {"pinocchio": pinocchio_pendulum, "mujoco": mujoco_pendulum, "pydy": pydy_pendulum}
AGREE = 1e-8          # cross-check: relative du/dt difference a peer must stay within
TARGET = 1e-8         # end to end: max state error over the output grid
T_END, N_OUT = 10.0, 101
DERIVE_LIMIT = 60.0   # s of sympy derivation beyond which pydy is skipped
T0 = 0.0


def model_params():
    """The model file's own defaults: L, m, g, start angles and rates (one source of truth)."""
    mod = mbcomp.load_model_file(MODEL_FILE)
    d = {k: v.default for k, v in inspect.signature(mod.build).parameters.items()}
    return mod, dict(L=d["L"], m=d["m"], g=d["g"]), d["phi0"], d["w0"]


MOD, PHYS, PHI0, W0 = model_params()


def generic_state(N):
    """A state with no symmetry (every angle and rate different) for the cross-check."""
    k = np.arange(1, N + 1)
    return np.concatenate((0.3 + 0.4 * np.sin(1.7 * k), 0.5 * np.cos(2.3 * k)))


# ------------------------------------------------------------------------------------------
# mbcomp's engines: the one place that says which mbcomp right-hand sides are compared
# ------------------------------------------------------------------------------------------
@dataclass
class Engine:
    """One way mbcomp evaluates the pendulum's ``du/dt``.

    Calling it is ``rhs(t, y)`` (``y = [q, u]``); ``system`` is what :meth:`simulate` hands to
    ``mbcomp.simulate``; ``build_seconds`` is the CPU time to make it from the model
    (compiler processes included), ``warm_seconds`` the same with the compiled library
    already in the cache; ``note`` says anything unusual about it.
    """
    rhs: object
    system: object
    build_seconds: float
    note: str = ""
    simulate_kwargs: dict = field(default_factory=dict)
    warm_seconds: float = math.nan

    def __call__(self, t, y):
        return self.rhs(t, y)

    def simulate(self, **kwargs):
        return mbcomp.simulate(self.system, **{**self.simulate_kwargs, **kwargs})


def mbcomp_engines(model_or_system, *, cache_dir=None, codegen=True, c=True, max_nodes=3_000_000,
                   c_max_ops=300_000, notes=None):
    """mbcomp's right-hand sides of one model: ``{name: Engine}`` (an Engine is ``rhs(t, y)``).

    Today:

    * ``"numeric"``: :class:`mbcomp.formulations.LagrangeIndex1` on the assembled and
      initialized system (build = assemble + initialize);
    * ``"python"``, ``"c"``: the same on ``mbcomp.codegen.compile_system(system, backend,
      lazy=True)`` (build adds tracing and compiling the O(N) Lagrange right-hand side, made
      at the first ``fun`` call, as ``mbcomp.simulate`` builds it -- the O(N^2) evaluation
      program is left lazy; C in ``cache_dir``, which should be empty so the compiler runs;
      ``warm_seconds`` is the C build again with the cache filled).

    ``codegen=False`` (the caller predicts generation too slow) or ``c=False`` leave engines
    out; so do a refused generation (``max_nodes``), a program over ``c_max_ops`` operations
    for the C compiler, or no C compiler. Each reason is put in ``notes[name]``.

    To compare another engine, add it here (an :class:`Engine` whose ``system`` can be
    simulated, or whose ``simulate_kwargs`` select it, e.g. ``backend=...``): every table of
    this benchmark -- cross-check, one call, build, end to end -- loops over this dict.
    """
    from mbcomp.codegen import CodegenError, c_compiler, compile_system

    notes = {} if notes is None else notes
    c0 = cpu()
    system = model_or_system
    if isinstance(model_or_system, mbcomp.Model):
        system = mbcomp.assemble(model_or_system)
    initialize(system, T0)
    base = cpu() - c0
    if base < 0.1 and isinstance(model_or_system, mbcomp.Model):  # milliseconds: timed in batches
        base = batch_seconds(lambda: initialize(mbcomp.assemble(model_or_system), T0))
    # backend="numeric": simulate's default ("auto") would compile a numeric system first
    out = {"numeric": Engine(LagrangeIndex1(system).fun, system, base, simulate_kwargs=dict(backend="numeric"))}
    y = generic_state(system.nq)  # the pendulum: nq = nu = N

    def program(backend, **kw):
        c0 = cpu()
        # lazy: as mbcomp.simulate builds it -- the O(N^2) evaluation program (dense M, for
        # monitors and the numeric cross-check) is made only if something asks for it, so
        # what is built and timed here is the O(N) Lagrange program ``fun`` calls
        cs = compile_system(system, backend, max_nodes=max_nodes, verify=False, lazy=True, **kw)
        fun = LagrangeIndex1(cs).fun
        fun(T0, y)  # the Lagrange program is traced (and compiled) at its first use
        return cs, fun, cpu() - c0

    if not codegen:
        notes["python"] = notes["c"] = notes.get("codegen", "code generation skipped")
        return out
    try:
        py, fun, s = program("python")
        out["python"] = Engine(fun, py, base + s)
    except CodegenError as exc:
        notes["python"] = notes["c"] = f"generation refused: {str(exc)[:70]}"
        return out
    n_ops = py.stats["n_ops_fun"]
    if not c:
        notes["c"] = notes.get("c", "C skipped (--skip c)")
    elif c_compiler() is None:
        notes["c"] = "no C compiler"
    elif n_ops > c_max_ops:
        notes["c"] = f"C skipped: {n_ops} operations > {c_max_ops} (compiler time)"
    else:
        cs, fun, s = program("c", cache_dir=cache_dir)
        _, _, warm = program("c", cache_dir=cache_dir)
        if warm < 0.1:
            warm = batch_seconds(lambda: program("c", cache_dir=cache_dir))
        out["c"] = Engine(fun, cs, base + s, warm_seconds=base + warm)
    return out


# ------------------------------------------------------------------------------------------
# building everything for one N
# ------------------------------------------------------------------------------------------
class Bench:
    """Everything built for one N: ``peers`` and ``engines`` by name, ``notes`` by name."""

    def __init__(self, N, args, state, cache):
        self.N, self.notes, self.peers, self.cache = N, {}, {}, cache
        for name, mod in PEERS.items():
            if name in args.skip:
                self.notes[name] = "skipped (--skip)"
                continue
            why = mod.available()
            if why:
                self.notes[name] = why
                continue
            if name == "pydy":
                self._pydy(N, args, state)
                continue
            try:
                peer = mod.build(N, **PHYS)
                if peer.build_seconds < 0.1:  # a build of microseconds: timed in batches
                    peer.build_seconds = batch_seconds(lambda: mod.build(N, **PHYS))
                self.peers[name] = peer
            except MemoryError as exc:
                self.notes[name] = str(exc)
                continue
            if self.peers[name].note:
                self.notes[name] = self.peers[name].note
        self.engines = self._engines(N, args, state)

    def _pydy(self, N, args, state):
        pred = state.get("pydy_pred")
        if state.get("pydy_dead") or (pred is not None and pred(N) > DERIVE_LIMIT):
            self.notes["pydy"] = f"skipped (derivation > {DERIVE_LIMIT:.0f} s)"
            state["pydy_dead"] = True
            return
        gen = "lambdify" if "cython" in args.skip else "cython"
        try:
            p = pydy_pendulum.build(N, **PHYS, timeout=DERIVE_LIMIT, generator=gen)
        except pydy_pendulum.DerivationTimeout:
            self.notes["pydy"] = f"skipped (derivation > {DERIVE_LIMIT:.0f} s)"
            state["pydy_dead"] = True
            return
        self.peers["pydy"] = p
        self.notes["pydy"] = "; ".join(x for x in (p.note, f"derivation {p.derive_seconds:.1f} s") if x)
        pts = state.setdefault("pydy_pts", []) + [(N, p.derive_seconds)]
        state["pydy_pts"] = pts
        if len(pts) >= 2 and pts[-1][1] > 0.5:  # derivation grows like N^k (k ~ 3-4 measured)
            (n1, t1), (n2, t2) = pts[-2], pts[-1]
            k = max(2.5, math.log(t2 / max(t1, 1e-3)) / math.log(n2 / n1))
            state["pydy_pred"] = lambda n, n2=n2, t2=t2, k=k: t2 * (n / n2) ** k

    def _engines(self, N, args, state):
        notes = {}
        codegen, c = "python" not in args.skip, "c" not in args.skip
        # predict the build from the last measured N: the Lagrange program is O(N) (~120
        # operations per link) but gcc's time per statement grows slowly with the function's
        # surroundings, so the prediction scales like N^1.2 (measured: 3.2 s at N = 100 cold)
        prev = state.get("codegen_pts")
        if prev:
            n1, t_py, t_c = prev
            guess_py, guess_c = t_py * (N / n1) ** 1.2, t_c * (N / n1) ** 1.2
            if codegen and guess_py > args.codegen_limit:
                codegen = False
                notes["codegen"] = (f"code generation skipped (about {guess_py:.0f} s predicted > {args.codegen_limit:g} s)")
            elif c and not math.isnan(t_c) and guess_c > args.codegen_limit:
                c = False
                notes["c"] = (f"C skipped: trace + compile about {guess_c:.0f} s predicted > {args.codegen_limit:g} s")
        model = MOD.build(N=N, **PHYS, phi0=PHI0, w0=W0)
        engines = mbcomp_engines(model, cache_dir=self.cache, codegen=codegen, c=c, notes=notes)
        if "python" in engines:
            base = engines["numeric"].build_seconds
            t_c = engines["c"].build_seconds - base if "c" in engines else math.nan
            state["codegen_pts"] = (N, engines["python"].build_seconds - base, t_c)
        for name in ("python", "c"):
            if name in notes and name not in engines:
                self.notes[f"mbcomp {name}"] = notes[name]
        return engines

    def everyone(self):
        """(label, kind, rhs) for every peer and engine, peers first."""
        return ([(n, "peer", p.rhs) for n, p in self.peers.items()]
                + [(f"mbcomp {n}", "mbcomp", e) for n, e in self.engines.items()])

    def build_seconds(self):
        out = {**{n: p.build_seconds for n, p in self.peers.items()},
               **{f"mbcomp {n}": e.build_seconds for n, e in self.engines.items()}}
        if "c" in self.engines:
            out["mbcomp c (warm cache)"] = self.engines["c"].warm_seconds
        return out


# ------------------------------------------------------------------------------------------
# 1. cross-check and 2. one call
# ------------------------------------------------------------------------------------------
def cross_check(b, rows):
    """Relative du/dt difference of every peer and engine to mbcomp's numeric one; the set
    of labels that agree within :data:`AGREE`."""
    N, y = b.N, generic_state(b.N)
    ref = np.asarray(b.engines["numeric"](T0, y))[N:]
    scale = np.max(np.abs(ref))
    agreed = set()
    for label, kind, rhs in b.everyone():
        diff = float(np.max(np.abs(np.asarray(rhs(T0, y))[N:] - ref)) / scale)
        ok = diff <= AGREE
        rows.append(dict(table="cross_check", N=N, who=label, quantity="rel_diff", value=diff,
                         note="" if ok else f"disagrees with mbcomp numeric by {diff:.1e} > {AGREE:g}: not timed"))
        if ok:
            agreed.add(label)
        else:
            print(f"  {label}: du/dt differs from mbcomp numeric by {diff:.1e} (relative) > {AGREE:g}: not timed")
    return agreed


def one_call(b, agreed, rows, batch_time):
    """Microseconds per rhs call of every agreeing peer and engine (+ Pinocchio's C loop)."""
    N, y = b.N, generic_state(b.N)
    out = {}
    for label, kind, rhs in b.everyone():
        if label in agreed:
            out[label] = 1e6 * per_call(lambda: rhs(T0, y), batch_time)
    if "pinocchio" in agreed:
        s, acc = b.peers["pinocchio"].aba_c_loop(y)
        ref = np.asarray(b.engines["numeric"](T0, y))[N:]
        if np.max(np.abs(acc - ref)) <= AGREE * np.max(np.abs(ref)):
            out["pinocchio ABA C loop"] = 1e6 * s
    base = out.get("pinocchio")
    for label, us in out.items():
        rows.append(dict(table="one_call", N=N, who=label, quantity="us_per_call", value=us))
        if base:
            rows.append(dict(table="one_call", N=N, who=label, quantity="ratio_to_pinocchio_aba_python", value=us / base))
    return out


# ------------------------------------------------------------------------------------------
# 4. end to end
# ------------------------------------------------------------------------------------------
def run_peer(rhs, method, tol, y0, grid, ref):
    count = [0]

    def f(t, y):
        count[0] += 1
        return rhs(t, y)

    c0 = time.process_time()
    sol = solve_ivp(f, (0.0, T_END), y0, method=method, rtol=tol, atol=tol, t_eval=grid)
    cpu_s = time.process_time() - c0
    if not sol.success or sol.y.shape[1] != len(grid):
        return Try(tol, cpu_s, fail=f"solve_ivp: {sol.message}")
    return Try(tol, cpu_s, float(np.max(np.abs(sol.y.T - ref))), count[0])


def run_mbcomp(engine, method, setting, grid, ref):
    kw = dict(h=setting, rtol=1e-10, atol=1e-10) if method == "genalpha" else dict(rtol=setting, atol=setting)
    system = engine.system
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c0 = time.process_time()
        res = engine.simulate(t_end=T_END, method=method, n_out=N_OUT, **kw)
        cpu_s = time.process_time() - c0
    if res.status != "success" or len(res.time) != len(grid):
        return Try(setting, cpu_s, fail=f"{res.status}: {res.message[:80]}")
    Y = np.column_stack([res[n] for n in list(system.q_names) + list(system.u_names)])
    assert np.allclose(res.time, grid)
    return Try(setting, cpu_s, float(np.max(np.abs(Y - ref))), res.stats.get("nfev", math.nan))


def run_default(N, setting, grid, ref):
    """The default call from the Model, as a user writes it: assemble + trace (+ compile, or the
    cache's library) + initialize + integrate with the default method and backend; CPU time
    with the compiler's processes."""
    model = MOD.build(N=N, **PHYS, phi0=PHI0, w0=W0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        c0 = cpu()
        res = mbcomp.simulate(model, t_end=T_END, rtol=setting, atol=setting, n_out=N_OUT)
        cpu_s = cpu() - c0
    said = "; ".join(dict.fromkeys(str(w.message)[:100] for w in caught))
    if res.status != "success" or len(res.time) != len(grid):
        return Try(setting, cpu_s, fail=f"{res.status}: {res.message[:80]}")
    names = [f"joint{k + 1}.phi" for k in range(N)] + [f"joint{k + 1}.w" for k in range(N)]
    Y = np.column_stack([res[n] for n in names])
    t = Try(setting, cpu_s, float(np.max(np.abs(Y - ref))), res.stats.get("nfev", math.nan))
    t.note = f"method {res.stats.get('method')}, backend {res.stats.get('backend')}" + (f"; warned: {said}" if said else "")
    return t


MBCOMP_METHODS = ("dop853", "dopri5", "RK45", "DOP853", "LSODA", "Radau", "BDF", "radau5", "ida", "RK23", "genalpha")
#: the methods of "mbcomp best" by default: the explicit ones and LSODA (the pendulum is not
#: stiff; every implicit method was slower in every run of --methods all, at many times the time)
DEFAULT_METHODS = ("dop853", "dopri5", "DOP853", "LSODA")


def end_to_end(b, agreed, speed, args, rows):
    """Cheapest run within TARGET of: each peer x {LSODA, DOP853}, mbcomp's default call, and
    each engine x method (the cheapest of those is "mbcomp best"). Returns ``(runs, base)``
    (``base``: Pinocchio's cheapest CPU s) or ``(runs, None)``."""
    N = b.N
    y0 = np.concatenate((np.broadcast_to(PHI0, (N,)), np.broadcast_to(W0, (N,)))).astype(float)
    grid = np.linspace(0.0, T_END, N_OUT)
    ref_who = "pinocchio" if "pinocchio" in agreed else "mbcomp numeric"
    ref_rhs = b.peers["pinocchio"].rhs if ref_who == "pinocchio" else b.engines["numeric"]
    c0 = time.process_time()
    ref = solve_ivp(ref_rhs, (0.0, T_END), y0, method="DOP853", rtol=1e-13, atol=1e-13, t_eval=grid).y.T
    ref12 = solve_ivp(ref_rhs, (0.0, T_END), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=grid).y.T
    qual = float(np.max(np.abs(ref - ref12)))
    print(f"  reference: DOP853 1e-13 on {ref_who} ({time.process_time() - c0:.1f} s); vs 1e-12: {qual:.1e}")
    rows.append(dict(table="e2e", N=N, who=ref_who, method="DOP853 reference", quantity="diff_to_1e-12_run",
                     value=qual))
    out, hints = [], {}
    if qual > TARGET / 10:  # chaotic motion: the reference itself is not within 1e-8 of the truth
        note = (f"not measurable: the reference moves {qual:.0e} between rtol 1e-12 and 1e-13, so {TARGET:g} over "
                f"{T_END:g} s is beyond double precision at N = {N} (chaotic motion)")
        print(f"  skipped: {note}")
        rows.append(dict(table="e2e", N=N, who="all", method="", quantity="cpu_s", value=math.nan, note=note))
        return out, None

    def record(who, method, t, note, kind):
        out.append(dict(N=N, who=who, method=method, kind=kind, t=t, note=note or (t.note if t else "")))
        print(f"  {who:<22} {method:<9} " + (f"tol {t.setting:.0e}  err {t.err:.1e}  {t.cpu_s:7.3f} s" if t else note),
              flush=True)

    for name, p in b.peers.items():
        if name not in agreed:
            continue
        for method in ("LSODA", "DOP853"):
            start = hints.get(method, 12)
            t, note, k = sweep(lambda s: run_peer(p.rhs, method, s, y0, grid, ref), start, args.budget)
            if t is not None:
                hints[method] = min(hints.get(method, k), k)
            record(name, method, t, note, "peer")

    # the default call: mbcomp.simulate(model, ...) -- warm cache: the engines' build compiled the
    # evaluation and Lagrange programs; one short call compiles the output program (>= 100 points)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mbcomp.simulate(MOD.build(N=N, **PHYS, phi0=PHI0, w0=W0), t_end=0.1, n_out=N_OUT)
    t, note, k = sweep(lambda s: run_default(N, s, grid, ref), hints.get("DOP853", 12), args.budget)
    record("mbcomp default call", "default", t, note, "default")
    if t is not None:  # and its first call, compiler included: a cache of its own
        with fresh_cache():
            cold = run_default(N, t.setting, grid, ref)
        record("mbcomp default call (cold cache)", "default", None if cold.fail else cold, cold.fail, "default cold")

    engines = sorted((n for n in b.engines if f"mbcomp {n}" in agreed), key=lambda n: speed.get(f"mbcomp {n}", 0))
    unreachable, passed = {}, {}
    for method in args.methods:
        for i, n in enumerate(engines):
            if method in unreachable:
                record(f"mbcomp {n}", method, None, f"not tried: {unreachable[method]} on the faster engine", "mbcomp")
                continue
            start = hints.get(f"mbcomp {method}", 4 if method == "genalpha" else hints.get(method, 12))
            done = passed.get(method)
            if done is not None:  # same steps as on the faster engine: predict before spending the budget
                extra = done.nfev * 1e-6 * (speed.get(f"mbcomp {n}", 0) - speed.get(f"mbcomp {engines[0]}", 0))
                if done.cpu_s + extra > args.budget:
                    record(f"mbcomp {n}", method, None, f"not run: ~{done.cpu_s + extra:.0f} s predicted "
                           f"({done.nfev:.0f} calls) > the {args.budget:g} s budget", "mbcomp")
                    continue
            t, note, k = sweep(lambda s: run_mbcomp(b.engines[n], method, s, grid, ref), start, args.budget,
                               stop=14 if method == "genalpha" else 26)
            if t is not None:
                hints[f"mbcomp {method}"] = min(hints.get(f"mbcomp {method}", k), k)
                passed.setdefault(method, t)
            elif i == 0:
                unreachable[method] = note
            record(f"mbcomp {n}", method, t, note, "mbcomp")
    pin = [r["t"].cpu_s for r in out if r["who"] == "pinocchio" and r["t"]]
    base = min(pin) if pin else None
    for r in out:
        t = r["t"]
        common = dict(table="e2e", N=N, who=r["who"], method=r["method"], note=r["note"])
        if t is None:
            rows.append(dict(common, quantity="cpu_s", value=math.nan))
            continue
        for q, v in (("setting", t.setting), ("max_err", t.err), ("nfev", t.nfev), ("cpu_s", t.cpu_s)):
            rows.append(dict(common, quantity=q, value=v))
        if base:
            rows.append(dict(common, quantity="ratio_to_pinocchio_best", value=t.cpu_s / base))
    return out, base


# ------------------------------------------------------------------------------------------
# report
# ------------------------------------------------------------------------------------------
def pivot(rows, table, quantity):
    """{N: {who: value}} and the who's in first-seen order."""
    out, whos = {}, []
    for r in rows:
        if r["table"] == table and r["quantity"] == quantity:
            out.setdefault(r["N"], {})[r["who"]] = r["value"]
            if r["who"] not in whos:
                whos.append(r["who"])
    return out, whos


def best_of(runs, pred):
    """The cheapest passing run whose row satisfies ``pred``, or None."""
    ok = [r for r in runs if r["t"] is not None and pred(r)]
    return min(ok, key=lambda r: r["t"].cpu_s) if ok else None


def e2e_summary(e2e, rows):
    """One line per N: each peer's cheapest, mbcomp's default call (warm, cold) and best."""
    body = []
    for N, (runs, base) in sorted(e2e.items()):
        if not runs:
            note = next((r["note"] for r in rows if r["table"] == "e2e" and r["N"] == N and r["who"] == "all"), "")
            body.append([N] + ["-"] * 7 + [note])
            continue
        cells = []
        for pred in (lambda r: r["who"] == "pinocchio", lambda r: r["who"] == "mujoco", lambda r: r["who"] == "pydy",
                     lambda r: r["kind"] == "default", lambda r: r["kind"] == "default cold",
                     lambda r: r["kind"] == "mbcomp"):
            r = best_of(runs, pred)
            if r is None:
                cells.append("-")
                continue
            t, what = r["t"], r["method"] if r["kind"] not in ("mbcomp",) else f"{r['who'][7:]} {r['method']}"
            ratio = f", {t.cpu_s / base:.2f}x" if base else ""
            cells.append(f"{t.cpu_s:.3f} s ({what}{ratio})" if r["kind"] not in ("default", "default cold")
                         else f"{t.cpu_s:.3f} s{ratio}")
        best = best_of(runs, lambda r: r["kind"] == "mbcomp")
        dflt = best_of(runs, lambda r: r["kind"] == "default")
        tol = f"{dflt['t'].setting:.0e}" if dflt else "-"
        body.append([N] + cells + [tol, ""])
        if best:
            rows.append(dict(table="e2e_summary", N=N, who="mbcomp best", method=f"{best['who'][7:]} {best['method']}",
                             quantity="cpu_s", value=best["t"].cpu_s))
    return md_table(["N", "pinocchio", "mujoco", "pydy", "mbcomp default call (warm cache)",
                     "mbcomp default call (cold cache)", "mbcomp best", "default's rtol=atol", "note"], body)


def print_tables(rows, notes, e2e):
    order = ["pinocchio ABA C loop", "pinocchio", "mujoco", "pydy", "mbcomp numeric", "mbcomp python", "mbcomp c",
             "mbcomp c (warm cache)"]

    def cols(whos):
        return [w for w in order if w in whos] + [w for w in whos if w not in order]

    for title, table, q, fmt in (
            ("Cross-check: max |du/dt - mbcomp numeric| / max |du/dt| at a generic state", "cross_check", "rel_diff", ".1e"),
            ("One call: microseconds per forward-dynamics call rhs(t, y) (CPU, median of batches; mbcomp: "
             "LagrangeIndex1.fun as scipy calls it)", "one_call", "us_per_call", ".3g"),
            ("One call relative to Pinocchio ABA called from Python (lower is faster)", "one_call",
             "ratio_to_pinocchio_aba_python", ".3g"),
            ("Build: CPU seconds incl. compiler processes (peers: model / derivation + generation + Cython; mbcomp "
             "numeric: assemble + initialize; python: + trace + generate the Lagrange program; c: + trace + generate + "
             "compile, cold cache; c (warm cache): the same with the libraries cached)", "build", "seconds", ".3g")):
        data, whos = pivot(rows, table, q)
        if not data:
            continue
        c = cols(whos)
        print(f"\n### {title}\n")
        print(md_table(["N"] + c, [[N] + [num(data[N].get(w), fmt) for w in c] for N in sorted(data)]))
        print(f"\n- = not built or not timed (reason under Notes); Pinocchio is not built above "
              f"{pinocchio_pendulum.MAX_LINKS} links: its Data for a serial chain grows like N^3 in memory")
    for N, (runs, base) in sorted(e2e.items()):
        if not runs:
            continue
        print(f"\n### End to end, N = {N}: {T_END:g} s to max state error <= {TARGET:g} on {N_OUT} points "
              f"(CPU s; ratio to Pinocchio's cheapest{'' if base else ': n/a'})\n")
        body = []
        for r in runs:
            t = r["t"]
            if t is None:
                body.append([r["who"], r["method"], "-", "-", "-", "-", "-", r["note"]])
                continue
            setting = f"h={t.setting:.0e}" if r["method"] == "genalpha" else f"{t.setting:.0e}"
            body.append([r["who"], r["method"], setting, f"{t.err:.1e}", num(float(t.nfev), ".0f"), f"{t.cpu_s:.3f}",
                         num(t.cpu_s / base if base else None, ".3g"), r["note"]])
        print(md_table(["who", "method", "rtol=atol", "max err", "nfev", "CPU s", "ratio", "note"], body))
    if e2e:
        print(f"\n### End to end summary: {T_END:g} s to max state error <= {TARGET:g}, CPU s (cheapest passing run; "
              f"ratio to Pinocchio's cheapest). Peers: scipy LSODA / DOP853 on their rhs; mbcomp default call: "
              f"mbcomp.simulate(model, t_end={T_END:g}, rtol=tol, atol=tol, n_out={N_OUT}) from the Model (assemble, "
              f"trace, compile or load from cache, initialize, integrate); mbcomp best: cheapest engine x method\n")
        print(e2e_summary(e2e, rows))
    if notes:
        print("\n### Notes\n")
        for (N, who), note in sorted(notes.items(), key=lambda kv: (kv[0][0], kv[0][1])):
            print(f"- N = {N}, {who}: {note}")


def write_csv(rows, path):
    keys = ["table", "N", "who", "method", "quantity", "value", "note"]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in keys})


def plot(rows, e2e, path, starts=None):
    """Four panels: one call vs N, build vs N (log-log), end to end per N from the model's start
    (bars), end to end from the three starts per N (bars)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 4, figsize=(22, 5.2))
    plot_starts(axes[3], starts or {})
    for ax, table, q, ylabel, title in (
            (axes[0], "one_call", "us_per_call", "CPU time per rhs call [us]", "one forward-dynamics call"),
            (axes[1], "build", "seconds", "CPU time [s]", "build (+ generate + compile)")):
        data, whos = pivot(rows, table, q)
        for w in whos:
            pts = sorted((N, d[w]) for N, d in data.items() if w in d and not math.isnan(d[w]))
            if not pts:
                continue
            style = "--" if w.startswith("mbcomp") else "-"
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], style, marker="o", label=w)
        Ns = sorted(data)
        if Ns:
            ax.set_xticks(Ns, [str(N) for N in Ns])
        ax.minorticks_off()
        ax.set(xlabel="N (links)", ylabel=ylabel, title=f"N-link pendulum: {title}")
        ax.grid(True, which="both", alpha=0.3)
        if whos:
            ax.legend(fontsize=7)
    ax = axes[2]
    measured = [(N, runs, base) for N, (runs, base) in sorted(e2e.items()) if runs]
    labels = ("pinocchio", "mujoco", "pydy", "mbcomp default call", "mbcomp best")
    preds = (lambda r: r["who"] == "pinocchio", lambda r: r["who"] == "mujoco", lambda r: r["who"] == "pydy",
             lambda r: r["kind"] == "default", lambda r: r["kind"] == "mbcomp")
    width = 0.8 / len(labels)
    for i, (lab, pred) in enumerate(zip(labels, preds)):
        xs, ys = [], []
        for j, (N, runs, base) in enumerate(measured):
            r = best_of(runs, pred)
            if r is not None:
                xs.append(j + (i - (len(labels) - 1) / 2) * width)
                ys.append(r["t"].cpu_s)
        if xs:
            ax.bar(xs, ys, width, label=lab)
    ax.set_xticks(range(len(measured)), [f"N = {N}" for N, _, _ in measured])
    ax.set_yscale("log")
    ax.set(ylabel="CPU time [s]", title=f"end to end: {T_END:g} s to {TARGET:g} max state error")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    if measured:
        ax.legend(fontsize=7)
    else:
        ax.text(0.5, 0.5, "end to end not run", ha="center", va="center", transform=ax.transAxes)
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def plot_starts(ax, starts):
    """Bars: CPU s of Pinocchio + LSODA, MuJoCo + C DOP853 and mbcomp's default call (warm,
    cold) for each (N, start)."""
    from peers.report import cheapest

    keys = sorted(starts, key=lambda k: (k[1], k[0]))
    series = (("Pinocchio + LSODA", lambda r: r["who"] == "pinocchio" and r["method"] == "LSODA"),
              ("MuJoCo + C DOP853", lambda r: r["who"] == "mujoco + C DOP853"),
              ("mbcomp default call", lambda r: r["who"] == "mbcomp default call"),
              ("mbcomp default call, cold cache", lambda r: r["who"] == "mbcomp default call (cold cache)"))
    width = 0.8 / len(series)
    for i, (lab, pred) in enumerate(series):
        xs, ys = [], []
        for j, key in enumerate(keys):
            r = cheapest(starts[key][1], pred)
            if r is not None:
                xs.append(j + (i - (len(series) - 1) / 2) * width)
                ys.append(r["t"].cpu_s)
        if xs:
            ax.bar(xs, ys, width, label=lab)
    ax.set_xticks(range(len(keys)), [f"N={N}\n{s}\n{starts[(s, N)][0].get('t_end') or '-'} s" for s, N in keys],
                  fontsize=7)
    ax.set_yscale("log")
    ax.set(ylabel="CPU time [s]", title="end to end from three starts, to 1e-8")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    if keys:
        ax.legend(fontsize=7)
    else:
        ax.text(0.5, 0.5, "starts not run", ha="center", va="center", transform=ax.transAxes)


# ------------------------------------------------------------------------------------------
CASES = ("onecall", "e2e", "starts", "stiff", "events", "andrews", "exudyn", "chain3d")


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=",".join(CASES), help="comma-separated parts to run: onecall (cross-check, "
                    "one call, build tables over --Ns), e2e (end to end from the model's start, every method), starts "
                    "(end to end from three starts at --starts-Ns: the targets), stiff, events, andrews, exudyn, chain3d "
                    f"(default all: {','.join(CASES)})")
    ap.add_argument("--Ns", default="2,5,10,20,40,100,1000", help="link counts of the one-call and build tables")
    ap.add_argument("--quick", action="store_true", help="N = 2,5,10,20; end to end at N = 5 with dop853, DOP853, "
                    "LSODA; budget 5 s")
    ap.add_argument("--skip", default="", help="comma-separated: pinocchio, mujoco, pydy, cython (pydy with "
                    "lambdify), python (mbcomp code generation), c (mbcomp's C backend), e2e")
    ap.add_argument("--e2e-Ns", default=None, help="end-to-end sizes (default the --Ns up to 20; --quick: 5)")
    ap.add_argument("--starts-Ns", default="5,20", help="sizes of the three-starts end to end (the targets' N)")
    ap.add_argument("--budget", type=float, default=None, help="CPU s allowed per end-to-end run (default 30, quick 5)")
    ap.add_argument("--methods", default=None, help="mbcomp.simulate methods of 'mbcomp best' (default "
                    f"{','.join(DEFAULT_METHODS)}; 'all': {','.join(MBCOMP_METHODS)}; --quick: dop853,DOP853,LSODA)")
    ap.add_argument("--t-end", type=float, default=T_END, help="end-to-end simulated time (s; default 10: chaotic, "
                    "so not measurable to 1e-8, from N = 10 on)")
    ap.add_argument("--codegen-limit", type=float, default=60.0, help="skip mbcomp code generation predicted over this (s)")
    args = ap.parse_args(argv)
    args.cases = [c.strip() for c in args.cases.split(",") if c.strip()]
    unknown = set(args.cases) - set(CASES)
    if unknown:
        ap.error(f"unknown --cases {sorted(unknown)}: choose from {','.join(CASES)}")
    args.skip = {s.strip() for s in args.skip.split(",") if s.strip()}
    if args.quick and args.Ns == ap.get_default("Ns"):
        args.Ns = "2,5,10,20"
    args.Ns = [int(x) for x in args.Ns.split(",")] if "onecall" in args.cases else []
    if args.e2e_Ns is None:
        args.e2e_Ns = [5] if args.quick else sorted(N for N in args.Ns if N <= 20)
    else:
        args.e2e_Ns = [int(x) for x in args.e2e_Ns.split(",") if x]
    if "e2e" in args.skip or "e2e" not in args.cases:
        args.e2e_Ns = []
    args.starts_Ns = [int(x) for x in args.starts_Ns.split(",") if x] if "starts" in args.cases else []
    args.budget = args.budget or (5.0 if args.quick else 30.0)
    quick_methods = "dop853,DOP853,LSODA"  # the default (the C engine) and the two the peers run
    methods = args.methods or (quick_methods if args.quick else ",".join(DEFAULT_METHODS))
    args.methods = list(MBCOMP_METHODS) if methods == "all" else methods.split(",")
    return args


def per_n_tables(args, rows, notes, e2e):
    """Cross-check, one call, build and end to end (the model's start) for every N."""
    state = {}
    for N in sorted(set(args.Ns) | set(args.e2e_Ns)):
        print(f"N = {N}: building ...", flush=True)
        with fresh_cache() as cache:  # cold: the compiler runs for this N's programs
            b = Bench(N, args, state, cache)
            notes.update({(N, k): v for k, v in b.notes.items()})
            for who, s in b.build_seconds().items():
                rows.append(dict(table="build", N=N, who=who, quantity="seconds", value=s))
            agreed = cross_check(b, rows)
            speed = one_call(b, agreed, rows, 0.02 if args.quick else 0.05) if N in args.Ns else {}
            if N not in args.Ns:  # end-to-end only: still rank the engines by speed
                speed = {f"mbcomp {n}": per_call(lambda e=e: e(T0, generic_state(N)), 0.01) for n, e in b.engines.items()}
            if N in args.e2e_Ns:
                print(f"N = {N}: end to end ...", flush=True)
                e2e[N] = end_to_end(b, agreed, speed, args, rows)
            del b


def case_rows(table, head, case_rows_, rows, N=""):
    """A case's rows into the CSV's long format."""
    for r in case_rows_:
        t = r["t"]
        common = dict(table=table, N=N, who=r["who"], method=r["method"], note=r["note"])
        if t is None:
            rows.append(dict(common, quantity="cpu_s", value=math.nan))
            continue
        for q, v in (("setting", t.setting), ("max_err", t.err), ("nfev", t.nfev), ("cpu_s", t.cpu_s)):
            rows.append(dict(common, quantity=q, value=v))


def run_cases(args, rows):
    """The three-starts end to end and the stiff, event, Andrews and Exudyn cases:
    ``(starts, andrews, others)`` as :func:`peers.report.targets` takes them."""
    from peers import cases, starts as starts_mod

    starts, andrews, others = {}, None, {}
    for N in args.starts_Ns:
        for start in starts_mod.STARTS:
            print(f"starts: N = {N}, {start} ...", flush=True)
            head, rs = starts_mod.run_case(MOD, PHYS, N, start, args.budget)
            starts[(start, N)] = (head, rs)
            case_rows(f"starts {start}", head, rs, rows, N)
    for name in ("stiff", "events", "andrews", "exudyn", "chain3d"):
        if name not in args.cases:
            continue
        print(f"{name} ...", flush=True)
        head, rs = getattr(cases, name)(args.budget)
        case_rows(name, head, rs, rows)
        if name == "andrews":
            andrews = (head, rs)
        else:
            others[name] = (head, rs)
    return starts, andrews, others


def print_cases(starts, andrews, others):
    from peers.report import TARGETS_DOC, case_table, targets

    lsoda = lambda r: r["who"] == "pinocchio" and r["method"] == "LSODA"  # noqa: E731
    for (start, N), (head, rs) in sorted(starts.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        if head.get("t_end") is None:
            print(f"\n### Start '{start}', N = {N}: {head.get('note', '')}")
            continue
        print(case_table(f"End to end from the start '{start}', N = {N}: {head['t_end']:g} s to max state error "
                         f"<= 1e-8 on 101 points (reference {head['ref']}, moves {head['quality']:.0e} vs 1e-12; the "
                         f"default call over 1 us of motion: {head.get('fixed_s', math.nan):.4f} s)",
                         rs, lsoda))
    for head, rs, base in ((andrews or (None, None)) + (lambda r: r["who"].startswith("sympy"),),
                           *((h, r, None) for h, r in others.values())):
        if head is None:
            continue
        if base is None:
            base = {"stiff": lsoda, "events": lambda r: r["who"].startswith("pinocchio")}.get(head["case"])
        print(case_table(f"{head['case']}: {head['what']}" + (f" -- {head['note']}" if head.get("note") else ""),
                         rs, base))
    body, info = targets(starts, andrews, others)
    print(f"\n### Targets (issue 32 item 8: {TARGETS_DOC}); ratio = CPU time of mbcomp's default call "
          "(warm cache) / the peer's cheapest passing run, same run\n")
    print(md_table(["target", "case", "ratio", "limit", "met", "CPU s (mbcomp / peer) or why not"], body)
          if body else "(no target case run: --cases starts,andrews)")
    if info:
        print("\n### Other ratios of this run (items 4 and 5 set the limits shown; item 8 none)\n")
        print(md_table(["ratio", "case", "value", "limit", "met", "CPU s (mbcomp / peer) or why not"], info))
    return body


def main(argv=None):
    global T_END
    args = parse(argv)
    T_END = args.t_end
    wall0, cpu0 = time.perf_counter(), cpu()
    head = subprocess.run(["git", "-C", str(ROOT), "describe", "--always", "--dirty"], capture_output=True, text=True)
    print(f"mbcomp {head.stdout.strip() or '?'}; cases {args.cases}; N-link pendulum {PHYS}, model start angles "
          f"{PHI0}, rates {W0}; Ns {args.Ns}, end to end at {args.e2e_Ns}, starts at {args.starts_Ns}, mbcomp methods "
          f"{args.methods}")
    rows, notes, e2e = [], {}, {}
    per_n_tables(args, rows, notes, e2e)
    starts, andrews, others = run_cases(args, rows)
    print_tables(rows, notes, e2e)
    body = print_cases(starts, andrews, others)
    for r in body:
        rows.append(dict(table="targets", who=r[0], method=r[1], quantity="ratio", value=float(r[2]) if r[2] != "-"
                         else math.nan, note=f"{r[3]} {r[4]}"))
    write_csv(rows, HERE / "peers.csv")
    plot(rows, e2e, HERE / "peers.png", starts)
    print(f"\nwrote {HERE / 'peers.csv'} and {HERE / 'peers.png'} ({time.perf_counter() - wall0:.0f} s wall, "
          f"{cpu() - cpu0:.0f} s CPU)")


if __name__ == "__main__":
    main()
