"""End to end from three start states: the N-link pendulum's figure of ``bench/peers.py``.

The model's own start (every hinge at 0.3 rad, at rest: a curled chain falling) is one of
three; the others are chosen not to favour anyone:

* ``curled``: ``phi_k = 0.3``, ``w_k = 0`` (``models/n_link_pendulum.py``'s default);
* ``low swing``: ``phi_k = 0.1 sin(1.7 k)``, ``w_k = 0`` (small irregular angles: nearly
  linear motion, many frequencies);
* ``thrown``: ``phi_1 = 0.5``, other angles 0, ``w_k = cos(2.3 k)`` rad/s (every rate
  different, more energy in the lower links).

For each start and N: the reference is the C DOP853 over MuJoCo (or Pinocchio's rhs in
scipy's DOP853 without it) at rtol = atol = 1e-13; the simulated time is the longest of
``T_ENDS`` over which it moves by at most 1e-9 against the same at 1e-12 (the chain's motion
is chaotic: 10 s from the curled start is not measurable to 1e-8 at N = 20). Rows: scipy
LSODA and DOP853 on Pinocchio's ``rhs``, scipy DOP853 on MuJoCo's ``mj_forward``, MuJoCo +
C DOP853 (:mod:`peers.mujoco_dop853`), and mbcomp's default call
``mbcomp.simulate(model, t_end, rtol=tol, atol=tol, n_out=101)`` from the Model, its cache
warm, and the same first call in an empty cache (cold: tracing and the compiler included);
the header's ``fixed_s`` is the warm default call over 1 us of motion (:func:`fixed_cost`).
Each is the cheapest tolerance (half decades) within 1e-8 max state error on 101 points.
"""
import math
import time
import warnings

import numpy as np
from scipy.integrate import solve_ivp

from . import mujoco_dop853, mujoco_pendulum, pinocchio_pendulum
from .cpu_clock import cpu
from .timing import Try, fresh_cache, sweep

__all__ = ["STARTS", "start_state", "run_case", "T_ENDS", "peer_run", "construct_run", "default_run", "reference", "fixed_cost"]

STARTS = ("curled", "low swing", "thrown")
T_ENDS = (10.0, 5.0, 2.0, 1.0, 0.5)
TARGET, N_OUT, AGREE = 1e-8, 101, 1e-8


def start_state(name, N):
    """``(phi0, w0)`` arrays (rad, rad/s) of the start ``name`` for N links."""
    k = np.arange(1, N + 1)
    if name == "curled":
        return np.full(N, 0.3), np.zeros(N)
    if name == "low swing":
        return 0.1 * np.sin(1.7 * k), np.zeros(N)
    if name == "thrown":
        phi = np.zeros(N)
        phi[0] = 0.5
        return phi, np.cos(2.3 * k)
    raise ValueError(f"unknown start {name!r}: one of {STARTS}")


def peer_run(rhs, method, y0, grid, ref):
    def run(tol):
        count = [0]

        def f(t, y):
            count[0] += 1
            return rhs(t, y)

        c0 = time.process_time()
        sol = solve_ivp(f, (grid[0], grid[-1]), y0, method=method, rtol=tol, atol=tol, t_eval=grid)
        cpu_s = time.process_time() - c0
        if not sol.success or sol.y.shape[1] != len(grid):
            return Try(tol, cpu_s, fail=f"solve_ivp: {sol.message}")
        return Try(tol, cpu_s, float(np.max(np.abs(sol.y.T - ref))), count[0])
    return run


def construct_run(c, y0, grid, ref):
    def run(tol):
        c0 = time.process_time()
        try:
            Y, nfev = c.integrate(y0, grid, tol, tol)
        except RuntimeError as exc:
            return Try(tol, time.process_time() - c0, fail=str(exc)[:80])
        return Try(tol, time.process_time() - c0, float(np.max(np.abs(Y - ref))), nfev)
    return run


def default_run(build, N, t_end, grid, ref):
    names = [f"joint{k + 1}.phi" for k in range(N)] + [f"joint{k + 1}.w" for k in range(N)]

    def run(tol):
        model = build()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            c0 = cpu()
            res = __import__("mbcomp").simulate(model, t_end=t_end, rtol=tol, atol=tol, n_out=N_OUT)
            cpu_s = cpu() - c0
        if res.status != "success" or len(res.time) != len(grid):
            return Try(tol, cpu_s, fail=f"{res.status}: {res.message[:80]}")
        Y = np.column_stack([res[n] for n in names])
        t = Try(tol, cpu_s, float(np.max(np.abs(Y - ref))), res.stats.get("nfev", math.nan))
        t.note = f"method {res.stats.get('method')}" + (f", stiff from {res.stats['stiff_from']:.3g} s"
                                                         if "stiff_from" in res.stats else "")
        return t
    return run


def fixed_cost(build, repeats=5):
    """CPU s of the default call over 1 us of motion (warm cache): what a call costs before its
    integration (assembly, tracing or the cached library, initialization, outputs); median."""
    import mbcomp

    times = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(repeats):
            model = build()
            c0 = cpu()
            mbcomp.simulate(model, t_end=1e-6, n_out=N_OUT)
            times.append(cpu() - c0)
    return float(np.median(times))


def reference(rhs_ref, construct, y0, N):
    """``(t_end, grid, ref, quality, who)``: the longest of :data:`T_ENDS` over which the
    reference (``construct`` at rtol 1e-13, or ``rhs_ref`` in scipy's DOP853) moves by at most
    ``TARGET / 10`` against the same at 1e-12; ``t_end`` None when none does."""
    for t_end in T_ENDS:
        grid = np.linspace(0.0, t_end, N_OUT)
        if construct is not None:
            ref = construct.integrate(y0, grid, 1e-13, 1e-13)[0]
            ref12 = construct.integrate(y0, grid, 1e-12, 1e-12)[0]
            who = "MuJoCo + C DOP853"
        else:
            ref = solve_ivp(rhs_ref, (0, t_end), y0, method="DOP853", rtol=1e-13, atol=1e-13, t_eval=grid).y.T
            ref12 = solve_ivp(rhs_ref, (0, t_end), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=grid).y.T
            who = "Pinocchio + scipy DOP853"
        qual = float(np.max(np.abs(ref - ref12)))
        if qual <= TARGET / 10:
            return t_end, grid, ref, qual, who
    return None, None, None, qual, who


def run_case(model_module, phys, N, start, budget, log=print):
    """Every row of one (start, N): a list of dicts ``who, method, t (Try or None), note``, and
    a header dict (``t_end``, reference)."""
    phi0, w0 = start_state(start, N)
    y0 = np.concatenate((phi0, w0))
    pin = pinocchio_pendulum.build(N, **phys) if pinocchio_pendulum.available() is None else None
    mj = mujoco_pendulum.build(N, **phys) if mujoco_pendulum.available() is None else None
    why_c = mujoco_dop853.available()
    construct = mujoco_dop853.build_from_mjcf(mujoco_pendulum.mjcf(N, **phys)) if why_c is None else None
    build = lambda: model_module.build(N=N, **phys, phi0=phi0, w0=w0)  # noqa: E731
    # cross-check at the start against mbcomp's numeric right-hand side
    import mbcomp
    from mbcomp.formulations import LagrangeIndex1
    from mbcomp.initialization import initialize

    system = mbcomp.assemble(build())
    initialize(system, 0.0)
    yc = np.concatenate((phi0 + 0.1, w0 + 0.2))
    mine = np.asarray(LagrangeIndex1(system).fun(0.0, yc))[N:]
    peers = {}
    for who, rhs in (("pinocchio", pin and pin.rhs), ("mujoco", mj and mj.rhs),
                     ("mujoco + C DOP853", construct and construct.rhs)):
        if rhs is None:
            continue
        d = float(np.max(np.abs(np.asarray(rhs(0.0, yc))[N:] - mine)) / np.max(np.abs(mine)))
        if d <= AGREE:
            peers[who] = rhs
        else:
            log(f"  {who}: du/dt differs from mbcomp by {d:.1e} > {AGREE:g}: not timed")
    rows = []
    t_end, grid, ref, qual, ref_who = reference(pin.rhs if pin else None,
                                                  construct if "mujoco + C DOP853" in peers else None, y0, N)
    head = dict(start=start, N=N, t_end=t_end, ref=ref_who, quality=qual)
    if t_end is None:
        head["note"] = f"not measurable: the reference moves {qual:.0e} between 1e-12 and 1e-13 even over {T_ENDS[-1]} s"
        return head, rows
    log(f"  {start}, N = {N}: {t_end:g} s (reference {ref_who}, moves {qual:.0e} vs 1e-12)")

    def record(who, method, t, note):
        rows.append(dict(who=who, method=method, t=t, note=note or (t.note if t else "")))
        log(f"    {who:<30} {method:<8} " + (f"tol {t.setting:.0e} err {t.err:.1e} {t.cpu_s:8.4f} s" if t else note),
            flush=True)

    for who, method in (("pinocchio", "LSODA"), ("pinocchio", "DOP853"), ("mujoco", "DOP853")):
        if who in peers:
            t, note, _ = sweep(peer_run(peers[who], method, y0, grid, ref), 12, budget)
            record(who, method, t, note)
    if construct is not None and "mujoco + C DOP853" in peers:
        t, note, _ = sweep(construct_run(construct, y0, grid, ref), 12, budget)
        record("mujoco + C DOP853", "dop853", t, note)
    else:
        record("mujoco + C DOP853", "dop853", None, why_c or "disagrees with mbcomp: not timed")
    with fresh_cache():
        run = default_run(build, N, t_end, grid, ref)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            mbcomp.simulate(build(), t_end=0.01, n_out=N_OUT)  # fill the cache (the output program too)
        t, note, _ = sweep(run, 12, budget)
        record("mbcomp default call", "default", t, note)
        head["fixed_s"] = fixed_cost(build)
    if t is not None:
        with fresh_cache():  # the first call: tracing and the C compiler in the time
            cold = run(t.setting)
        record("mbcomp default call (cold cache)", "default", None if cold.fail else cold, cold.fail)
    return head, rows
