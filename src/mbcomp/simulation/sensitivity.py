"""Forward trajectory sensitivities ``S(t) = d[q, u](t) / dp`` integrated with a run.

``simulate(model, ..., sensitivities=["rod.m", "crank_joint.phi0"])`` integrates, next to the
states, the forward sensitivity equations of the Lagrange index-1 right-hand side
``fun(t, y, p)``::

    dS/dt = (d fun/dy) S + d fun/dp,        S(t0) = d y0 / dp

with exact derivatives from the generated programs (:mod:`mbcomp.codegen.sensitivity`).

**Two paths.** A smooth run (no events, not projected, an explicit method, a C program) is
integrated as usual, then ``[y, S]`` together from the start in one C call
(:class:`~mbcomp.codegen.sensitivity_engine.SensitivityIntegrator`: the runtime's DOP853, error
control over both at the run's tolerances; the run's own states are kept). Every other run
is *staggered*: after every accepted step the sensitivity equations are integrated over
that step, along the step's dense output ``y(t)``, by scipy's ``DOP853`` (explicit runs) or
``Radau`` (implicit runs, the Jacobian ``I (x) d fun/dy`` exact) with the run's ``rtol`` and
``atol``, and jumped at its events. Why not simultaneous there: the augmented state would
change the steps, and the hybrid layer's events, projections and repartitions would all have
to carry it; staggered, the states are bit for bit those of the same run without
sensitivities. The price: one dense-output evaluation of ``y`` per sensitivity stage, in
Python.

**Constraints.** With Baumgarte stabilization the sensitivity equations are those of the
stabilized right-hand side (its gains in ``fun``): the linearized constraint drift decays as
the states' does. A run that projects (``stabilization="projection"``, D'Alembert, the DAE
forms) integrates ``fun`` without gains and projects ``S`` after every step, and at every kept
output, onto the tangent of the constraint manifold: ``dPhi/dq S_q + dPhi/dp = 0``,
``d[Phid, Psi]/dy S + d[Phid, Psi]/dp = 0``, by minimum-norm corrections -- the derivative of
the projection the run applies to the state (:mod:`mbcomp.assembly.kkt`).

**The start.** ``S(t0)`` is the derivative of the consistent initial state: a start value a
user fixed (``crank_joint.phi0=0.3``) moves its coordinate; the free coordinates and speeds
follow by the implicit function theorem on ``Phi = 0`` and ``[Phid, Psi] = 0`` (the minimum-norm
solution, as the initialization's Gauss-Newton); a ``Guess`` is free, so its sensitivity is zero.

**Events.** At an event at ``tau`` with event function ``g`` and the state after the action
``y+ = R(y-, p)`` (an impact's impulse map, or the identity), the sensitivities jump by the
standard conditions of hybrid systems::

    dtau/dp = -(g_y S- + g_p) / (g_y f-)
    S+ = R_y S- + R_p + (R_y f- - f+) dtau/dp

``g`` and ``R`` are the hybrid layer's own (:meth:`mbcomp.hybrid.events.Events.event_value`,
:meth:`~mbcomp.hybrid.events.Events.reset`); their derivatives along each column ``(S-_j, e_j)``
are central differences of the combined perturbation (states moved by ``eps S-_j``, the
parameter by ``eps`` in a copy of the system), accurate to about ``1e-9`` relative: ``g``
and ``R`` are evaluated numerically (not traced). A segment in which rows are held by a
mode (a stop engaged, a ball come to rest, a stuck friction, a sliding contact) is not
covered: the sensitivities end at its start and ``res.sensitivity`` says so.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.1)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> r = mbcomp.simulate(m, t_end=1.0, rtol=1e-10, atol=1e-12, sensitivities=["j.phi0", "bob.m"])
>>> s = r.sensitivity("j.phi", "j.phi0")    # small swings: phi = phi0 cos(sqrt(g/l) t)
>>> bool(abs(s[-1] - np.cos(np.sqrt(9.81))) < 2e-3), float(np.abs(r.sensitivity("j.phi", "bob.m")).max())
(True, 0.0)
"""
from __future__ import annotations


import numpy as np

from ..codegen.graph import CodegenError
from ..codegen.sensitivity import SensitivityCode, parameter_ref
from ..codegen.sensitivity_engine import SensitivityIntegrator
from ..assembly.kkt import project_state, solve_kkt
from ..errors import SimulationError
from .sensitivity_start import differenced_start, free_start, rate_map
from .sensitivity_events import Jump, moved_params, with_value
from .sensitivity_table import SensitivityTable
from .stepping import StepHook

__all__ = ["Sensitivities", "check_sensitivities", "initial_sensitivities"]

#: relative step of the central differences of a held segment's right-hand side (about the
#: cube root of the rounding error: truncation and rounding both near 1e-11 relative)
HELD_STEP = 6e-6
#: the sensitivities' tolerance in a held segment is at least this: its differenced right-hand
#: side is accurate to about 1e-10 relative, and an error control below that rejects steps over
#: rounding (at rtol 1e-12 a pendulum held on its stop took 480 steps for 34 of the run's)
HELD_RTOL = 1e-9


def check_sensitivities(names):
    """The requested parameter names as a list of str (a ``ValueError`` for anything else:
    not a str or a list of str, empty, or a name given twice); None stays None.

    Examples
    --------
    >>> from mbcomp.simulation.sensitivity import check_sensitivities
    >>> check_sensitivities("rod.m"), check_sensitivities(("rod.m", "crank_joint.phi0"))
    (['rod.m'], ['rod.m', 'crank_joint.phi0'])
    """
    if names is None:
        return None
    if isinstance(names, str):
        names = [names]
    names = list(names)
    if not names or not all(isinstance(n, str) for n in names):
        raise ValueError(f"sensitivities={names!r}: give a list of parameter names, e.g. ['rod.m', 'crank_joint.phi0']")
    if len(set(names)) != len(names):
        raise ValueError(f"sensitivities={names!r} names a parameter twice -> give each once")
    return names


def initial_sensitivities(system, names, t0, y0):
    """``S(t0) = d y0 / dp``: the derivative of the consistent start state ``y0 = [q, u]`` of
    the initialized ``system`` with respect to the parameters ``names`` (see the module notes:
    fixed start values move their coordinates, the free ones follow the rows; exact, from the
    residual program, no second initialization).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.assembly.initialization import initialize
    >>> from mbcomp.simulation.sensitivity import initial_sensitivities
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1), s0=1.0, v0=2.0)); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m); init = initialize(system)
    >>> initial_sensitivities(system, ["s.v0", "b.m"], 0.0, np.array([1.0, 2.0])).tolist()
    [[0.0, 0.0], [1.0, 0.0]]
    """
    return Sensitivities(system, names, t0, y0, (0.0, 0.0), False, 1e-8, 1e-10).S


def _backend(system):
    return "c" if system.backend == "c" else "python"


class Sensitivities(StepHook):
    """The sensitivities of one run (see the module notes): a hook after every accepted step.

    Parameters
    ----------
    system : MultibodySystem
        The run's system, initialized.
    names : list of str
        Parameter names (:func:`mbcomp.codegen.sensitivity.parameter_ref`).
    t0 : float
        Start time (s).
    y0 : ndarray
        Consistent start state ``[q, u]``.
    gains : tuple
        ``(alpha, beta)`` (1/s) of the run's Baumgarte stabilization, ``(0, 0)`` without.
    implicit : bool
        Whether the run's stepper is implicit (the sensitivities are then stepped by Radau).
    rtol, atol : float
        The run's tolerances.
    events : Events, optional
        The run's hybrid events (:class:`mbcomp.hybrid.events.Events`), if it has any.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1), v0=2.0)); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a); system = mbcomp.assemble(m)
    >>> sens = Sensitivities(system, ["world.g[2]"], 0.0, np.array([0.0, 2.0]), (0.0, 0.0), False, 1e-8, 1e-10)
    >>> sens.derivative(system, 0.0, np.array([0.0, 2.0]), sens.S)[1].tolist()   # d/dg_z [v, g_z] at S = 0
    [[0.0], [1.0]]
    """

    def __init__(self, system, names, t0, y0, gains, implicit, rtol, atol, events=None):
        self.system = system
        self.refs = [parameter_ref(system, n) for n in names]
        self.names = [r.name for r in self.refs]
        self.gains = tuple(float(g) for g in gains)
        self.implicit, self.rtol, self.atol = implicit, rtol, atol
        self.n, self.k = system.nq + system.nu, len(self.refs)
        self._codes, self._held = {}, {}
        self._programmed = [j for j, r in enumerate(self.refs) if r.kind == "param"]
        self.t = float(t0)
        self.stopped = None  # why the sensitivities end early, with the time
        self.S = self.initial(system, t0, np.asarray(y0, float))
        if events is not None and events.holds_rows():  # a start in a mode that holds rows or applies forces
            self.hold(system, events)
            self.S = _projected_by_differences(self._held[id(system)], t0, np.asarray(y0, float), self.S)
        self.kept = [self.S.copy()]
        self.kept_systems = [system]
        self.stats_ = dict(sensitivity_steps=0, sensitivity_evaluations=0, sensitivity_jumps=0)

    # --- smooth runs: one C call after the run -----------------------------------------------
    @staticmethod
    def after_the_run(form, events, stepper):
        """Whether a run's sensitivities are integrated after it, simultaneously with a copy of
        its states in one C call (:class:`~mbcomp.codegen.sensitivity_engine.SensitivityIntegrator`):
        a smooth run (no events), not projected, by an explicit method, on a C program. Else
        they are stepped with the run (staggered, a step hook)."""
        return (events is None and not form.projects and not stepper.implicit and form.system.backend == "c"
                and "lagrange_fun" in form.system.evaluator.capabilities)

    def integrate_after(self, run):
        """``S`` at every output the run kept, by the simultaneous C integration of ``[y, S]``
        from the run's start (see :meth:`after_the_run`); the run's own states are kept as they
        are, and the largest difference of the copy from them is in ``stats`` (both are within
        the tolerances). A failure there (a law's branch the program did not trace) ends the
        sensitivities at that time (:attr:`stopped`)."""
        n_kept = len(run.ys)
        self.stats_["sensitivity_method"] = "simultaneous, C (DOP853 over [y, S])"
        if n_kept < 2:
            return
        t = np.asarray(run.t_out[:n_kept], float)
        try:
            integ = SensitivityIntegrator(self.bound(self.system), self.gains)
            Y, S = integ.integrate(t, run.ys[0], self.S, self.rtol, self.atol)
        except (ArithmeticError, SimulationError) as exc:  # the run stands: its sensitivities end
            reached = list(exc.written[1]) if isinstance(exc, ArithmeticError) else []
            reached = reached or [self.kept[0]]
            self.stopped = (float(t[len(reached) - 1]), f"sensitivities: {exc}")
            self.kept = reached + [np.full((self.n, self.k), np.nan)] * (n_kept - len(reached))
            self.kept_systems = [self.system] * n_kept
            return
        self.kept, self.kept_systems = list(S), [self.system] * n_kept
        self.t, self.S = float(t[-1]), S[-1]
        self.stats_.update(sensitivity_steps=int(integ.stats.naccept), sensitivity_evaluations=int(integ.stats.nfev),
                           sensitivity_state_difference=float(np.max(np.abs(Y - np.asarray(run.ys[:n_kept])))))

    # --- programs ----------------------------------------------------------------------------
    def bound(self, system):
        """The bound sensitivity programs of ``system`` (a segment's), built once per structure."""
        key = id(system)
        if key not in self._codes:
            try:
                code = SensitivityCode.cached(system, self.names, _backend(system))
            except CodegenError as exc:
                raise SimulationError(str(exc)) from exc
            self._codes[key] = (system, code.bind(system))
        return self._codes[key][1]

    def _wide(self, D):
        """``D`` over the programs' parameters (the ``"param"`` kind) widened to every
        requested parameter: start values' columns are zero."""
        if D.shape[1] == self.k:
            return D
        out = np.zeros((D.shape[0], self.k))
        out[:, self._programmed] = D
        return out

    def hold(self, system, events):
        """Differentiate ``system`` (a segment whose modes hold rows or apply forces: the rows
        and forces are the hybrid layer's, not in a traced program) by central differences of
        its index-1 right-hand side, the parameters moved in twins of the system over the same
        modes (:meth:`mbcomp.hybrid.events.Events.twin`)."""
        twins = []
        for ref in self.refs:
            if ref.kind == "start":
                twins.append(None)
                continue
            eps = HELD_STEP * max(abs(ref.value), 1e-2)
            twins.append((events.twin(moved_params(system, ref, ref.value + eps)).system_now(),
                          events.twin(moved_params(system, ref, ref.value - eps)).system_now(), eps))
        self._held[id(system)] = (system, twins)

    def _held_rhs(self, held, t, y):
        system, twins = held
        f = _index1(system, t, y, self.gains)
        J = np.empty((self.n, self.n))
        for i in range(self.n):
            h = HELD_STEP * max(1.0, abs(y[i]))
            e = np.zeros(self.n)
            e[i] = h
            J[:, i] = (_index1(system, t, y + e, self.gains) - _index1(system, t, y - e, self.gains)) / (2 * h)
        Jp = np.zeros((self.n, self.k))
        for j, twin in enumerate(twins):
            if twin is not None:
                plus, minus, eps = twin
                Jp[:, j] = (_index1(plus, t, y, self.gains) - _index1(minus, t, y, self.gains)) / (2 * eps)
        self.stats_["sensitivity_held_evaluations"] = self.stats_.get("sensitivity_held_evaluations", 0) + 1
        return f, J, Jp

    _NOT_HELD = ("sensitivities: the {program} program does not hold at t={t:.12g} s (a law's branch the trace "
                 "did not take, or a singular matrix) -> write the law's branch smoothly (e.g. with tanh), or run "
                 "without sensitivities")

    def derivative(self, system, t, y, S):
        """``(fun, f_y S + f_p)`` of ``system`` at ``(t, y)`` for the columns ``S`` (``(n, k)``)
        with the run's gains: the ``jvp`` program's ``k`` forward sweeps (a held segment:
        differences); a ``SimulationError`` where the program does not hold."""
        held = self._held.get(id(system))
        if held is not None:
            f, J, Jp = self._held_rhs(held, t, y)
            return f, J @ S + Jp
        out = self.bound(system).jvp(t, y, S, *self.gains)
        if out is None:
            raise SimulationError(self._NOT_HELD.format(program="sensitivity", t=t))
        self.stats_["sensitivity_evaluations"] += 1
        return out

    def state_jacobian(self, system, t, y):
        """``d fun/dy`` of ``system`` at ``(t, y)`` (what an implicit method's Newton matrix
        needs): from ``ceil(n/k) + 1`` calls of the jvp program along unit columns (exact, and
        no program of the whole Jacobian, whose size grows as N^2 on a chain); a held segment's
        by differences."""
        held = self._held.get(id(system))
        if held is not None:
            return self._held_rhs(held, t, y)[1]
        n, k = self.n, self.k
        base = self.derivative(system, t, y, np.zeros((n, k)))[1]  # f_p (start values: 0)
        J = np.empty((n, n))
        for first in range(0, n, k):
            cols = range(first, min(first + k, n))
            E = np.zeros((n, k))
            for j, c in enumerate(cols):
                E[c, j] = 1.0
            D = self.derivative(system, t, y, E)[1] - base
            for j, c in enumerate(cols):
                J[:, c] = D[:, j]
        return J

    # --- the start ---------------------------------------------------------------------------
    def initial(self, system, t0, y0):
        """``S(t0)``: the derivative of the consistent start state (see the module notes)."""
        nq, nu = system.nq, system.nu
        S = np.zeros((self.n, self.k))
        qfree, ufree, moves = free_start(system)
        for j, ref in enumerate(self.refs):
            if ref.kind != "start":
                continue
            e = system.edge(ref.path)
            if e.q.stop == e.q.start and not e.comp.tree_edge:
                raise SimulationError(f"sensitivities: {ref.name} is a start value of {ref.path!r}, which closes a "
                                      "loop -> take the sensitivity with respect to a tree joint's start value")
            h = 1e-6 * max(1.0, abs(ref.value))
            up, down = ref.value + h, ref.value - h
            step = up - down  # the step between the two representable values: exact for a linear start
            plus, minus = (e.comp.start(with_value(system.P[ref.path], ref, v)) for v in (up, down))
            dq = (np.asarray(plus[0], float) - np.asarray(minus[0], float)) / step
            du = (np.asarray(plus[2], float) - np.asarray(minus[2], float)) / step
            S[e.q, j] = np.where(qfree[e.q], 0.0, dq)  # a Guess is free: the start does not follow it
            S[nq + e.u.start: nq + e.u.stop, j] = np.where(ufree[e.u], 0.0, du)
        ev = system.evaluate(t0, y0[:nq], y0[nq:], masked=False)
        if ev.Phi.size == 0 and ev.Psi.size == 0:  # no rows: nothing follows (and no residual program)
            return S
        res = self._residuals(system, t0, y0)
        if res is None or res[1][0].size == 0:
            return S
        m, (r, Dq, Du, Dp) = res
        Gq, Gp = Dq[:m], Dp[:m]
        Q = rate_map(system, y0[:nq])
        Vq, Vu, Vp = Dq[m:], Du[m:], Dp[m:]
        if (np.linalg.matrix_rank(Gq @ Q[:, moves]) < moves.sum() if m else False) or (
                Vq.shape[0] and np.linalg.matrix_rank(Vu[:, ufree]) < ufree.sum()):
            # the rows leave free directions: which consistent start is reached depends on the
            # initialization's steps from the guesses, so its derivative is differenced
            numeric = system.with_evaluator(None)
            for j, ref in enumerate(self.refs):
                S[:, j] = differenced_start(numeric, ref.path, ref.param, ref.index, ref.value, t0)
            return S
        if m:  # the free coordinates are determined by the rows: the implicit function theorem
            S[:nq] -= Q[:, moves] @ (np.linalg.pinv(Gq @ Q[:, moves]) @ (Gq @ S[:nq] + Gp))
        if Vq.shape[0]:
            rhs = Vq @ S[:nq] + Vu[:, ~ufree] @ S[nq:][~ufree] + Vp
            Su = S[nq:]
            Su[ufree] = -np.linalg.pinv(Vu[:, ufree]) @ rhs
        return S

    @staticmethod
    def _masked(system, bound, res):
        """``(m, (r, d/dq, d/du, d/dp))``: ``res`` (:meth:`BoundSensitivity.residuals`) with
        only the kept holonomic rows, ``[Phi_kept, Phid_kept, Psi]``, ``m`` of them in ``Phi``."""
        r, Dq, Du, Dp = res
        m_all = bound.code.m
        keep = np.ones(m_all, bool) if system.row_mask is None else np.asarray(system.row_mask, bool)
        rows = np.concatenate((keep, keep, np.ones(r.size - 2 * m_all, bool)))
        return int(keep.sum()), (r[rows], Dq[rows], Du[rows], Dp[rows])

    def _residuals(self, system, t, y):
        """The residuals with their derivatives (:meth:`BoundSensitivity.residuals`), the
        parameter columns widened (:meth:`_wide`); None where the program does not hold."""
        bound = self.bound(system)
        res = bound.residuals(t, y)
        if res is None:
            return None
        return self._masked(system, bound, (res[0], res[1], res[2], self._wide(res[3])))

    # --- projection --------------------------------------------------------------------------
    def project(self, system, t, y, S):
        """``S`` moved onto the tangent of ``system``'s constraint manifold at ``(t, y)`` by
        minimum-norm corrections (positions, then speeds)."""
        held = self._held.get(id(system))
        if held is not None:
            return _projected_by_differences(held, t, y, S)
        if system.nq != system.nu:  # quaternions: the run normalizes them, S_Q goes onto the sphere's tangent
            S = _normalized(system, y, S)
        res = self._residuals(system, t, y)
        if res is None:
            raise SimulationError(self._NOT_HELD.format(program="constraint residuals' sensitivity", t=t))
        if res[1][0].size == 0:
            return S
        m, (r, Dq, Du, Dp) = res
        nq = system.nq
        S = S.copy()
        if m:  # minimum norm along the speeds' directions, as the run's projection
            Gq, Q = Dq[:m], rate_map(system, y[:nq])
            S[:nq] -= Q @ (np.linalg.pinv(Gq @ Q) @ (Gq @ S[:nq] + Dp[:m]))
        if Dq.shape[0] > m:
            Vq, Vu, Vp = Dq[m:], Du[m:], Dp[m:]
            S[nq:] -= np.linalg.pinv(Vu) @ (Vq @ S[:nq] + Vu @ S[nq:] + Vp)
        return S

    # --- stepping ----------------------------------------------------------------------------
    def __call__(self, run):
        self.guarded(run, self.advance, run, run.stepper.t)

    def guarded(self, run, step, *args):
        """``step(*args)``; where the sensitivities cannot go on (their program does not hold:
        a law's branch the trace did not take) they end there -- NaN from then on, the reason
        in :attr:`stopped` and the run's message -- and the run goes on."""
        if self.stopped is not None:
            return self.sync(run)
        try:
            return step(*args)
        except SimulationError as exc:
            self.stopped = (float(self.t), str(exc))
            self.S = np.full((self.n, self.k), np.nan)
            return self.sync(run)

    def advance(self, run, t1):
        """Integrate ``S`` from where it is to ``t1`` (s) along the run's last step's dense
        output, and keep it at the outputs the run kept up to ``t1`` (called through :meth:`guarded`)."""
        system = run.form.system
        dense = run.dense()
        t0 = self.t
        if run.projects:  # the state the step started from was projected: S is projected there too
            self.S = self.project(system, t0, np.asarray(dense(t0), float), self.S)
        if t1 > t0:
            sol = self._solve(system, dense, t0, t1)
            self.S = sol(t1)
        else:
            def sol(tt):
                return self.S
        self.t = float(t1)
        while len(self.kept) < len(run.ys) and run.t_out[len(self.kept)] <= t1 + 1e-15 * max(1.0, abs(t1)):
            k = len(self.kept)
            Sk = sol(run.t_out[k])
            if run.projects:
                Sk = self.project(system, run.t_out[k], run.ys[k], Sk)
            self.kept.append(Sk)
            self.kept_systems.append(system)

    def _solve(self, system, dense, t0, t1):
        from scipy.integrate import solve_ivp

        n, k = self.n, self.k

        def rhs(t, s):
            return self.derivative(system, t, np.asarray(dense(t), float), s.reshape(n, k))[1].ravel()

        rtol, atol = self.rtol, self.atol
        if id(system) in self._held:  # a differenced right-hand side: finer control only chases its rounding
            rtol, atol = max(rtol, HELD_RTOL), max(atol, HELD_RTOL * 1e-2)
        opts = dict(rtol=rtol, atol=atol, dense_output=True, first_step=t1 - t0)
        if self.implicit:
            def jac(t, s):
                return np.kron(self.state_jacobian(system, t, np.asarray(dense(t), float)), np.eye(k))
            sol = solve_ivp(rhs, (t0, t1), self.S.ravel(), method="Radau", jac=jac, **opts)
        else:
            sol = solve_ivp(rhs, (t0, t1), self.S.ravel(), method="DOP853", **opts)
        if sol.status != 0:
            raise SimulationError(f"sensitivities: their integration failed in [{t0:.12g}, {t1:.12g}] s: "
                                  f"{sol.message} -> loosen rtol/atol (the sensitivities use the run's), or run "
                                  "without sensitivities")
        self.stats_["sensitivity_steps"] += len(sol.t) - 1
        return lambda tt: sol.sol(tt).reshape(n, k)

    def sync(self, run):
        """Keep ``S`` (where it is now) at outputs the run kept at its time without a step (the
        end of an event that ends the run, a budget's last state)."""
        while len(self.kept) < len(run.ys):
            k = len(self.kept)
            at_now = abs(run.t_out[k] - self.t) <= 1e-12 * max(1.0, abs(self.t))
            self.kept.append(self.S.copy() if at_now and self.stopped is None else np.full((self.n, self.k), np.nan))
            self.kept_systems.append(run.form.system)

    # --- events ------------------------------------------------------------------------------
    def before_act(self, run, cut, events):
        """At an event (``cut``, the outputs up to it kept, the events not acted yet): ``S``
        integrated to the event and the pieces of the jump that need the state before it."""
        self.guarded(run, self.advance, run, cut.t)
        if self.stopped is not None or cut.action is None:
            return None
        return self.guarded(run, Jump, self, run, cut, events)

    def after_act(self, run, jump, outcome, events):
        """Apply the jump (:meth:`before_act`) once the events acted: ``outcome`` is the next
        segment (or the end)."""
        if outcome.ends or self.stopped is not None:
            return self.sync(run)

        def jumped():
            new_system = outcome.form.system  # every new segment: its rows and forces decide how it is differentiated
            if events.holds_rows() and id(new_system) not in self._held:
                self.hold(new_system, events)
            if jump is not None:  # None: no action (a slide turning its direction), the state goes on
                self.S = jump.apply(self, new_system, np.asarray(outcome.state, float))
                self.stats_["sensitivity_jumps"] += 1
            self.t = float(outcome.t)
            self.sync(run)
        self.guarded(run, jumped)

    def stats(self):
        return dict(self.stats_)

    def table(self, time, Y):
        """The :class:`SensitivityTable` of the run's outputs at ``time`` (s), states ``Y``."""
        n_kept = len(time)
        while len(self.kept) < n_kept:
            self.kept.append(np.full((self.n, self.k), np.nan))
            self.kept_systems.append(self.kept_systems[-1])
        return SensitivityTable(self.refs, np.asarray(time, float), np.asarray(Y, float),
                                np.array(self.kept[:n_kept]).reshape(n_kept, self.n, self.k),
                                self.kept_systems[:n_kept], self.gains, self.stopped, set(self._held),
                                list(self.system.q_names) + list(self.system.u_names),
                                self.system.topology.flat.aliases)


def _index1(system, t, y, gains):
    """``[dq/dt, du/dt]`` of the index-1 form of ``system`` (its evaluator: held rows and mode
    forces included) with the Baumgarte ``gains`` (1/s): what the run integrates there."""
    nq = system.nq
    q, u = y[:nq], y[nq:]
    ev = system.evaluate(t, q, u)
    alpha, beta = gains
    rhs = np.concatenate((-ev.cb - 2.0 * alpha * ev.Phid - beta ** 2 * ev.Phi, -ev.Bb - alpha * ev.Psi))
    ud, _ = solve_kkt(ev.M, ev.f, ev.A, rhs, t)
    return np.concatenate((system.q_rate(q, u), ud))


def _projected_by_differences(held, t, y, S):
    """``S`` through the derivative of the run's projection (:func:`mbcomp.assembly.kkt.project_state`)
    of a held segment's system, by central differences along each column ``(S_j, e_j)``: the
    state moved by ``eps S_j``, the parameter by ``eps`` (in the twins)."""
    system, twins = held
    out = np.empty_like(S)
    for j in range(S.shape[1]):
        if twins[j] is None:  # a start value: the projection does not depend on it
            plus = minus = system
            eps = HELD_STEP / max(1.0, float(np.max(np.abs(S[:, j]))))
        else:
            plus, minus, eps = twins[j]
        out[:, j] = (project_state(plus, t, y + eps * S[:, j]) - project_state(minus, t, y - eps * S[:, j])) / (2 * eps)
    return out


def _normalized(system, y, S):
    """``S`` with the coordinates' columns moved by the derivative of the quaternions'
    normalization at ``y`` (``I - Q Q^T`` on each unit quaternion), by central differences of
    :meth:`~mbcomp.assembly.system.MultibodySystem.normalize` (exact to rounding: the map is
    the projection onto the sphere, its second derivative vanishes along the tangent)."""
    nq = system.nq
    q = np.asarray(y[:nq], float)
    S = S.copy()
    for j in range(S.shape[1]):
        d = S[:nq, j]
        size = float(np.max(np.abs(d)))
        if size == 0.0:
            continue
        eps = 1e-7 / size
        S[:nq, j] = (system.normalize(q + eps * d) - system.normalize(q - eps * d)) / (2 * eps)
    return S
