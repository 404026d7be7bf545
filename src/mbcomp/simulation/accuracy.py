"""Accuracy alarms: a conserved quantity that drifted more than the tolerances promise.

A run that reached ``t_end`` is not necessarily right: a 2,000 s pendulum at rtol 1e-6 ended
0.165 m from the exact position, a cart-pole at scipy's default tolerances gained 6.2 J in a
conservative system, and both reported "success" although mbcomp computes the energy that
shows the error. When every component declares that it conserves energy
(:func:`mbcomp.assembly.conservation.nonconservative` is empty: no damper, drive
or applied law) the total energy is a constant of the motion, and its drift measures the
integration error. :func:`energy_alarm` compares the drift (the deviation from the start
value exceeded over a tenth of the output grid: a drift, not one bad point) with the energy the
motion exchanges (the largest kinetic energy plus the range of the potential one): above
:data:`ALARM_RTOL` times ``rtol`` and above :data:`ALARM_FLOOR` (below it a plot cannot show
the error) the run's status becomes ``"inaccurate"`` and its message gives the drift and the
tolerance that would bring it under the floor (the drift scales about linearly with the
tolerance, and is above 100 tolerances already).

Examples
--------
>>> import numpy as np
>>> t = np.linspace(0.0, 10.0, 11)
>>> T, V = 2.0 + np.cos(t), -np.cos(t)            # conserved: E = 2 J
>>> status, msg = energy_alarm(T, V - 0.01 * t, rtol=1e-6)   # loses 0.1 J by t = 10 s
>>> status, msg.split(";")[0]
('inaccurate', 'accuracy alarm: the total energy drifted by 0.09 J (1.8e-02 of the 4.98 J the motion exchanges, over a tenth of the run) in a conservative system')
>>> energy_alarm(T, V, rtol=1e-6)
(None, '')
"""
from __future__ import annotations

import math

import numpy as np

from ..assembly.recursive import generalized_forces, generalized_momenta, tree_pass

__all__ = ["energy_alarm", "balance_alarm", "momentum_alarm", "between_events", "tolerance_energy", "ALARM_RTOL",
           "ALARM_FLOOR", "DRIFT_SHARE", "TOLERANCE_SPAN"]

#: a relative energy drift above this many times ``rtol`` is more than the tolerance promises
#: (global errors grow over a run: the bar leaves room for 100 tolerances' worth)
ALARM_RTOL = 100.0
#: ... and above this relative drift (below it, the plotted motion is right)
ALARM_FLOOR = 1e-5
#: the drift is the deviation from the start exceeded over this share of the output grid
DRIFT_SHARE = 0.1
#: ... and above this many times the energy the tolerances leave open at one state
#: (:func:`tolerance_energy`): a nearly still mechanism exchanges almost no energy, so the
#: bars relative to the exchanged energy would judge the tolerance's own resolution. A few
#: states' worth: the dense output between steps is accurate to a few tolerances (a ball
#: resting on a floor under DOP853's 0.5 s steps: 1.7 tolerances, 1.3 times the energy one
#: state leaves open); a drift that grew over many steps beyond it is the integration's (a
#: pendulum spinning to 300 rad at rtol 1e-5 leaves 0.03 J open and drifts 0.29 J)
TOLERANCE_SPAN = 3.0
#: output points at most on which :func:`tolerance_energy` evaluates the mechanism
TOLERANCE_POINTS = 20
#: speeds from which :func:`tolerance_energy` takes ``f`` and ``M u`` where it has neither the
#: output program's terms nor the start's evaluation from the recursive pass (O(N): 0.07 s a
#: point at 1000 links against 0.4 s for the dense evaluation; the same numbers to rounding),
#: as initialization checks the inertia of a tree that large (``TREE_CHECK_SPEEDS``)
RECURSIVE_SPEEDS = 20


def _rounding(T, V):
    """The rounding (J) of energies summed from terms as large as ``|T| + |V|``: a hundred
    roundings of the largest (a pendulum swinging 1e-7 rad exchanges 1e-13 J of its 9.81 J)."""
    return 100.0 * np.finfo(float).eps * float(np.max(np.abs(T) + np.abs(V)))


def tolerance_energy(system, t, Y, rtol, atol, known=None, terms=None):
    """The energy (J) the integration tolerances leave open: how far ``E = T + V`` moves when
    every state moves by its tolerance, ``sum |dE/dq_i| (atol + rtol |q_i|) + |dE/du_i| (atol +
    rtol |u_i|)``, with ``dE/du = M u`` (the momenta) and ``|dE/dq|`` sized by the generalized
    forces ``f`` (``-dV/dq`` at rest); the largest over up to :data:`TOLERANCE_POINTS` of the
    outputs ``Y`` (``[q, u]`` rows at times ``t``, s). A ball resting on a floor at rtol 1e-10
    leaves ``m g rtol z`` open: its energy wanders by that much, and exchanges nothing else.
    ``known``: an evaluation of ``system`` already made (the start's), taken instead of
    evaluating again at an output of exactly its time and state. ``terms``: ``(F, P, ok)``,
    the generalized forces and momenta ``M u`` at every output (arrays ``(n, nu)``, the output
    program's hidden columns, :func:`mbcomp.assembly.outputs.tolerance_terms`) and where they
    hold: taken instead of evaluating there.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -10.0)))
    >>> j = m.add("j", Prismatic(n=(0, 0, 1), s0=2.0)); b = m.add("b", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
    >>> s = mbcomp.assemble(m)                     # 10 N along z = 2 m, at rest: 10 (1e-12 + 1e-10 2)
    >>> float(np.round(tolerance_energy(s, [0.0], np.array([[2.0, 0.0]]), 1e-10, 1e-12), 15))
    2.01e-09
    """
    Y = np.asarray(Y, float)
    if not len(Y):
        return 0.0
    nq, nu = system.nq, system.nu
    atol = float(np.max(atol))
    rtol = float(np.max(rtol))
    worst = 0.0
    ks = np.unique(np.linspace(0, len(Y) - 1, min(len(Y), TOLERANCE_POINTS)).astype(int))
    if terms is not None:  # the points the output program holds, at once
        Q, U = Y[ks, :nq], Y[ks, nq:nq + nu]
        held = terms[2][ks] & np.isfinite(Q).all(axis=1) & np.isfinite(U).all(axis=1)
        if held.any():
            Q, U, F, P = Q[held], U[held], np.abs(terms[0][ks[held]]), np.abs(terms[1][ks[held]])
            dq = atol + rtol * (np.abs(Q) if nq == nu else np.max(np.abs(Q), axis=1, initial=0.0)[:, None])
            worst = float(np.max(np.sum(F * dq, axis=1) + np.sum(P * (atol + rtol * np.abs(U)), axis=1)))
        ks = ks[~held]
    for k in ks:
        q, u = Y[k, :nq], Y[k, nq:nq + nu]
        if not (np.isfinite(q).all() and np.isfinite(u).all()):
            continue
        try:
            at_start = _at(known, t[k], q, u)
            if not at_start and nu >= RECURSIVE_SPEEDS:  # O(N): no dense M
                tp = tree_pass(system, t[k], q, u)
                f, p = np.abs(generalized_forces(tp, nu)), np.abs(generalized_momenta(tp, u, nu))
            else:
                ev = known if at_start else system.evaluate(t[k], q, u)
                f, p = np.abs(np.asarray(ev.f, float)), np.abs(np.asarray(ev.M, float) @ u)
        except Exception:  # noqa: BLE001 - a state the mechanism cannot evaluate adds nothing here
            continue
        dq = atol + rtol * (np.abs(q) if nq == nu else np.max(np.abs(q), initial=0.0))
        worst = max(worst, float(f @ (dq * np.ones(nu)) + p @ (atol + rtol * np.abs(u))))
    return worst


def _at(ev, t, q, u):
    """Whether the evaluation ``ev`` (or None) is at exactly the time ``t`` and state ``q, u``."""
    return (ev is not None and ev.t == t and np.array_equal(np.asarray(ev.q), q)
            and np.array_equal(np.asarray(ev.u), u))


def _drift(x):
    """The deviation of the rows of ``x`` (n, k) from the first exceeded over
    :data:`DRIFT_SHARE` of them (a drift, not one bad point)."""
    d = np.abs(x - x[0]) if x.ndim == 1 else np.linalg.norm(x - x[0], axis=1)
    return float(np.quantile(d, 1.0 - DRIFT_SHARE))


def _fix(rtol, rel):
    """The tolerance that brings a drift of ``rel`` at ``rtol`` under the floor (the drift
    scales about linearly with rtol and already exceeds 100 rtol, so only the floor can be
    met: rel r'/r <= floor), as the message's advice."""
    suggest = float(np.max(rtol)) * ALARM_FLOOR / rel
    suggest = 10.0 ** math.floor(math.log10(suggest)) if suggest > 0 else 0.0
    return (f"rerun with rtol={suggest:.0e} (and atol 100 times smaller)" if suggest >= 1e-13 else
            "no tolerance reaches it in double precision: shorten the run")


def momentum_alarm(P, L, P_scale, L_scale, rtol):
    """``(status, message)`` of the alarm on the linear and angular momenta ``P``, ``L``
    ((n, 3): kg m/s, kg m^2/s about the world origin) of a mechanism nothing outside loads
    (:func:`mbcomp.assembly.conservation.momentum_conserved`), relative to the
    sums of the bodies' contributions' magnitudes ``P_scale``, ``L_scale`` (their largest
    over the run), at ``rtol``: ``("inaccurate", text)`` or ``(None, "")``.

    Examples
    --------
    >>> P = np.tile([1.0, 0.0, 0.0], (11, 1)); L = np.tile([0.0, 0.0, 2.0], (11, 1))
    >>> momentum_alarm(P, L, 1.0, 2.0, 1e-8)
    (None, '')
    >>> L[:, 2] += np.linspace(0.0, 1e-3, 11)                 # a growing error in L
    >>> momentum_alarm(P, L, 1.0, 2.0, 1e-8)[1].split(";")[0]
    'accuracy alarm: the angular momentum drifted by 0.0009 kg m^2/s (4.5e-04 of its scale 2) although nothing outside the mechanism loads it'
    """
    bar = max(ALARM_RTOL * float(np.max(rtol)), ALARM_FLOOR)
    for name, x, scale, unit in (("linear momentum", P, P_scale, "kg m/s"), ("angular momentum", L, L_scale,
                                                                              "kg m^2/s")):
        x = np.asarray(x, float)
        x = x[np.isfinite(x).all(axis=1)]
        if len(x) < 2 or not scale > 0.0:
            continue
        drift = _drift(x)
        rel = drift / scale
        if rel > bar:
            return "inaccurate", (f"accuracy alarm: the {name} drifted by {drift:.2g} {unit} ({rel:.1e} of its "
                                  f"scale {scale:.3g}) although nothing outside the mechanism loads it; "
                                  f"rtol={float(np.max(rtol)):g} promises about {bar:.0e} -> {_fix(rtol, rel)}")
    return None, ""


def energy_alarm(T, V, rtol, floor=0.0):
    """``(status, message)`` of the alarm on the kinetic and potential energies ``T``, ``V``
    (J, on the output grid) of a conservative system integrated at ``rtol``: ``("inaccurate",
    text)`` or ``(None, "")``. A drift within the energies' rounding or within
    :data:`TOLERANCE_SPAN` times ``floor`` (J, what the tolerances leave open:
    :func:`tolerance_energy`) rings no alarm."""
    T, V = np.asarray(T, float), np.asarray(V, float)
    E = T + V
    ok = np.isfinite(E)
    if ok.sum() < 2:
        return None, ""
    scale = float(np.max(T[ok]) + np.ptp(V[ok]))
    if not scale > 0.0:
        return None, ""
    # a drift, not a spike: exceeded over a tenth of the run (BDF's interpolated outputs next
    # to a near-flat four-bar were off by 2e-4 at one point of 251, and right before and after)
    drift = _drift(E[ok])
    rel = drift / scale
    bar = max(ALARM_RTOL * float(np.max(rtol)), ALARM_FLOOR)
    if rel <= bar or drift <= _rounding(T[ok], V[ok]) or drift <= TOLERANCE_SPAN * floor:
        return None, ""
    return "inaccurate", (f"accuracy alarm: the total energy drifted by {drift:.2g} J ({rel:.1e} of the "
                          f"{scale:.3g} J the motion exchanges, over a tenth of the run) in a conservative system; "
                          f"rtol={float(np.max(rtol)):g} "
                          f"promises about {bar:.0e} -> {_fix(rtol, rel)}")


def balance_alarm(balance, T, V, work, dissipated, quadrature, rtol, floor=0.0):
    """``(status, message)`` of the alarm on the energy balance (J, on the output grid) of a
    driven or damped mechanism (:mod:`mbcomp.simulation.balance`) integrated at ``rtol``: as
    :func:`energy_alarm`, relative to the energy the motion exchanges (largest kinetic energy,
    range of the potential one, largest work and dissipation), and only when the output
    grid's ``quadrature`` estimate (J) is below a tenth of the balance error -- else the grid,
    not the integration, may be what is off: no alarm, ``(None, note)`` saying so -- and the
    error is above the rounding of the energies (a body at rest exchanges 1e-15 J) and above
    :data:`TOLERANCE_SPAN` times ``floor`` (J, :func:`tolerance_energy`).

    Examples
    --------
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> T, V, D = np.exp(-t), np.zeros(101), 1.0 - np.exp(-t)   # a damped motion, balanced
    >>> balance_alarm(T + D - 1.0, T, V, 0 * t, D, 0.0, 1e-6)
    (None, '')
    >>> balance_alarm(T + D - 1.0 + 1e-3 * t, T, V, 0 * t, D, 0.0, 1e-6)[1].split(";")[0]
    'accuracy alarm: the energy balance is off by 0.009 J (4.5e-03 of the 2 J the motion exchanges, over a tenth of the run)'
    """
    arrays = [np.asarray(x, float) for x in (balance, T, V, work, dissipated)]
    ok = np.all([np.isfinite(x) for x in arrays], axis=0)
    if ok.sum() < 2:
        return None, ""
    balance, T, V, work, dissipated = (x[ok] for x in arrays)
    scale = float(np.max(T) + np.ptp(V) + np.max(np.abs(work)) + np.max(np.abs(dissipated)))
    if not scale > 0.0:
        return None, ""
    drift = _drift(balance)
    rel = drift / scale
    bar = max(ALARM_RTOL * float(np.max(rtol)), ALARM_FLOOR)
    rounding = 1e3 * np.finfo(float).eps * (scale + float(np.max(np.abs(T) + np.abs(V))))
    if rel <= bar or drift <= rounding or drift <= TOLERANCE_SPAN * floor:
        return None, ""
    if quadrature >= 0.1 * drift:
        return None, (f"the energy balance ({drift:.2g} J off) cannot be judged on this output grid: the elements' "
                      "power changes faster than the grid samples it -> more output points (n_out) to check it")
    return "inaccurate", (f"accuracy alarm: the energy balance is off by {drift:.2g} J ({rel:.1e} of the "
                          f"{scale:.3g} J the motion exchanges, over a tenth of the run); "
                          f"rtol={float(np.max(rtol)):g} promises about {bar:.0e} -> {_fix(rtol, rel)}")


def between_events(x, t, times):
    """``x`` (on the output grid ``t``, s) less its changes over the intervals that hold one
    of the event ``times`` (s) and the intervals on either side (cumulative Simpson, which
    integrates the work, fits each interval's parabola through a neighbour's point: a jump
    inside an interval spreads its error to the one before it and, across grid parities, to
    the one after): what drifts between the events.

    A power that jumps inside an interval (a friction breaking away, a load landing on a
    stop) is integrated there with an error of the jump times the interval, which is the
    output grid's, not the integration's: it is no drift.

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> x = np.where(t > 0.45, 0.3, 0.0) + 1e-3 * t      # a step at 0.45 s, a slow drift
    >>> np.round(between_events(x, t, [0.45]), 6).tolist()[-1]
    0.0007
    """
    x = np.asarray(x, float)
    k = np.searchsorted(t, np.asarray(times, float), side="left")
    k = np.unique(np.concatenate((k - 1, k, k + 1)))
    k = k[(k > 0) & (k < len(t))]
    step = np.zeros(len(t))
    step[k] = x[k] - x[k - 1]
    return x - np.cumsum(step)
