"""The stiff, event, Andrews, Exudyn and 3-D chain cases of ``bench/peers.py``: each a function returning the
rows of one table (``who``, ``method``, ``t``: a :class:`~peers.timing.Try` or None, ``note``)
and a header dict (what is measured, to which error).

* :func:`stiff`: ``stiff_chain`` (N = 2 links, bobs on springs of 1e6 N/m damped by 1e5 N s/m)
  for 0.5 s to 1e-8 max state error on 101 points against scipy's Radau at rtol 1e-13 on
  Pinocchio's rhs: scipy LSODA and Radau on Pinocchio; mbcomp's default call (``auto``: DOP853
  in C until its stiffness test fires, then LSODA with the exact Jacobian) warm and cold.
* :func:`events`: ``stop_pendulum`` (five impacts on a rigid stop in 5 s) to 1e-8 max impact
  time error against the closed form: Pinocchio with scipy's event loop (LSODA, DOP853);
  mbcomp's default call (the stop's events located on the C integrator's dense output) warm
  and cold.
* :func:`andrews`: Andrews' squeezer to 1e-6 relative angle error at 0.03 s, by
  ``bench/andrews.py``'s own runners and sweep: sympy Kane + pydy's Cython rhs in scipy's
  DOP853 against mbcomp's default call from the Model (warm, and cold).

* :func:`exudyn`: Exudyn's kinematic tree under its DOPRI5 (pendulum N = 5, curled, 10 s, 1e-8
  at t_end) and its redundant-coordinate slider-crank under generalized-alpha (10 s, 1e-4 at
  t_end; step counts swept) against the default call on the same measure.
* :func:`chain3d`: ``chain3d``'s 3-D chain at N = 5 and 10 (the starts' measure and reference,
  :mod:`peers.starts`) against Pinocchio + LSODA / DOP853 and MuJoCo + C DOP853.

Tolerances: rtol = atol = 10^(-k/2) swept to the target (Andrews: atol = rtol/100, as
``bench/andrews.py``); CPU seconds, medians of three for short runs.
"""
import importlib.util
import math
import pathlib
import time
import warnings

import numpy as np
from scipy.integrate import solve_ivp

from . import stiff_chain, stop_pendulum
from .cpu_clock import cpu
from .timing import Try, fresh_cache, sweep

__all__ = ["stiff", "events", "andrews", "exudyn", "chain3d"]

BENCH = pathlib.Path(__file__).resolve().parent.parent
TARGET = 1e-8


def _bench_script(name):
    """A script of ``bench/`` as a module (its ``main`` not run), under a name of its own."""
    spec = importlib.util.spec_from_file_location(f"bench_{name}", BENCH / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _simulate(model, **kw):
    import mbcomp

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c0 = cpu()
        res = mbcomp.simulate(model, **kw)
        return res, cpu() - c0


def _log_row(log, who, method, t, note):
    log(f"    {who:<34} {method:<8} " + (f"tol {t.setting:.0e} err {t.err:.1e} {t.cpu_s:8.4f} s" if t else note),
        flush=True)


def _default_rows(run, start, budget, log, target=TARGET, warm_up=None):
    """The default call warm (the cache filled by ``warm_up()``) and cold, as rows."""
    rows = []
    with fresh_cache():
        if warm_up:
            warm_up()
        t, note, _ = sweep(run, start, budget, target=target)
    rows.append(dict(who="mbcomp default call", method="default", t=t, note=note or (t.note if t else "")))
    if t is not None:
        with fresh_cache():
            cold = run(t.setting)
        rows.append(dict(who="mbcomp default call (cold cache)", method="default", t=None if cold.fail else cold,
                         note=cold.fail or cold.note))
    for r in rows:
        _log_row(log, r["who"], r["method"], r["t"], r["note"])
    return rows


# ------------------------------------------------------------------------------------------
def stiff(budget, log=print):
    """The stiff chain: ``(header, rows)``."""
    d = stiff_chain.DEFAULTS
    N, t_end = d["N"], 0.5
    names = stiff_chain.state_names(N)
    head = dict(case="stiff", what=f"damped stiff spring chain (N = {N}), {t_end} s, max state error <= {TARGET:g} "
                f"on 101 points (reference: scipy Radau 1e-13 on Pinocchio)")
    why = stiff_chain.available()
    if why:
        head["note"] = why
        return head, []
    import mbcomp
    from mbcomp.formulations import LagrangeIndex1
    from mbcomp.initialization import initialize

    peer = stiff_chain.build()
    system = mbcomp.assemble(stiff_chain.build_model())
    initialize(system, 0.0)
    phi0, s0 = stiff_chain.start(N)
    y0 = np.array([v for k in range(N) for v in (phi0[k], s0[k])] + [0.0] * (2 * N))
    yc = y0 + np.linspace(0.01, 0.08, len(y0)) * np.r_[np.ones(2 * N), 10 * np.ones(2 * N)]
    mine = np.asarray(LagrangeIndex1(system).fun(0.0, yc))
    diff = float(np.max(np.abs(peer.rhs(0.0, yc) - mine)) / np.max(np.abs(mine)))
    if diff > TARGET:
        head["note"] = f"Pinocchio's rhs differs from mbcomp's by {diff:.1e}: not timed"
        return head, []
    grid = np.linspace(0.0, t_end, 101)
    c0 = time.process_time()
    ref = solve_ivp(peer.rhs, (0, t_end), y0, method="Radau", rtol=1e-13, atol=1e-13, t_eval=grid).y.T
    ref12 = solve_ivp(peer.rhs, (0, t_end), y0, method="Radau", rtol=1e-12, atol=1e-12, t_eval=grid).y.T
    qual = float(np.max(np.abs(ref - ref12)))
    log(f"  stiff: reference {time.process_time() - c0:.1f} s, moves {qual:.0e} vs 1e-12; du/dt agrees to {diff:.0e}")
    head["quality"] = qual
    rows = []
    for method in ("LSODA", "Radau"):
        def run(tol, method=method):
            count = [0]

            def f(t, y):
                count[0] += 1
                return peer.rhs(t, y)
            c0 = time.process_time()
            sol = solve_ivp(f, (0, t_end), y0, method=method, rtol=tol, atol=tol, t_eval=grid)
            cpu_s = time.process_time() - c0
            if not sol.success:
                return Try(tol, cpu_s, fail=sol.message[:80])
            return Try(tol, cpu_s, float(np.max(np.abs(sol.y.T - ref))), count[0])
        t, note, _ = sweep(run, 8, budget)
        rows.append(dict(who="pinocchio", method=method, t=t, note=note))
        _log_row(log, "pinocchio", method, t, note)

    def run_default(tol, **kw):
        res, cpu_s = _simulate(stiff_chain.build_model(), t_end=t_end, rtol=tol, atol=tol, n_out=101, **kw)
        if res.status != "success":
            return Try(tol, cpu_s, fail=f"{res.status}: {res.message[:80]}")
        Y = np.column_stack([res[n] for n in names])
        t = Try(tol, cpu_s, float(np.max(np.abs(Y - ref))), res.stats.get("nfev", math.nan))
        sf = res.stats.get("stiff_from")
        t.note = f"method {res.stats.get('method')}" + (f", stiff from {sf:.2g} s" if sf is not None else ", no switch")
        return t
    rows += _default_rows(run_default, 8, budget, log,
                          warm_up=lambda: _simulate(stiff_chain.build_model(), t_end=0.01, n_out=101))
    # radau5 as a user asks for it (the index-1 ODE, the exact Jacobian): issue 32 item 4's
    # "radau5 <= 1x Pinocchio + LSODA on a stiff chain"
    t, note, _ = sweep(lambda tol: run_default(tol, method="radau5"), 8, budget)
    rows.append(dict(who="mbcomp radau5", method="radau5", t=t, note=note))
    _log_row(log, "mbcomp radau5", "radau5", t, note)
    return head, rows


# ------------------------------------------------------------------------------------------
def events(budget, log=print):
    """The pendulum on a stop: ``(header, rows)``."""
    ev = _bench_script("events")
    t_end, e, phi0 = 5.0, 0.7, 0.8
    exact = ev.pendulum_times(20, e=e, phi0=phi0)
    exact = exact[exact < t_end]
    head = dict(case="events", what=f"pendulum onto a rigid stop (restitution {e}), {t_end} s, {len(exact)} impacts, "
                f"max impact time error <= {TARGET:g} (closed form)")
    why = stop_pendulum.available()
    rows = []

    def err_of(times):
        if len(times) != len(exact):
            return None
        return float(np.max(np.abs(np.asarray(times) - exact)))

    if why:
        head["note"] = why
    else:
        peer = stop_pendulum.build(e=e, phi0=phi0, t_end=t_end)
        for method in ("LSODA", "DOP853"):
            def run(tol, method=method):
                c0 = time.process_time()
                times, nfev, msg = peer.impact_times(method, tol, tol)
                cpu_s = time.process_time() - c0
                if msg:
                    return Try(tol, cpu_s, fail=msg[:80])
                err = err_of(times)
                if err is None:
                    return Try(tol, cpu_s, fail=f"{len(times)} impacts, {len(exact)} expected")
                return Try(tol, cpu_s, err, nfev)
            t, note, _ = sweep(run, 8, budget)
            rows.append(dict(who="pinocchio + scipy event loop", method=method, t=t, note=note))
            _log_row(log, "pinocchio + scipy event loop", method, t, note)

    def run_default(tol):
        res, cpu_s = _simulate(ev.pendulum(e=e, phi0=phi0), t_end=t_end, rtol=tol, atol=tol, n_out=101)
        if res.status != "success":
            return Try(tol, cpu_s, fail=f"{res.status}: {res.message[:80]}")
        err = err_of(ev.impacts(res))
        if err is None:
            return Try(tol, cpu_s, fail=f"{len(ev.impacts(res))} impacts, {len(exact)} expected")
        t = Try(tol, cpu_s, err, res.stats.get("nfev", math.nan))
        t.note = f"method {res.stats.get('method')}"
        return t
    rows += _default_rows(run_default, 8, budget, log,
                          warm_up=lambda: _simulate(ev.pendulum(e=e, phi0=phi0), t_end=0.1, n_out=101))
    return head, rows


# ------------------------------------------------------------------------------------------
def andrews(budget, repeats=3, log=print):
    """Andrews' squeezer: ``(header, rows)`` through ``bench/andrews.py``'s runners."""
    import mbcomp
    from mbcomp import workprecision as wp

    an = _bench_script("andrews")
    head = dict(case="andrews", what=f"Andrews' squeezer to t = {an.T_END} s, max relative angle error <= "
                f"{an.TARGET:g} (published reference); rtol swept, atol = rtol/100")
    mod = mbcomp.load_model_file(BENCH.parent / "models" / "andrews.py")
    _, values, _ = wp.reference_values(mod)
    names = list(values)
    ref = np.array([values[n] for n in names])
    tols = an.tolerances()
    rows = []

    def as_row(who, method, r):
        if "cpu_s" not in r:
            return dict(who=who, method=method, t=None, note=r["note"])
        return dict(who=who, method=method, t=Try(r["tol"], r["cpu_s"], r["error"], r["nfev"]), note="")

    quiet = lambda *a, **k: None  # noqa: E731 - the sweep's per-tolerance lines
    try:
        from . import sympy_andrews

        c0 = cpu()
        rhs, y0, _ = sympy_andrews.pydy_full("cython")
        head["peer_build_s"] = cpu() - c0
        r = an.sweep("pydy", an.peer_runner(rhs, y0, ref), tols, budget, repeats, quiet)
        rows.append(as_row("sympy Kane + pydy Cython", "DOP853", r))
    except Exception as exc:  # noqa: BLE001 - an optional peer (pydy, Cython, a compiler)
        rows.append(dict(who="sympy Kane + pydy Cython", method="DOP853", t=None,
                         note=f"not built: {type(exc).__name__}: {str(exc)[:80]}"))
    with fresh_cache():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            # warm: a call with the default grid makes the structure's programs, the output program
            # too (bench/fixed_cost.py's warm call); the timed calls then post-process by it
            mbcomp.simulate(mod.build(), t_end=an.T_END, rtol=1e-3, atol=1e-5)
        r = an.sweep("mbcomp", an.mbcomp_runner(mod, names, ref, {}), tols, budget, repeats, quiet)
        rows.append(as_row("mbcomp default call", "default", r))
    if rows[-1]["t"] is not None:
        with fresh_cache():
            cold = an.mbcomp_runner(mod, names, ref, {})(rows[-1]["t"].setting)
        rows.append(dict(who="mbcomp default call (cold cache)", method="default",
                         t=None if cold["fail"] else Try(rows[-1]["t"].setting, cold["cpu_s"], cold["error"],
                                                         cold["nfev"]), note=cold["fail"]))
    for r in rows:
        _log_row(log, r["who"], r["method"], r["t"], r["note"])
    return head, rows


# ------------------------------------------------------------------------------------------
def _exudyn_pendulum(budget, log, N=5, t_end=10.0):
    from . import exudyn_peers, mujoco_dop853, mujoco_pendulum, starts

    phi0, w0 = starts.start_state("curled", N)
    y0 = np.concatenate((phi0, w0))
    if mujoco_dop853.available() is None:
        c = mujoco_dop853.build_from_mjcf(mujoco_pendulum.mjcf(N))
        ref = c.integrate(y0, np.array([0.0, t_end]), 1e-13, 1e-13)[0][-1]
        ref_who = "MuJoCo + C DOP853 at 1e-13"
    else:
        from . import pinocchio_pendulum

        p = pinocchio_pendulum.build(N)
        ref = solve_ivp(p.rhs, (0, t_end), y0, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
        ref_who = "Pinocchio + scipy DOP853 at 1e-13"
    peer, rows = exudyn_peers.pendulum(N, phi0, w0, t_end=t_end), []
    for solver in ("DOPRI5",):  # its error-controlled explicit solver of the highest order
        def run(tol, solver=solver):
            try:
                cpu_s, y = peer.run(tol, solver)
            except Exception as exc:  # noqa: BLE001 - Exudyn's SolverError
                return Try(tol, math.nan, fail=str(exc)[:80])
            return Try(tol, cpu_s, float(np.max(np.abs(y - ref))))
        t, note, _ = sweep(run, 12, budget)
        rows.append(dict(who=f"exudyn pendulum N = {N}", method=solver, t=t, note=note))
        _log_row(log, rows[-1]["who"], solver, t, note)
    names = [f"joint{k + 1}.phi" for k in range(N)] + [f"joint{k + 1}.w" for k in range(N)]
    mod = __import__("mbcomp").load_model_file(BENCH.parent / "models" / "n_link_pendulum.py")

    def run_default(tol):
        res, cpu_s = _simulate(mod.build(N=N, phi0=phi0, w0=w0), t_end=t_end, rtol=tol, atol=tol, n_out=2)
        if res.status != "success":
            return Try(tol, cpu_s, fail=res.message[:80])
        return Try(tol, cpu_s, float(np.max(np.abs(np.array([res[n][-1] for n in names]) - ref))), res.stats["nfev"])
    for r in _default_rows(run_default, 12, budget, log, warm_up=lambda: run_default(1e-3)):
        r["who"] = r["who"].replace("mbcomp default call", f"mbcomp default call, pendulum N = {N}")
        rows.append(r)
    return ref_who, rows


def _exudyn_slider_crank(budget, log, t_end=10.0, target=1e-4):
    import mbcomp

    from . import exudyn_peers

    mod = mbcomp.load_model_file(BENCH.parent / "models" / "slider_crank.py")
    names = ("crank_joint.phi", "slider_joint.s", "crank_joint.w", "slider_joint.v")

    def end(tol, method="auto"):
        res, cpu_s = _simulate(mod.build(), t_end=t_end, rtol=tol, atol=tol, n_out=2, method=method)
        return res, cpu_s, (np.array([res[n][-1] for n in names]) if res.status == "success" else None)
    ref = end(1e-13, "dop853")[2]
    ref12 = end(1e-12, "dop853")[2]
    log(f"  slider-crank reference (mbcomp dop853 1e-13) moves {np.max(np.abs(ref - ref12)):.0e} vs 1e-12")
    peer, rows, best = exudyn_peers.slider_crank(t_end=t_end), [], None
    for steps in (1000, 3000, 10000, 30000, 100000, 200000, 300000, 1000000):
        try:
            cpu_s, y = peer.run(steps)
        except Exception as exc:  # noqa: BLE001 - Exudyn's SolverError
            best = None, f"failed with {steps} steps: {str(exc)[:60]}"
            break
        err = float(np.max(np.abs(y - ref)))
        log(f"    exudyn slider-crank generalized-alpha {steps:>8} steps  err {err:.1e}  {cpu_s:.3f} s")
        if err <= target:
            t = Try(t_end / steps, cpu_s, err, steps)
            t.note = f"{steps} steps (h = {t_end / steps:.0e} s)"
            best = t, ""
            break
        if cpu_s > budget / 3:
            best = None, f"error {err:.0e} with {steps} steps ({cpu_s:.1f} s): more steps over the budget"
            break
    t, note = best if best else (None, "no step count reached the target")
    rows.append(dict(who="exudyn slider-crank", method="gen-alpha", t=t, note=note or t.note))

    def run_default(tol):
        res, cpu_s, y = end(tol)
        if y is None:
            return Try(tol, cpu_s, fail=res.message[:80])
        return Try(tol, cpu_s, float(np.max(np.abs(y - ref))), res.stats["nfev"])
    for r in _default_rows(run_default, 8, budget, log, target=target, warm_up=lambda: end(1e-3)):
        r["who"] = r["who"].replace("mbcomp default call", "mbcomp default call, slider-crank")
        rows.append(r)
    return rows


def exudyn(budget, log=print):
    """Exudyn on the pendulum chain (N = 5, curled, 10 s, 1e-8 at t_end) and the slider-crank
    (10 s, 1e-4 at t_end): ``(header, rows)``."""
    from . import exudyn_peers

    head = dict(case="exudyn", what="Exudyn's own solvers: pendulum N = 5 (curled, 10 s, max state error at t_end "
                f"<= {TARGET:g}); slider-crank (10 s, max error of crank angle, slider position and their rates at "
                "t_end <= 1e-4: Exudyn's generalized-alpha stalls near 7e-6 at 1e6 steps; reference mbcomp dop853 1e-13); error at t_end only (Exudyn writes no dense output)")
    why = exudyn_peers.available()
    if why:
        head["note"] = why
        return head, []
    ref_who, rows = _exudyn_pendulum(budget, log)
    head["what"] += f"; pendulum reference {ref_who}"
    rows += _exudyn_slider_crank(budget, log)
    return head, rows


# ------------------------------------------------------------------------------------------
def chain3d(budget, log=print, Ns=(5, 10)):
    """End to end on ``peers/chain3d.py``'s 3-D chain (hinges about x, y, z in turn, every joint
    at 0.3 rad, at rest) to 1e-8 on 101 points: Pinocchio + scipy LSODA / DOP853, MuJoCo + C
    DOP853 and the default call, warm and cold. ``(header, rows)``."""
    import mbcomp
    from mbcomp.formulations import LagrangeIndex1
    from mbcomp.initialization import initialize

    from . import chain3d as c3, chain3d_mujoco, mujoco_dop853, starts

    head = dict(case="chain3d", what="3-D chain (hinges about x, y, z in turn; all at 0.3 rad, at rest), max state "
                f"error <= {TARGET:g} on 101 points over the longest of {starts.T_ENDS} s measurable")
    why = c3.available()
    if why:
        head["note"] = why
        return head, []
    rows = []
    for N in Ns:
        y0 = np.concatenate((np.full(N, 0.3), np.zeros(N)))
        build = lambda N=N: c3.build_model(N, phi0=0.3, w0=0.0)  # noqa: E731
        pin = c3.build(N)
        construct = (mujoco_dop853.build_from_mjcf(chain3d_mujoco.mjcf(N)) if mujoco_dop853.available() is None
                     else None)
        system = mbcomp.assemble(build())
        initialize(system, 0.0)
        yc = y0 + np.linspace(0.05, 0.4, 2 * N)
        mine = np.asarray(LagrangeIndex1(system).fun(0.0, yc))[N:]
        peers = {}
        for who, rhs in (("pinocchio", pin.rhs), ("mujoco + C DOP853", construct and construct.rhs)):
            if rhs is None:
                continue
            d = float(np.max(np.abs(np.asarray(rhs(0.0, yc))[N:] - mine)) / np.max(np.abs(mine)))
            if d <= TARGET:
                peers[who] = rhs
            else:
                rows.append(dict(who=f"{who}, N = {N}", method="-", t=None, note=f"du/dt differs by {d:.1e}: not timed"))
        t_end, grid, ref, qual, ref_who = starts.reference(pin.rhs, construct if "mujoco + C DOP853" in peers else None,
                                                           y0, N)
        if t_end is None:
            rows.append(dict(who=f"all, N = {N}", method="-", t=None, note=f"not measurable (reference moves {qual:.0e})"))
            continue
        log(f"  chain3d N = {N}: {t_end:g} s (reference {ref_who}, moves {qual:.0e} vs 1e-12)")
        for method in ("LSODA", "DOP853"):
            if "pinocchio" in peers:
                t, note, _ = sweep(starts.peer_run(pin.rhs, method, y0, grid, ref), 12, budget)
                rows.append(dict(who=f"pinocchio, N = {N}", method=method, t=t, note=note))
                _log_row(log, rows[-1]["who"], method, t, note)
        if "mujoco + C DOP853" in peers:
            t, note, _ = sweep(starts.construct_run(construct, y0, grid, ref), 12, budget)
            rows.append(dict(who=f"mujoco + C DOP853, N = {N}", method="dop853", t=t, note=note))
            _log_row(log, rows[-1]["who"], "dop853", t, note)
        run = starts.default_run(build, N, t_end, grid, ref)
        for r in _default_rows(run, 12, budget, log, warm_up=lambda: run(1e-3)):
            r["who"] = r["who"].replace("mbcomp default call", f"mbcomp default call, N = {N}")
            rows.append(r)
        head[f"t_end_{N}"] = t_end
    return head, rows
