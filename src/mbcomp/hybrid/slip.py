"""Coulomb friction at rolling contacts in a run: sliding contacts' systems, forces and columns.

A contact with friction (``SphereContact``/``DiskContact(unilateral=True,
friction=ContactFriction(mu_s, mu_k))``, :class:`mbcomp.library.plane_contact.Frictional`)
rolls in its mode ``"closed"`` -- its rolling rows (``velocity_constraints``, the slip
velocity along orthonormal tangents ``t1``, ``t2``) hold and the run watches the friction
cone ``mu_s N - |F_t|`` (:func:`~mbcomp.hybrid.contacts.contact_pushes`) -- and slides
in the mode where :meth:`~mbcomp.modeling.modes.Modes.slip_friction` gives its kinetic
coefficient ``mu_k``:

* the mode's system leaves the sliding contacts' rolling rows out (:func:`~mbcomp.hybrid.active.without_rolling`;
  the normal row stays) and :class:`SlipEvaluator` adds the friction ``F = -mu_k N s`` to
  the generalized forces, ``f += C_t^T F``, ``s`` the unit slip velocity ``v_t / |v_t|``
  (``C_t u`` plus the rows' offset, in the tangents' coordinates);
* ``N`` is the normal row's push, which itself depends on the friction: the forces are
  linear in ``N``, ``f + G N`` with ``G = -mu_k C_t^T s``, so one factorization of the
  index-1 saddle-point matrix with the right-hand sides ``f`` and ``G`` gives the
  multipliers ``lam0 + L1 N`` and the exact normal forces from ``N = -(lam0_n + L1_n N)``:
  ``(I + L1_n) N = -lam0_n`` (:func:`friction_solve`). Where ``I + L1_n`` is not positive
  (a single contact: ``1 + L1_n <= 0``) no normal force is consistent with sliding -- the
  Painleve paradox -- and the run fails saying so, instead of stepping a negative mass;
* the friction is then a force of the state, so every formulation and solver steps the
  mode as any other (its program is the jets': a sliding mode runs on the numeric path);
* the mode's event is the slip speed along the direction it started with, ``v_t . d``
  (:class:`~mbcomp.modeling.events.SlipSpeed`) falling through zero: at rest
  (``|v_t|`` ~ 0) the contact rolls again if the cone holds it there, else it slides on
  the other way; a plane slip whose direction turned by 90 degrees takes the new direction
  (:data:`TURN`). A slide starting from rest (a break-away, or a start at rest beyond the
  cone) starts in the direction its own friction gives: ``a_t(d) = lambda d``, ``lambda >
  0``, the slip accelerating along ``d`` with the friction against it, the root nearest
  ``-F_t / |F_t|`` (the load the sticking force held) (:func:`start_directions`).

After the run (:func:`mbcomp.simulation.hybrid_columns.segment_columns`),
:func:`sliding_values` gives the columns at sliding outputs over the system with the rolling
rows, their multipliers set to the friction (so the contact's ``F_1``/``F_2`` or
``F_long``/``F_lat`` are the kinetic friction and every reaction carries it);
:func:`slip_state` gives ``<contact>.sticking`` (1 rolling, 0 sliding or open) and
``<contact>.slip`` (m/s, ``|v_t|``), :func:`slip_dissipation` ``<contact>.power`` (W, the
friction's power, ``-mu_k N |v_t|``). The
friction's dissipated energy ``int mu_k N |v_t| dt`` is integrated while the run goes, on each
step's dense output (:func:`slide_work`, Gauss-Legendre between the step's ends, events and
output times), and :func:`slip_dissipation` adds it to ``energy.dissipated`` and
``energy.balance`` (exact to the integrator's accuracy on any output grid, two points too).

Examples
--------
A ball thrown along a floor without spin slides until ``t = 2 v0 / (7 mu g)`` and rolls on at
``5 v0 / 7``:

>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, FreeMotion, RigidBody, SphereContact, ContactFriction
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> free = m.add("free", FreeMotion(r0=(0, 0, 0.1), v0=(2.0, 0, 0)))
>>> ball = m.add("ball", RigidBody(m=1.0, I=0.004 * np.eye(3)))
>>> c = m.add("floor", SphereContact(r=0.1, unilateral=True, friction=ContactFriction(0.3, 0.2)))
>>> m.connect(w.frame_b, free.frame_a); m.connect(free.frame_b, ball.frame_a)
>>> m.connect(w.frame_b, c.frame_a); m.connect(c.frame_b, ball.frame_a)
>>> res = mbcomp.simulate(m, t_end=1.0, rtol=1e-10, atol=1e-12)
>>> [e.kind for e in res.events], round(res.events[0].time, 9), round(2 * 2.0 / (7 * 0.2 * 9.81), 9)
(['switch'], 0.291247998, 0.291247998)
>>> round(float(res["ball.v.x"][-1]), 9), round(5 / 7 * 2.0, 9)
(1.428571429, 1.428571429)
"""
from __future__ import annotations

import numpy as np

from ..assembly.kkt import accelerations, saddle_point
from ..errors import SimulationError
from ..modeling.events import ContactRow
from .active import (ForcesAdded, WrappingEvaluator, cone_joints, mode_system, open_joints, rows_in_force, segment_at,
                     slipping_joints, with_mode_forces, without_rows)
from .contacts import contact_rows, tangent_force
from .friction import count_dissipation

__all__ = ["tangent_rows", "friction_solve", "SlipEvaluator",
           "with_slip_friction", "slip_accelerations", "start_directions", "frictional_contacts", "slip_state",
           "sliding_values", "slide_power", "slide_work", "slip_dissipation",
           "SlideEvents", "V_TINY", "TURN", "SPIN_TURNS", "SPIN_SPAN"]

#: m/s: a slip slower than this slides along the direction it started (or last turned) with
V_TINY = 1e-12
#: a slip-speed event with ``|v_t|`` above this times ``atol`` is a turn of a plane slip, not a stick
TURN = 1e3
#: a slide turning this many times within SPIN_SPAN max(1, |t|) seconds is taken as sticking
SPIN_TURNS, SPIN_SPAN = 3, 1e-6


def tangent_rows(system, name, t, q, u, jets=None):
    """``(C_t, v_t, bias_t)`` of contact ``name``'s rolling rows at ``(t, q, u)``: their
    Jacobian (k, nu), the slip velocity along the tangents (k,, m/s) and its rate at
    ``du/dt = 0`` (k,, m/s^2)."""
    cr = contact_rows(system, name, t, q, u, jets=jets)
    return cr.C[1:], cr.C[1:] @ u + cr.offset[1:], cr.bias[1:]


def slip_direction(v_t, d):
    """The unit slip direction of a slide that started along ``d``: ``v_t / |v_t|`` turned
    to ``d``'s side (``sign(v_t . d)``), or ``d`` where ``|v_t| <=`` :data:`V_TINY`.

    On the far side of its stick (``v_t . d < 0``, where the integrator's trial
    stages go before the event is located) the friction keeps pushing the way it did, as the
    mode's constant force on a 1-DOF axis does: the right-hand side stays smooth through the
    event, and its dense output locates it (a sign flip there would cost tiny steps and
    spoil the location, 2e-9 s on a ball at rtol 1e-10)."""
    d = np.asarray(d, float)
    s = float(np.linalg.norm(v_t))
    if not s > V_TINY:
        return d
    return v_t / s if v_t @ d >= 0.0 else -v_t / s


def _normal_index(system, name):
    names = system.constraint_names()
    key = f"{name}.normal"
    if key not in names:
        raise SimulationError(f"{name}: its normal row was dropped as redundant with the mechanism's other rows, so "
                              "its normal force, which the sliding friction needs, is not defined -> remove the "
                              "redundant support, or give the contact no friction")
    return names.index(key)


def friction_solve(system, ev, slips):
    """``(f, N)``: the generalized forces of evaluation ``ev`` (of ``system``, the mode's
    system) with the sliding friction of ``slips`` (``[(contact, mu_k, d)]``) and the exact
    normal forces ``N`` (N) of those contacts (see the module notes)."""
    nu, k = system.nu, len(slips)
    G = np.zeros((nu, k))
    for j, (name, mu, d) in enumerate(slips):
        C_t, v_t, _ = tangent_rows(system, name, ev.t, ev.q, ev.u, ev.jets)
        G[:, j] = -mu * (C_t.T @ slip_direction(v_t, d))
    K, b = saddle_point(ev)
    rhs = np.zeros((K.shape[0], 1 + k))
    rhs[:, 0], rhs[:nu, 1:] = b, G
    try:
        X = np.linalg.solve(K, rhs)
    except np.linalg.LinAlgError:
        names = ", ".join(n for n, _, _ in slips)
        raise SimulationError(f"{names}: the saddle-point matrix of the sliding mode is singular at t={ev.t:.9g} s "
                              "(the mechanism's rows are redundant there) -> remove the redundant support, or "
                              "give the contact no friction") from None
    rows = [_normal_index(system, name) for name, _, _ in slips]
    lam0, L1 = X[nu:, 0][rows], X[nu:, 1:][rows, :]
    S = np.eye(k) + L1
    if np.min(np.linalg.eigvals(S).real) <= 1e-12:
        names = ", ".join(n for n, _, _ in slips)
        raise SimulationError(
            f"{names}: Painleve paradox at t={ev.t:.9g} s: sliding with mu_k = "
            f"{', '.join(f'{mu:g}' for _, mu, _ in slips)} the friction presses the contact into its surface harder "
            "than any normal force can answer (no consistent normal force exists) -> lower mu_k, or change the "
            "geometry (a contact trailing its body's centre of mass does not jam)")
    N = np.linalg.solve(S, -lam0)
    return ev.f + G @ N, N


class SlipEvaluator(WrappingEvaluator):
    """The evaluator of a mode with sliding contacts: the wrapped evaluation with the
    friction of ``slips`` (``[(contact, mu_k, start direction)]``) in its forces ``f``
    (:func:`friction_solve` over ``system``, the mode's system this evaluator serves)."""

    def __init__(self, inner, system, slips):
        super().__init__(inner)
        self.system, self.slips = system, slips

    def evaluate(self, t, q, u, masked=True):
        ev = self.inner.evaluate(t, q, u, masked)
        if not masked:
            return ev
        return ForcesAdded(ev, friction_solve(self.system, ev, self.slips)[0])

    def rebind(self, system, laws=False):
        return SlipEvaluator(self.inner.rebind(system, laws), system, self.slips)


def slips_of(system, modes, dirs):
    """``[(contact, mu_k, direction)]`` of the contacts sliding in ``modes`` (``dirs``: their
    start directions, default along the first tangent)."""
    return [(n, float(system.edge(n).comp.modes(system.P[n]).slip_friction(modes[n])),
             np.asarray(dirs.get(n, (1.0, 0.0)), float)) for n in slipping_joints(system, modes)]


def with_slip_friction(sysm, system, modes, dirs):
    """The mode's system ``sysm`` with the friction of the contacts sliding in ``modes``
    (``system`` the assembled one; itself when none slides)."""
    slips = slips_of(system, modes, dirs)
    if not slips:
        return sysm
    return sysm.with_evaluator(lambda new: SlipEvaluator(sysm.evaluator, new, slips))


def slip_accelerations(sysm, ev, slips):
    """``{contact: a_t}``: the slip accelerations (m/s^2, tangents' coordinates) at the
    evaluation ``ev`` of a sliding mode's system without its friction (``sysm``) with the
    friction of ``slips`` (``[(contact, mu_k, direction)]``) applied (index-1 solve, the
    exact normal forces of :func:`friction_solve`)."""
    f, _ = friction_solve(sysm, ev, slips)
    K, b = saddle_point(ev)
    b[: sysm.nu] = f
    ud = np.linalg.lstsq(K, b, rcond=1e-13)[0][: sysm.nu]
    out = {}
    for n, _, _ in slips:
        C_t, _, b_t = tangent_rows(sysm, n, ev.t, ev.q, ev.u, ev.jets)
        out[n] = C_t @ ud + b_t
    return out


#: directions scanned on the unit circle for a slide's start (then refined by Brent)
START_SCAN = 72


def start_directions(sysm, slips, t, q, u, names):
    """The start directions of the contacts ``names`` (of ``slips``: ``[(contact, mu_k,
    first guess)]``) sliding from rest at ``(t, q, u)`` in the sliding mode's system ``sysm``
    (without its friction): the direction ``d`` in which the slip accelerates when its
    friction opposes ``d``, ``a_t(d) = lambda d`` with ``lambda > 0``.

    On the unit circle ``d(phi)`` the roots of ``d x a_t(d)`` with ``d . a_t > 0`` are found
    by a scan of :data:`START_SCAN` angles and Brent's method; of several, the one nearest the
    first guess (``-F_t``, the load the rolling rows held) is taken. A contact's tangential
    mobility may be far from isotropic (a wheel: its spin's small inertia against the whole
    vehicle's), so the plain iteration ``d <- a_t(d)/|a_t(d)|`` does not converge there. With
    several contacts starting at once each is solved with the others' directions fixed, in
    turn, a few sweeps."""
    from scipy.optimize import brentq

    ev = sysm.evaluate(t, q, u)
    cur = {n: np.asarray(d, float) for n, _, d in slips}

    def residual(n, phi):
        d = np.array([np.cos(phi), np.sin(phi)])
        a = slip_accelerations(sysm, ev, [(m, mu, d if m == n else cur[m]) for m, mu, _ in slips])[n]
        return d[0] * a[1] - d[1] * a[0], d @ a

    for _ in range(3 if len(names) > 1 else 1):
        for n in names:
            guess = np.arctan2(cur[n][1], cur[n][0])
            phis = guess + np.linspace(0.0, 2 * np.pi, START_SCAN + 1)
            vals = [residual(n, p) for p in phis]
            roots = []
            for (p0, (c0, _)), (p1, (c1, _)) in zip(zip(phis, vals), zip(phis[1:], vals[1:])):
                if c0 == 0.0 or c0 * c1 < 0.0:
                    p = p0 if c0 == 0.0 else brentq(lambda x: residual(n, x)[0], p0, p1, xtol=1e-14)
                    if residual(n, p)[1] > 0.0:
                        roots.append(p)
            if roots:
                best = min(roots, key=lambda p: abs(np.angle(np.exp(1j * (p - guess)))))
                cur[n] = np.array([np.cos(best), np.sin(best)])
    return cur


def closed_force(sysc, name, t, q, u):
    """The rolling rows' force ``F_t`` (N, on the body, along the tangents) of contact
    ``name`` held rolling in the system ``sysc``."""
    ev = sysc.evaluate(t, q, u)
    _, lam = accelerations(ev)
    return tangent_force(ev, sysc.row_multipliers(ev, lam), name)


def frictional_contacts(system, segments):
    """The contacts with a friction cone that roll (a cone row held) or slide in some segment
    of ``segments`` (the run's :class:`~mbcomp.hybrid.active.SegmentStart` list): they get the
    columns ``<contact>.sticking`` (1 rolling, 0 sliding or open) and ``<contact>.slip`` (m/s,
    ``|v_t|``)."""
    return sorted({n for seg in segments for n in slipping_joints(system, seg.modes) + cone_joints(system, seg.modes)})


def slip_state(system, names, modes, t, q, u):
    """``{column: value}`` of the contacts ``names`` at ``(t, q, u)`` in the active set
    ``modes``: ``<contact>.sticking`` (1 rolling, 0 sliding or open) and ``<contact>.slip``
    (m/s, ``|v_t|``)."""
    rolling = cone_joints(system, modes)
    out = {}
    for n in names:
        out[f"{n}.sticking"] = float(n in rolling)
        out[f"{n}.slip"] = float(np.linalg.norm(tangent_rows(system, n, t, q, u)[1]))
    return out


def sliding_values(system, sysm, modes, dirs, t, q, u):
    """Every column at ``(t, q, u)`` in the active set ``modes`` with sliding contacts (start
    directions ``dirs``; ``sysm`` the mode's system, its friction included): over the system
    with the rolling rows, their multipliers set to the kinetic friction (so the contact's
    ``F_1``/``F_2`` or ``F_long``/``F_lat`` are the friction and every reaction carries it;
    see the module notes)."""
    from types import SimpleNamespace

    from ..assembly.outputs import result_columns

    ev = sysm.evaluate(t, q, u)
    ud, lam = accelerations(ev)
    slips = slips_of(system, modes, dirs)
    _, N = friction_solve(sysm, ev, slips)
    base = without_rows(system, rows_in_force(system, modes).open)  # the rolling rows carry the friction
    evb = base.evaluate(t, q, u)
    force = {}
    for (n, mu, d), Nn in zip(slips, N):
        v_t = tangent_rows(base, n, t, q, u, evb.jets)[1]
        force[n] = -mu * Nn * slip_direction(v_t, d)  # on the body, along the tangents
    lam_b = _multipliers(sysm, ev, lam, evb, force)
    Psi = np.array(evb.Psi, float)  # a sliding contact's slip is no violation
    i = 0
    for e, rows, _ in evb.local_nh:
        if e.name in force:
            Psi[i:i + len(rows)] = 0.0
        i += len(rows)
    evf = base.evaluate(t, q, u, masked=False) if evb.local else evb
    cols = SimpleNamespace(t=t, q=q, u=u, jets=evb.jets, local_nh=evb.local_nh, B=evb.B, Phi_all=evf.Phi,
                           Phid_all=evf.Phid, Psi=Psi)
    values, _ = result_columns(base, cols, ud, lam_b, base.reactions(evb, ud, lam_b))
    return values


def _multipliers(sysm, ev, lam, evb, force):
    """The multipliers over the system with the sliding contacts' rolling rows (``evb``):
    the mode's own (``lam`` at ``ev``; rows appended by stops left out) and, for the
    sliding contacts' rows, minus their friction ``force`` (N, along the tangents)."""
    nh = ev.B.shape[0]
    hol = lam[: evb.Phi.size]  # the mode's holonomic rows first: the same as the base's
    mult_nh = {(e.name, r): lam[lam.size - nh + i] for i, (e, r) in
               enumerate((e, r) for e, rows, _ in ev.local_nh for r in rows)}
    out = list(hol)
    for e, rows, _ in evb.local_nh:
        for i, r in enumerate(rows):
            out.append(-force[e.name][i] if e.name in force else mult_nh[(e.name, r)])
    return np.array(out, float)


def slide_power(sysm, slips, t, y):
    """Each sliding contact's friction loss ``mu_k N |v_t|`` (W) at ``(t, y = [q, u])`` in the
    mode's system ``sysm`` (``slips``: :func:`slips_of`)."""
    q, u = y[: sysm.nq], y[sysm.nq: sysm.nq + sysm.nu]
    ev = sysm.evaluate(t, q, u)
    _, N = friction_solve(sysm, ev, slips)
    return np.array([mu * Nn * float(np.linalg.norm(tangent_rows(sysm, n, t, q, u, ev.jets)[1]))
                     for (n, mu, _), Nn in zip(slips, N)])


_GAUSS = np.polynomial.legendre.leggauss(5)


def slide_work(sysm, slips, qu, a, b):
    """``int_a^b sum mu_k N |v_t| dt`` (J) along the step's dense output ``qu(t) -> [q, u]``:
    five-point Gauss-Legendre (exact to degree 9: well below the integrator's error on a
    step)."""
    mid, half = 0.5 * (a + b), 0.5 * (b - a)
    return half * sum(w * float(np.sum(slide_power(sysm, slips, mid + half * x, qu(mid + half * x))))
                      for x, w in zip(*_GAUSS))


def slip_dissipation(res, system, segments, work_log, Y, system_now):
    """The sliding friction's columns ``<contact>.power`` (W) at the outputs and its
    dissipated energy (J), integrated along each step's dense output while the run went
    (``work_log``: ``[(t, work done up to t)]`` at the step ends and output times), added to
    ``energy.dissipated`` and ``energy.balance`` of ``res`` (the energy alarm is judged again
    by :func:`mbcomp.simulation.hybrid_columns.finish`).
    ``segments``: the run's :class:`~mbcomp.hybrid.active.SegmentStart` list; ``Y`` the
    outputs' states."""
    t = res.time
    if not len(t):
        return res
    at = segment_at([seg.t for seg in segments], t)  # an event's output: the segment before it
    for i, seg in enumerate(segments):
        slips = slips_of(system, seg.modes, seg.dirs)
        if not slips:
            continue
        sel = np.flatnonzero(at == i)
        sysm = system_now(seg.modes, seg.dirs)
        for k in sel:
            for (n, _, _), p in zip(slips, slide_power(sysm, slips, t[k], Y[k])):
                res[f"{n}.power"][k] = -p
    if "energy.balance" in res:
        times, work = np.array(work_log).T
        count_dissipation(res, np.interp(t, times, work))
    return res


class SlideEvents:
    """The part of :class:`mbcomp.hybrid.events.Events` that handles sliding contacts: a
    start that rolls, start directions of new slides, turns of a plane slip, contacts that
    land slipping, the cone of a contact's rolling mode and the friction's work along the
    steps (see the module notes). Uses the events' ``system``, ``modes``, ``slip_dirs``,
    ``records``, ``atol``/``rtol`` and their ``system_now`` and ``_record``."""

    def _slide_work(self, run, qu, t_to):
        """Integrate the sliding contacts' friction loss from where it was integrated to up to
        ``t_to`` (s) on the step's dense output ``qu`` (:func:`~mbcomp.hybrid.slip.slide_work`),
        recording the work done at ``t_to`` and at the output times passed."""
        a, self._worked_to = self._worked_to, t_to
        slips = slips_of(self.system, self.modes, self.slip_dirs)
        if not slips or not t_to > a:
            self.work_log.append((t_to, self.slide_worked))  # no slide: the work stays (a point to interpolate)
            return
        sysm = self.system_now()
        cuts = [a] + [to for to in run.t_out if a < to < t_to] + [t_to]
        for lo, hi in zip(cuts[:-1], cuts[1:]):
            self.slide_worked += slide_work(sysm, slips, qu, lo, hi)
            self.work_log.append((hi, self.slide_worked))

    def _turns(self, who, t_e, state):
        """The new direction (unit, tangent coordinates) of the slide of ``who`` if it only
        turned, else None: its slip speed ``|v_t|`` is more than :data:`TURN` ``atol + 10 rtol
        v_peak`` where its speed along the start direction passes zero (``v_peak`` the slide's
        fastest slip at a step's end so far: the integration's own error across the slip is no
        turn); the run then slides on from ``t_e`` along the new direction (recorded as a
        ``"turn"`` by :meth:`~mbcomp.hybrid.events.Events.act`)."""
        nq = self.system.nq
        v_t = tangent_rows(self.system, who, t_e, state[:nq], state[nq:])[1]
        if not np.linalg.norm(v_t) > TURN * self.atol + 10.0 * self.rtol * self._slip_peak.get(who, 0.0):
            return None
        turns = [r.time for r in self.records[-SPIN_TURNS:] if r.component == who and r.kind == "turn"]
        if len(turns) == SPIN_TURNS and t_e - turns[0] <= SPIN_SPAN * max(1.0, abs(t_e)):
            return None  # its direction spins as it dies (stiff near |v_t| = 0): taken as sticking
        return v_t / np.linalg.norm(v_t)

    def _cone(self, who, mode):
        """``(mu_s, mu_k)`` of contact ``who`` rolling in ``mode`` (its row's friction cone, and
        the kinetic coefficient of the mode its ``"slide"`` event goes to), or None."""
        declared = self.system.edge(who).comp.modes(self.system.P[who])
        cone = [r.mu_s for r in declared.rows(mode) if isinstance(r, ContactRow) and r.mu_s is not None]
        if not cone:
            return None
        return cone[0], declared.slip_friction(declared.action("slide", mode).mode)

    def _sliding_now(self, t, q, u, modes):
        """``modes`` with the contacts that land rolling (open before, a friction cone now) but
        slip faster than :data:`TURN` ``atol`` (after an impact that slid: the rolling rows
        would take the slip away) switched to their sliding mode (``Modes.action("slide")``,
        recorded)."""
        out, landed = dict(modes), set(open_joints(self.system, self.modes))  # only a contact that was open
        for n, mode in modes.items():
            if n in landed and self._cone(n, mode) is not None and np.linalg.norm(
                    tangent_rows(self.system, n, t, q, u)[1]) > TURN * self.atol:
                out[n] = self.system.edge(n).comp.modes(self.system.P[n]).action("slide", mode).mode
                self._record(t, n, "slide", "switch", {"mode": out[n], "energy_loss": 0.0})
        return out

    def _directions(self, t, q, u, modes, going_on):
        """The start directions of the contacts sliding in ``modes`` at ``(t, q, u)``: a
        slide going on (``going_on``: sliding before the event and after its action) takes
        its slip velocity's direction (keeps its own below :data:`V_TINY`); a slide from
        rolling (a break-away: its slip speed is the rolling rows' drift, of no direction)
        starts along the direction of :func:`start_directions` nearest ``-F_t / |F_t|``, the
        load its rolling rows held."""
        dirs, fresh = {}, []
        for n in slipping_joints(self.system, modes):
            if n not in going_on:  # a new slide: its fastest slip so far is its own
                self._slip_peak.pop(n, None)
            v_t = tangent_rows(self.system, n, t, q, u)[1]
            if np.linalg.norm(v_t) > TURN * self.atol or (n in going_on and (np.linalg.norm(v_t) > V_TINY
                                                                              or n in self.slip_dirs)):
                dirs[n] = v_t / np.linalg.norm(v_t) if np.linalg.norm(v_t) > V_TINY else self.slip_dirs[n]
            else:
                rolling = self.system.edge(n).comp.modes(self.system.P[n]).action("stick", modes[n]).mode
                F = closed_force(self.system_now({**modes, n: rolling}), n, t, q, u)
                size = float(np.linalg.norm(F))
                dirs[n] = -F / size if size > 0.0 else np.eye(len(F))[0]
                fresh.append(n)
        if fresh:
            plain = with_mode_forces(mode_system(self.system, modes), modes)  # the sliding mode without friction
            dirs = start_directions(plain, slips_of(self.system, modes, dirs), t, q, u, fresh)
        return dirs

    def _rolling_at_start(self, t, q, u, modes):
        """``modes`` with the contacts that start sliding (a contact with friction starts in
        its sliding mode, its speeds as given) but whose slip speed is zero (at most
        ``atol``) rolling (``Modes.action("stick")``)."""
        out = dict(modes)
        for n in slipping_joints(self.system, modes):
            if np.linalg.norm(tangent_rows(self.system, n, t, q, u)[1]) <= self.atol:
                out[n] = self.system.edge(n).comp.modes(self.system.P[n]).action("stick", modes[n]).mode
        return out
