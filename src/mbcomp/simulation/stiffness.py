"""Saying once, during a long run of an explicit method, that the model looks stiff -- and why.

An explicit method's step is bounded by stability: ``h |lambda| <~ 3..6`` for the fastest
rate ``lambda`` of the linearized right-hand side, however smooth the solution. A stiff
spring (c = 1e7 N/m on 1 kg: 3,000 1/s) therefore forces 1e-3 s steps on a motion one
would resolve in 1e-1 s. :class:`StiffnessWatch` (a step hook) waits until a run has lasted
:attr:`StiffnessWatch.after` seconds of wall time with many steps, then estimates once:

* the mean step so far, ``h = (t - t0) / steps``;
* the fastest rate: the spectral radius of ``d fun / dy`` at the current state (the
  formulation's difference Jacobian, :meth:`~mbcomp.formulations.base.Formulation.jac`);
* which element makes it fast: for each force and flange element, how much its generalized
  force changes along the fastest mode (``|M^-1 dQ_c|`` for a unit move along the mode's
  coordinates), the largest named.

If ``h |lambda| > 0.5`` and the fastest rate is over :data:`STIFF_SPREAD` times the
slowest, the steps are held by that rate: the hint names the rate and the element and
suggests an implicit method. If the steps are far smaller than any rate needs
(``h |lambda| < 0.01``), the cause is not stiffness but a law the integrator cannot pass
smoothly (``sign``, ``abs``, a branch): the hint says so and names the elements with laws.
The hint is a ``RuntimeWarning`` when it is made and a note in the result's message.

Examples
--------
>>> import mbcomp
>>> from mbcomp.library import World, Prismatic, PointMass, TranslationalSpringDamper
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, 0)))
>>> j = m.add("j", Prismatic(n=(1, 0, 0), s0=0.01)); b = m.add("b", PointMass(m=1.0))
>>> k = m.add("k", TranslationalSpringDamper(c=1e6))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
>>> m.connect(j.support, k.flange_a); m.connect(j.axis, k.flange_b)
>>> from mbcomp.formulations import build
>>> form = build("lagrange", "ode", mbcomp.assemble(m))
>>> rate, who, smooth, spread = fastest_rate(form, 0.0, form.initial_state(0.0, [0.01], [0.0]))
>>> round(rate), who, smooth, round(spread)               # sqrt(c / m); one mode
(1000, "element 'k'", True, 1)
"""
from __future__ import annotations

import time
import warnings

import numpy as np

from ..modeling.component import PortRef
from .stepping import StepHook

__all__ = ["StiffnessWatch", "fastest_rate", "stiffness_hint"]

#: fastest / slowest rate above which steps held by the fastest mean stiffness (below it the
#: steps follow the motion's own rates: a loose tolerance, not stiffness)
STIFF_SPREAD = 100.0
#: steps a run must have made before a fast motion (no stiffness: every rate alike) is worth a
#: hint -- fewer are a normal run
FAST_STEPS = 10_000
#: states above which the rate comes from power iteration instead of a full eigen-solve
DENSE_STATES = 200


def _jacobian(form, t, y, rel):
    """``d fun / dy`` by forward differences with the relative step ``rel``."""
    f0 = np.asarray(form.fun(t, y))
    J = np.empty((f0.size, y.size))
    for j in range(y.size):
        yj = y.copy()
        yj[j] += rel * max(abs(y[j]), 1.0)
        J[:, j] = (np.asarray(form.fun(t, yj)) - f0) / (yj[j] - y[j])
    return J


def _spectrum(form, t, y, rel=1.5e-8):
    """``(|lambda|_max, mode, |lambda|_min)``: the fastest rate of ``d fun / dy`` at ``(t, y)``
    (differences of relative step ``rel``), its eigenvector (real and imaginary parts added)
    and the slowest non-zero rate (None above :data:`DENSE_STATES` states)."""
    if y.size <= DENSE_STATES:
        lam, vec = np.linalg.eig(_jacobian(form, t, y, rel))
        k = int(np.argmax(abs(lam)))
        return float(abs(lam[k])), np.real(vec[:, k]) + np.imag(vec[:, k]), _slowest(abs(lam))
    f0, v = np.asarray(form.fun(t, y)), np.random.default_rng(0).standard_normal(y.size)
    rate = 0.0
    for _ in range(30):  # power iteration by directional differences
        v /= np.linalg.norm(v)
        h = rel * max(1.0, float(np.linalg.norm(y)))
        w = (np.asarray(form.fun(t, y + h * v)) - f0) / h
        rate, v = float(np.linalg.norm(w)), w
    return rate, v / np.linalg.norm(v), None


def _slowest(rates):
    """The slowest rate that is not zero (above 1e-6 of the fastest), or None."""
    live = rates[rates > 1e-6 * rates.max()] if rates.size and rates.max() > 0 else rates[:0]
    return float(live.min()) if live.size else None


def _generalized(system, t, q, u, path):
    """The generalized force (u-space) of the element ``path`` alone at ``(t, q, u)``."""
    jets = system.kinematics(t, q, u)
    topo, f = system.topology, np.zeros(system.nu)
    for p, comp, ports in topo.forces:
        if p == path:
            frames = {pn: system.frame_state(jets[n]) for pn, n in ports.items()}
            for pn, (F, T) in comp.wrenches(t, frames, system.P[p]).items():
                J = jets[ports[pn]]
                f += J.Jv.T @ np.asarray(F, float) + J.Jw.T @ np.asarray(T, float)
    for p, comp in topo.flange_elements:
        if p != path:
            continue
        roots = {pn: topo.flange_of[PortRef(comp, pn, "flange")] for pn, pt in comp.ports().items()
                 if pt.kind == "flange"}
        states = {pn: system.flange_state(r, jets, t, q, u) for pn, r in roots.items()}
        for pn, flow in comp.flange_forces(t, states, system.P[p]).items():
            jname, which = topo.flange_owner[roots[pn]]
            if which != "axis":
                continue
            e = next(x for x in topo.edges if x.name == jname)
            n = e.comp.axis_world(jets[e.node_a].R, system.P[e.name]) * float(flow)
            a, b = jets[e.node_a], jets[e.node_b]
            f += ((b.Jw - a.Jw) if e.comp.axis_kind == "rotational" else (b.Jv - a.Jv)).T @ n
    return f


def fastest_rate(form, t, y):
    """``(rate, who, smooth, spread)``: the fastest rate (1/s) of the formulation's right-hand
    side at ``(t, y)``; ``"element '<name>'"``, the force or flange element that contributes
    most to it, or when none does (a stiff mass ratio, a constraint's gains) ``"speed <name>"``,
    the speed its mode moves most (``None`` if neither); and
    whether the right-hand side is smooth there: a rate that grows as the difference step
    shrinks (by over 10x for a 1000x smaller step) is a jump, not a rate; and the ratio of the
    fastest to the slowest non-zero rate (None when unknown)."""
    y = np.asarray(y, float)
    rate, mode, slow = _spectrum(form, t, y)
    spread = rate / slow if slow else None
    smooth = rate <= 10.0 * _spectrum(form, t, y, rel=1.5e-5)[0]
    system = form.system
    eps = 1e-6
    ya, yb = form.full(t, y + eps * mode), form.full(t, y - eps * mode)
    nq = system.nq
    du = np.abs(ya[nq:] - yb[nq:])
    # the speed the fastest mode moves most names its joint when no element can be blamed
    who = f"speed {system.u_names[int(np.argmax(du))]}" if du.size and du.max() > 0 else None
    names = [p for p, _, _ in system.topology.forces] + [p for p, _ in system.topology.flange_elements]
    if not names:
        return rate, who, smooth, spread
    M = system.evaluate_numeric(t, ya[:nq], ya[nq:]).M
    best, blamed = 0.0, None
    for path in names:
        dQ = (_generalized(system, t, ya[:nq], ya[nq:], path) - _generalized(system, t, yb[:nq], yb[nq:], path)) / (2 * eps)
        size = float(np.linalg.norm(np.linalg.lstsq(M, dQ, rcond=None)[0]))
        if size > best:
            best, blamed = size, path
    return rate, (f"element {blamed!r}" if best > 1e-3 * rate else who), smooth, spread


def smooth_step(stepper, rtol):
    """``h |lambda|`` a smooth motion needs at ``rtol`` with ``stepper``'s method of order
    ``p``: its local error ``(h |lambda|)^(p + 1)`` meets the tolerance at ``rtol^(1/(p+1))``
    (RK23 at rtol 1e-9: 5.6e-3; DOP853 at 1e-12: 0.046); 1 when the order is unknown.

    Examples
    --------
    >>> from mbcomp.solvers.scipy_adapter import SCIPY_STEPPERS
    >>> round(smooth_step(SCIPY_STEPPERS["RK23"], 1e-9), 4)
    0.0056
    """
    p = getattr(stepper, "order", None) or getattr(getattr(stepper, "method", None), "order", None)
    if not isinstance(p, (int, np.integer)) or p < 1:
        return 1.0
    return min(1.0, float(np.max(rtol)) ** (1.0 / (p + 1)))


def stiffness_hint(form, t, y, h, steps, t_reached=None, cut_short=False, smooth_h=1.0):
    """The hint at the state ``y`` at ``t`` (s) of a run whose recent steps are ``h`` (s) long
    and that made ``steps`` steps to ``t_reached`` (default ``t``; see the module notes), or
    ``None`` when the steps are neither held by a fast rate nor suspiciously small -- unless
    the run was cut short (``cut_short``: the span of the run, s, when a budget ran out or the
    integrator gave up) with steps that would need over ``10 FAST_STEPS`` for it: then the
    fastest rate and whom it belongs to are said in any case. ``smooth_h``: the ``h |lambda|`` a
    smooth motion needs at the run's tolerance (:func:`smooth_step`); steps ten times
    shorter are tiny (a pendulum on RK23 at rtol 1e-9 steps at 2e-3 for a smooth 5.6e-3: no
    kink)."""
    rate, who, smooth, spread = fastest_rate(form, t, y)
    t = t if t_reached is None else t_reached
    whose = f" ({who})" if who else ""
    element = who.split("'")[1] if who and who.startswith("element") else None
    if not smooth:
        return (f"the steps are held small (h={h:.2g} s, {steps} steps to t={t:g} s) by a jump in the right-hand "
                f"side{whose}: a law with a discontinuity (sign, a branch, a table) -> smooth it (e.g. "
                "tanh(w / 1e-3) for sign(w)), or end the run early with max_wall_time=")
    if h * rate > 0.5 and (spread is None or spread > STIFF_SPREAD):
        return (f"this model looks stiff: the largest rate is about {rate:.3g} 1/s{whose}, which holds the explicit "
                f"method's steps near h={h:.2g} s ({steps} steps to t={t:g} s) -> try method='radau5' or "
                f"method='BDF'{', or a softer ' + repr(element) if element else ''}")
    if h * rate > 0.5 and steps >= FAST_STEPS:
        return (f"the motion itself is fast: every rate is near {rate:.3g} 1/s{whose}, so following it takes steps "
                f"near h={h:.2g} s ({steps} steps to t={t:g} s) -> shorten the run, or soften{' ' + repr(element) if element else ' it'} "
                "if that speed is not meant")
    if cut_short and cut_short / h >= 10 * FAST_STEPS and h * rate > 0.5:  # (below: the motion sets the steps)
        return (f"the steps were h={h:.2g} s ({steps} steps to t={t:g} s); the fastest rate is about {rate:.3g} "
                f"1/s{whose} -> try method='radau5' or method='BDF', a shorter run, or "
                f"{'a softer ' + repr(element) if element else 'heavier light parts'}")
    if h * rate < 0.1 * smooth_h:
        comps = system_laws(form.system)
        return (f"the steps are tiny (h={h:.2g} s, {steps} steps to t={t:g} s) although the fastest rate is only "
                f"about {rate:.3g} 1/s: a law with a kink or a discontinuity makes the integrator creep"
                f"{' -- laws in ' + ', '.join(comps) if comps else ''} -> smooth it (e.g. tanh(w / 1e-3) for sign(w)) "
                "or end the run early with max_wall_time=")
    return None


def system_laws(system):
    """Names of the components whose parameters are callables (laws)."""
    return [name for name, comp in system.topology.flat.components.items()
            if any(callable(v) for v in vars(system.P.get(name, comp.p)).values())]


class StiffnessWatch(StepHook):
    """Makes :func:`stiffness_hint` once, after :attr:`after` s of wall time and
    :attr:`min_steps` steps of an explicit method (or, called with ``now=True`` when a budget
    ran out, after a quarter of that time or those steps), from the steps of the last half of
    that time; warns with it and keeps it for the result's message (``note``)."""

    #: wall time (s) a run lasts before the hint is made
    after = 2.0
    #: integrator steps a run has made before the hint is made
    min_steps = 2000

    def __init__(self):
        self.started = time.perf_counter()
        self.note = None
        self.done = False
        self.trail = []  # (wall time, t, steps) after every driver step

    def __call__(self, run, now=False):
        if self.done:
            return
        wall, steps = time.perf_counter() - self.started, run.counters()["steps"]
        self.trail.append((wall, run.t, steps))
        slow = wall >= self.after and steps >= self.min_steps
        if not (slow or (now and (wall >= self.after / 4 or steps >= self.min_steps))):
            return  # (a run cut short by a small budget early on is not a slow run)
        self.done = True
        t = run.stepper.t_reached  # (past the last accepted step when a failed stretch got further)
        past = next((x for x in self.trail if x[0] >= 0.5 * wall and x[2] < steps and x[1] < t), None)
        h = (t - past[1]) / (steps - past[2]) if past else (t - run.t_out[0]) / max(steps, 1)
        if not h > 0:
            return
        try:
            self.note = stiffness_hint(run.form, run.stepper.t, run.stepper.y, h, steps, t,
                                       cut_short=now and float(run.t_out[-1] - run.t_out[0]),
                                       smooth_h=smooth_step(run.stepper, run.options["rtol"]))
        except Exception:  # noqa: BLE001 - a hint must never end a run
            self.note = None
        if self.note:
            warnings.warn(f"mbcomp: {self.note}", RuntimeWarning, stacklevel=2)

    def stats(self):
        return {"stiffness_hint": self.note} if self.note else {}
