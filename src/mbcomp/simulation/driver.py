"""``simulate``: assemble, initialize, integrate, post-process.

The driver owns the stepping loop over a stepper: a ``scipy.integrate`` ``OdeSolver`` (any
of ``RK23, RK45, DOP853, Radau, BDF, LSODA``) for the ODE forms, or one of mbcomp's DAE
solvers (:data:`mbcomp.solvers.SOLVERS`: ``radau5``, ``ida``, ``genalpha``) for the
multiplier form kept as a DAE of index 1, 2 (GGL) or 3 (:mod:`mbcomp.daeforms`). Which
solver accepts which form is read from the solver's declared capabilities. The driver
interpolates outputs with the solver's dense output, applies projection after accepted
steps, shows a progress bar on request, and turns every failure into a ``Result`` with
``status="failed"`` and a message naming the cause (results up to the failure are kept).

Projection and the solvers' memory: one-step methods (RK23, RK45, DOP853, Radau) continue
from the projected state after every step (their stored derivative is refreshed); the
multistep methods (BDF, LSODA) are restarted from the projected state when the correction
exceeds their tolerance, because their history cannot be projected.

Examples
--------
>>> import mbcomp
>>> from mbcomp.library import World, Prismatic, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> s = m.add("slide", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=1.0))
>>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> r = mbcomp.simulate(m, t_end=1.0, rtol=1e-10, atol=1e-12)
>>> round(float(r["slide.s"][-1]), 6)   # free fall: -g t^2 / 2
-4.905
"""
from __future__ import annotations

import time as _time

import numpy as np
import scipy.integrate as si

from ..formulations.dae import DAE_FORMS, Mechanical
from ..errors import SimulationError
from ..formulations.lagrange import DAlembert, LagrangeIndex1
from ..assembly.initialization import initialize
from ..simulation.result import Result, postprocess
from ..assembly.system import MultibodySystem
from ..assembly.system import MultibodySystem, assemble

__all__ = ["simulate", "METHODS", "FORMULATIONS", "ALL_METHODS"]

FORMULATIONS = ("lagrange", "dalembert")

METHODS = {"RK23": si.RK23, "RK45": si.RK45, "DOP853": si.DOP853, "Radau": si.Radau, "BDF": si.BDF, "LSODA": si.LSODA}
_ONE_STEP = {"RK23", "RK45", "DOP853", "Radau", "radau5", "genalpha"}
ALL_METHODS = tuple(METHODS) + ("radau5", "ida", "genalpha")


def _solvers():
    from ..solvers import SOLVERS  # imported on use: keeps "import mbcomp" light

    return SOLVERS


def simulate(model, t_end=1.0, *, t_start=0.0, params=None, method="RK45", rtol=1e-6, atol=1e-8,
             formulation="lagrange", stabilization="baumgarte", alpha=10.0, beta=10.0, n_out=None, dt_out=None,
             max_step=np.inf, progress=False, independent=None, index=None, h=None,
             backend="numeric") -> Result:
    """Simulate a model: Lagrange multipliers at index 1, or D'Alembert projection to an ODE.

    Parameters
    ----------
    model : Model or MultibodySystem
    t_end, t_start : float
        Time span in s.
    params : dict, optional
        Runtime parameter values ``{"component.param": value}`` (nothing is re-derived).
    method : str
        A ``scipy.integrate.solve_ivp`` method name (ODE forms: Lagrange at index 1 and
        D'Alembert), or a DAE solver of :mod:`mbcomp.solvers`: ``"radau5"`` (Radau IIA order
        5, index 1-3, index-aware error control), ``"ida"`` (SUNDIALS IDA, index 1 and 2) or
        ``"genalpha"`` (generalized-alpha, index 3, fixed step ``h``).
    rtol, atol : float
        Integrator tolerances (the Newton tolerance of ``genalpha``).
    index : {1, 2, 3}, optional
        Lagrange formulation with a DAE solver: the constraints at acceleration level (1),
        velocity level with position correction (2, GGL) or position level (3). Default 1
        (3 for ``genalpha``). scipy methods integrate the index-1 ODE only.
    h : float, optional
        Step size (s) of fixed-step methods (``genalpha``); required there.
    backend : {"numeric", "python", "c", "auto"}
        ``"numeric"`` evaluates the jets directly (no set-up cost). The others trace the
        model once into a generated straight-line program (:mod:`mbcomp.codegen`): Python
        (no compiler), C (system compiler, cached on disk) or C when a compiler exists. The
        program is ~10-20x faster per evaluation for small and mid-size models and costs a
        generation time growing like N^3 (see ``bench/scaling.py``).
    formulation : {"lagrange", "dalembert"}
        ``"lagrange"``: multipliers, index 1 (:class:`~mbcomp.formulations.LagrangeIndex1`);
        ``"dalembert"``: projection onto independent speeds, a minimal ODE whose positions are
        corrected onto the constraint manifold after every step
        (:class:`~mbcomp.formulations.DAlembert`; ``stabilization`` does not apply).
    stabilization : {"baumgarte", "projection", "none"}
        Constraint stabilization of the Lagrange formulation (see :mod:`mbcomp.formulations`).
    alpha, beta : float
        Baumgarte parameters (1/s).
    n_out, dt_out : int, float, optional
        Output grid: ``n_out`` points or a step ``dt_out`` (default 501 points).
    independent : list of str, optional
        D'Alembert only: speed names to start with as independent (re-chosen automatically
        when they become ill-conditioned).
    progress : bool
        Show a progress bar (tqdm) when the run lasts more than two seconds.

    Returns
    -------
    Result
    """
    if method not in ALL_METHODS:
        raise ValueError(f"method {method!r} is unknown; use one of {', '.join(ALL_METHODS)}")
    if formulation not in FORMULATIONS:
        raise ValueError(f"formulation {formulation!r} is unknown; use one of {', '.join(FORMULATIONS)}")
    index = _check_method(method, formulation, index, stabilization, h)
    if not t_end > t_start:
        raise ValueError(f"t_end ({t_end}) must be greater than t_start ({t_start})")
    if backend not in ("numeric", "python", "c", "auto"):
        raise ValueError(f"backend {backend!r} is unknown; use 'numeric', 'python', 'c' or 'auto'")
    system = model.with_params(params) if isinstance(model, MultibodySystem) and params else (
        model if isinstance(model, MultibodySystem) else assemble(model, params))
    if backend != "numeric":
        from ..codegen.program import CompiledSystem, compile_system

        if not isinstance(system, CompiledSystem):
            system = compile_system(system, backend)
    init = initialize(system, t_start)
    if formulation == "dalembert":
        form = DAlembert(system, independent=independent)
        y0 = form.initial_state(t_start, init.q, init.u)
    elif method in METHODS:
        form = LagrangeIndex1(system, stabilization, alpha, beta)
        y0 = np.concatenate((init.q, init.u))
    else:
        if _solvers()[method].problem == "mechanical":
            form = Mechanical(system)
        elif index == 1:
            form = DAE_FORMS[1](system, stabilization, alpha, beta)
        else:
            form = DAE_FORMS[index](system)
        y0 = form.initial_state(t_start, init.q, init.u)
    if dt_out is not None:
        t_out = np.arange(t_start, t_end + 0.5 * dt_out, dt_out)
        t_out[-1] = min(t_out[-1], t_end)
    else:
        t_out = np.linspace(t_start, t_end, n_out or 501)
    wall0 = _time.perf_counter()
    ys, status, message, stats = _integrate(form, y0, t_start, t_end, t_out, method, rtol, atol, max_step, progress, h)
    wall = _time.perf_counter() - wall0
    stats.update(nfev=form.nfev, nlu=form.nlu + stats.pop("nlu_solver", 0), cpu_time=wall, method=method,
                 formulation=formulation, index=index, backend=backend,
                 stabilization=form.stabilization, projected_rows_dropped=list(init.dropped),
                 init_iterations=init.iterations)
    if formulation == "dalembert":
        stats.update(repartitions=form.repartitions, independent_speeds=[system.u_names[i] for i in form.ind])
    t_done = t_out[: len(ys)]
    return postprocess(system, form, t_done, np.array(ys).reshape(len(ys), -1), status, message, stats, init)


def _check_method(method, formulation, index, stabilization, h):
    """The DAE index to use; a clear error when the method cannot step the requested form."""
    if index not in (None, 1, 2, 3):
        raise ValueError(f"index={index!r} is unknown; use 1 (acceleration level), 2 (GGL) or 3 (position level)")
    if method in METHODS:
        if index not in (None, 1):
            raise ValueError(f"method {method!r} integrates ODEs: the index-{index} form is a DAE -> use "
                             "method='radau5' (index 1-3), 'ida' (index 1-2) or 'genalpha' (index 3)")
        return 1 if formulation == "lagrange" else None
    cls = _solvers()[method]
    if formulation == "dalembert":
        raise ValueError(f"formulation='dalembert' is an ODE in the independent speeds; method {method!r} is a DAE "
                         "solver -> use a scipy method (RK45, DOP853, Radau, BDF, LSODA) or formulation='lagrange'")
    if index is None:
        index = 3 if cls.problem == "mechanical" else 1
    if index > cls.max_index:
        raise ValueError(f"method {method!r} handles DAEs of index <= {cls.max_index}; index={index} was requested "
                         f"-> use index<={cls.max_index} or method='radau5' (index 1-3)")
    if cls.problem == "mechanical" and index != 3:
        raise ValueError(f"method {method!r} steps the index-3 (position-level) form only -> use index=3")
    if not cls.adaptive and not h:
        raise ValueError(f"method {method!r} uses a fixed step: give the step size h (s), e.g. h=1e-4")
    return index


def _integrate(form, y0, t0, t1, t_out, method, rtol, atol, max_step, progress, h=None):
    fun = getattr(form, "fun", None)
    sysm = form.system
    proj = form.stabilization == "projection" and bool(sysm.topology.cut or sysm.nq != sysm.nu or sysm._nonholonomic)
    if isinstance(form, DAlembert):
        proj = bool(sysm.topology.cut or sysm.nq != sysm.nu)
    y = form.project(t0, y0) if proj else y0
    full = getattr(form, "full", lambda t, yy: yy)
    repartition = hasattr(form, "needs_repartition")
    ys = [full(t0, y).copy()]
    k = 1
    stats = dict(steps=0, restarts=0, projections=0)
    watch = _SingularityWatch(sysm, atol)

    solvers = []

    def make(t, y):
        if method in METHODS:
            solvers.append(METHODS[method](fun, t, y, t1, rtol=rtol, atol=atol, max_step=max_step))
        else:
            solvers.append(_solvers()[method](form, t, y, t1, rtol=rtol, atol=atol, first_step=h, max_step=max_step))
        return solvers[-1]

    bar = None
    status, message = "success", "reached t_end"
    try:
        solver = make(t0, y)
        if progress:
            from tqdm.auto import tqdm

            bar = tqdm(total=float(t1 - t0), unit="s sim", delay=2.0, leave=False, disable=None,
                       bar_format="{l_bar}{bar}| {n:.3g}/{total:.3g} s [{elapsed}<{remaining}]")
        while k < len(t_out):
            if solver.status != "running":
                break
            t_prev = solver.t
            msg = solver.step()
            if solver.status == "failed":
                if method not in METHODS:  # mbcomp steppers name the cause themselves
                    raise SimulationError(msg)
                raise SimulationError(f"the integrator {method} failed at t={solver.t:g}: {msg} "
                                      "(step size collapsed: stiff or singular dynamics, or tolerances too tight)")
            stats["steps"] += 1
            if solver.t == t_prev:
                continue
            dense = solver.dense_output()
            try:  # before this step's outputs are kept
                watch.check(solver.t, full(solver.t, solver.y), t_prev, lambda tt, d=dense: full(tt, d(tt)))
            except _Singular as exc:  # drop outputs already kept past the singular position
                while len(ys) > 1 and t_out[len(ys) - 1] > exc.t:
                    ys.pop()
                k = len(ys)
                raise SimulationError(str(exc)) from None
            while k < len(t_out) and t_out[k] <= solver.t:
                yk = dense(t_out[k])
                ys.append(full(t_out[k], form.project(t_out[k], yk) if proj else yk))
                k += 1
            if proj:
                yp = form.project(solver.t, solver.y)
                stats["projections"] += 1
                if method in _ONE_STEP:
                    if method in METHODS:  # scipy: refresh the stored derivative
                        solver.y = yp
                        if hasattr(solver, "f"):
                            solver.f = fun(solver.t, yp)
                    else:
                        solver.reset_state(yp)
                else:
                    scale = atol + rtol * np.abs(yp)
                    if np.max(np.abs(yp - solver.y) / scale) > 1.0:
                        solver = make(solver.t, yp)
                        stats["restarts"] += 1
            if repartition and form.needs_repartition(solver.t, solver.y):
                solver = make(solver.t, form.repartition(solver.t, solver.y))
                stats["restarts"] += 1
            if bar is not None:
                bar.update(float(solver.t - t_prev))
    except SimulationError as exc:
        status, message = "failed", str(exc)
    except np.linalg.LinAlgError as exc:
        status, message = "failed", f"linear algebra failure: {exc}"
    finally:
        if bar is not None:
            bar.close()
    if watch.active:
        stats["min_constraint_sigma"] = watch.sigma_min
    if method in METHODS:
        stats["njev"] = int(sum(getattr(s, "njev", 0) for s in solvers))
        stats["nlu_integrator"] = int(sum(getattr(s, "nlu", 0) for s in solvers))
    else:  # mbcomp steppers count their own work
        for key in ("nreject", "njev", "nlu", "nnewton"):
            stats[key if key != "nlu" else "nlu_solver"] = int(sum(s.stats.get(key, 0) for s in solvers))
        stats["nlu_integrator"] = stats.get("nlu_solver", 0)
    return ys, status, message, stats


class _Singular(Exception):
    def __init__(self, msg, t):
        super().__init__(msg)
        self.t = t


class _SingularityWatch:
    """Checks, at every accepted step of a model with loops, what the formulations cannot see.

    * Rows dropped as redundant at the start (``system.row_mask``) must stay satisfied: a row
      that is dependent only at the start position (a four-bar started flat, a slider-crank
      started at a dead centre with a loop that closes there by coincidence) is a singular
      start, and the loop would otherwise open silently.
    * Joints that know where their own equations break down (``Joint.singularity``: a rolling
      disk lying flat) report their distance from it; below ``JOINT_MIN`` the run fails with
      the joint's reason, and a local minimum of step-end distances below ``JOINT_BRACKET`` is
      located along the dense output (a disk falling through flat between two steps).
    * The smallest relative singular value of the kept constraint Jacobian is tracked
      (``stats["min_constraint_sigma"]``: how close the run came to a singular position) and a
      value at rounding level is reported as a singular position. A solver may step *over* a
      singular position (BDF and fixed-step methods at a flat four-bar did, then followed
      another branch): when the step-end values have a local minimum below ``BRACKET``, the
      minimum is located along the dense output of the two steps around it.
    """

    BRACKET = 1e-2

    SIGMA_MIN = 1e-6  # a four-bar 1e-8 m from flat: 4e-5; passing exactly through flat: <= 1.6e-7

    JOINT_MIN = 1e-3  # a joint's own distance from where its equations break down (a flat disk)
    JOINT_BRACKET = 0.1

    def __init__(self, system, atol):
        self.system = system
        mask = system.row_mask
        self.joints = [e for e in system.topology.edges if e.kind == "joint" and e.comp.has_singularity]
        self.active = bool(system.topology.cut) or bool(self.joints)
        self._jhist = []  # (t_start, t_end, {joint: distance} at t_end, dense) of the last two steps
        self.dropped = None if mask is None or mask.all() else ~mask
        self.tol = 1e-6 + 1e3 * float(np.max(atol))
        self.sigma_min = 1.0
        self._hist = []  # (t_start, t_end, sigma at t_end, dense) of the last two steps

    def _sigma(self, ev):
        C = ev.C if self.dropped is None else ev.C[~self.dropped]
        if not C.shape[0]:
            return 1.0
        sv = np.linalg.svd(C, compute_uv=False)
        if not (sv.size and sv[0] > 0):
            return 1.0
        return float(sv[-1] / sv[0]) if sv.size == C.shape[0] else 0.0

    def _singular(self, t, rel):
        return _Singular(
            f"the mechanism reached a singular position at t={t:g}: the constraint Jacobian lost "
            f"rank (smallest relative singular value {rel:.2g}); beyond it the motion is not unique "
            "(a flat or dead-centre position) -> change the geometry or the start so it is avoided", t)

    def _locate(self):
        """Minimize sigma along the dense output of the last two steps (bounded scalar search)."""
        from scipy.optimize import minimize_scalar

        (a0, a1, _, da), (b0, b1, _, db) = self._hist
        sysm = self.system

        def sig(tt):
            qu = da(tt) if tt <= a1 else db(tt)
            q, u = qu[: sysm.nq], qu[sysm.nq: sysm.nq + sysm.nu]
            return self._sigma(sysm.evaluate(tt, sysm.normalize(q), u, masked=False))

        r = minimize_scalar(sig, bounds=(a0, b1), method="bounded", options=dict(xatol=1e-12 * max(1.0, abs(b1))))
        return float(r.x), float(r.fun)

    def _joint_distances(self, t, q, u):
        sysm = self.system
        jets = MultibodySystem.kinematics(sysm, t, q, u)
        out = {}
        for e in self.joints:
            d = e.comp.singularity(jets[e.node_a], jets[e.node_b], sysm.P[e.name])
            if d is not None:
                out[e.name] = d
        return out

    def _joint_failure(self, name, t, dist):
        e = self.system.topology.edge(name)
        return _Singular(f"{name}: {e.comp.singularity_reason} at t={t:g} (distance {dist:.2g}); beyond it the "
                         f"motion is not defined -> {e.comp.singularity_fix}", t)

    def _check_joints(self, t, q, u, t_prev, dense):
        dist = self._joint_distances(t, q, u)
        for name, d in dist.items():
            if d < self.JOINT_MIN:
                raise self._joint_failure(name, t, d)
        if dense is None:
            return
        self._jhist = (self._jhist + [(t_prev, t, dist, dense)])[-3:]
        if len(self._jhist) < 3:
            return
        (_, _, d0, _), (a0, a1, d1, da), (_, b1, d2, db) = self._jhist
        sysm = self.system
        from scipy.optimize import minimize_scalar

        for name in d1:
            v0, v1, v2 = d0.get(name, np.inf), d1[name], d2.get(name, np.inf)
            if not (v1 < v0 and v1 < v2 and v1 < self.JOINT_BRACKET):
                continue

            def dist_at(tt, name=name):
                qu = da(tt) if tt <= a1 else db(tt)
                qq, uu = sysm.normalize(qu[: sysm.nq]), qu[sysm.nq: sysm.nq + sysm.nu]
                return self._joint_distances(tt, qq, uu).get(name, np.inf)

            r = minimize_scalar(dist_at, bounds=(a0, b1), method="bounded",
                                options=dict(xatol=1e-12 * max(1.0, abs(b1))))
            if r.fun < self.JOINT_MIN:
                raise self._joint_failure(name, float(r.x), float(r.fun))

    def check(self, t, qu, t_prev=None, dense=None):
        if not self.active:
            return
        sysm = self.system
        q, u = qu[: sysm.nq], qu[sysm.nq: sysm.nq + sysm.nu]
        if self.joints:
            self._check_joints(t, q, u, t_prev, dense)
        if not sysm.topology.cut:
            return
        ev = sysm.evaluate(t, q, u, masked=False)
        if self.dropped is not None and ev.Phi.size:
            bad = np.abs(ev.Phi[self.dropped])
            if bad.size and bad.max() > self.tol:
                names = [n for n, d in zip(sysm.constraint_names(all_rows=True), self.dropped) if d]
                worst = names[int(np.argmax(bad))]
                raise SimulationError(
                    f"the constraint row {worst} was dropped at the start as redundant (dependent on the "
                    f"others there) but is violated by {bad.max():.3g} at t={t:g}: the start position is "
                    "singular (a flat or dead-centre position where the loop's rank drops) -> start the "
                    "mechanism away from it (change the fixed start values)")
        rel = self._sigma(ev)
        self.sigma_min = min(self.sigma_min, rel)
        if rel < self.SIGMA_MIN:
            raise self._singular(t, rel)
        if dense is None:
            return
        prev = self._hist[-1][2] if self._hist else None
        self._hist = (self._hist + [(t_prev, t, rel, dense)])[-2:]
        if len(self._hist) == 2 and prev is not None:
            s0 = self._hist[0][2]
            older = getattr(self, "_s_older", None)
            if older is not None and s0 < older and s0 < rel and s0 < self.BRACKET:
                ts, smin = self._locate()
                self.sigma_min = min(self.sigma_min, smin)
                if smin < self.SIGMA_MIN:
                    raise self._singular(ts, smin)
        self._s_older = prev
