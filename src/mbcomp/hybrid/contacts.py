"""Unilateral contacts in a run: a contact's rows in and out of the system, its gap and its impacts.

A contact (a cut joint, ``tree_edge = False``) with modes holds its own rows -- the
holonomic ``constraints`` and the ``velocity_constraints`` (rolling) -- only in the modes
where :meth:`~mbcomp.modeling.modes.Modes.holds_rows` is true (``"closed"``). In an
``"open"`` mode the system is the assembled one *without* them (:func:`~mbcomp.hybrid.active.without_rows`: a
numeric variant whose topology no longer cuts the contact, its row mask restricted to the
other rows), so every formulation steps the free flight unchanged. The contact's rows are
read straight from the frames' jets (:func:`contact_rows`): the gap (its normal row's value,
m) is the event while open, the normal row's Jacobian and the rolling rows make the impact at
touch-down (:func:`contact_impact`). A run whose contact starts open is initialized without
its rows (:func:`initialize_in_modes`).

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, PlaneContact, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> b = m.add("ball", PointMass(m=2.0), free=True)
>>> c = m.add("ground", PlaneContact(unilateral=True))
>>> m.connect(w.frame_b, c.frame_a); m.connect(c.frame_b, b.frame_a)
>>> system = mbcomp.assemble(m)
>>> len(system.constraint_names()), len(without_rows(system, ["ground"]).constraint_names())
(1, 0)
"""
from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np

from ..assembly.kkt import accelerations
from .active import open_joints, rows_in_force, start_modes, system_in_force, without_rows

__all__ = ["contact_rows", "contact_impact", "initialize_in_modes", "event_value",
           "contact_pushes", "tangent_force", "zero_open", "open_force_columns", "touching_at_start",
           "inward_gap_acceleration", "INWARD"]

#: a contact let go whose gap accelerates into the surface by more than this fraction of the
#: size of its acceleration terms (``|C_n| |du/dt| + |c_b,n|``) contradicts itself: see
#: :func:`inward_gap_acceleration`
INWARD = 1e-6


def contact_rows(system, name, t, q, u, row="normal", jets=None):
    """The rows of contact ``name`` at ``(t, q, u)`` from the frames' jets (``jets``: those of
    an evaluation at ``(t, q, u)``, else computed).

    Returns a namespace: ``gap`` (m, the holonomic ``row``'s value), ``speed`` (m/s, its
    rate), ``C`` (k, nu: the ``row`` first, then the velocity rows), ``offset`` (k,: each row's
    rate at ``u = 0``), ``bias`` (k,: the rows' rates' time derivatives at ``du/dt = 0``)."""
    e, p = system.edge(name), system.P[name]
    jets = system.kinematics(t, q, u) if jets is None else jets
    a, b = jets[e.node_a], jets[e.node_b]
    J = np.vstack((a.Jv, a.Jw, b.Jv, b.Jw))
    hol = dict(e.comp.constraints(a, b, p))
    if row not in hol:
        raise KeyError(f"{name}: no holonomic row {row!r} (rows: {', '.join(hol)})")
    rows = [hol[row]] + [c for _, c in e.comp.velocity_constraints(a, b, p)]
    C = np.array([np.asarray(c.jac, float) @ J for c in rows]).reshape(len(rows), system.nu)
    rate = np.array([float(c.dot) for c in rows[:1]] + [float(c.val) for c in rows[1:]])
    return SimpleNamespace(gap=float(hol[row].val), speed=float(rate[0]), C=C, offset=rate - C @ u,
                           bias=np.array([float(c.bias) for c in rows]))


def event_value(system, name, value, t, q, u):
    """A joint's event value: a number, or the value (m) of its own row ``value``
    (:class:`~mbcomp.modeling.events.ContactRow`: a contact's gap while open)."""
    from ..modeling.events import ContactRow

    if isinstance(value, ContactRow):
        return contact_rows(system, name, t, q, u, value.name).gap
    return float(value)


def contact_pushes(system, sysm, modes, t, q, u):
    """``{contact: {("release", contact, row): push}}`` (N, >= 0 while pressing) of the rows
    the contacts of ``modes`` hold (:class:`~mbcomp.modeling.events.ContactRow`) on the mode's
    system ``sysm``: minus their multipliers in the index-1 solve without stabilization. A
    row with a friction cone (``mu_s``) adds ``("joint", contact, "slide"): mu_s N - |F_t|``
    (N), ``F_t`` the force of the contact's rolling rows (:func:`tangent_force`)."""
    from ..modeling.events import ContactRow

    held = [(n, r) for n, mode in sorted(modes.items()) if not system.edge(n).comp.tree_edge
            for r in system.edge(n).comp.modes(system.P[n]).rows(mode) if isinstance(r, ContactRow)]
    if not held:
        return {}
    ev = sysm.evaluate(t, q, u)
    _, lam = accelerations(ev)
    mult = sysm.row_multipliers(ev, lam)
    out = {}
    for n, row in held:
        if row.name in mult.get(n, {}):  # a row dropped as redundant has no multiplier of its own
            push = -float(mult[n][row.name])
            out.setdefault(n, {})[("release", n, row.name)] = push
            if row.mu_s is not None:
                out[n][("joint", n, "slide")] = row.mu_s * push - float(np.linalg.norm(tangent_force(ev, mult, n)))
    return out


def tangent_force(ev, mult, name):
    """The force (N, on frame_b's body, along each rolling row's tangent) of contact ``name``'s
    velocity rows: minus their multipliers ``mult`` (:meth:`row_multipliers
    <mbcomp.assembly.system.MultibodySystem.row_multipliers>` at the evaluation ``ev``)."""
    rows = [r for e, names, _ in ev.local_nh if e.name == name for r in names]
    return np.array([-float(mult[name][r]) for r in rows])


def inward_gap_acceleration(system, sysm, name, t, q, u):
    """The gap acceleration (m/s^2) of contact ``name``, open in the mode's system ``sysm`` at
    ``(t, q, u)``, where it points into the surface beyond rounding (below -:data:`INWARD`
    times the size of its terms), else None.

    A contact let go because it would pull (its push fell through zero) separates: with one
    row (a point on a plane) the open gap's acceleration is the pull's own sign. With rolling
    rows it need not be: their tangential force does not vanish with the normal one (a wheel
    whose rows hold no slip needs an unbounded friction coefficient as ``N -> 0``), and once
    open the body may accelerate into the surface -- closed it pulls, open it penetrates, no
    mode is consistent (Painleve-like). A run must fail there, not fly the body through the
    surface (its touch event, the gap falling *through* zero, cannot fire from a gap that
    starts at zero and falls)."""
    ud, _ = accelerations(sysm.evaluate(t, q, u))
    cr = contact_rows(system, name, t, q, u)
    a = float(cr.C[0] @ ud + cr.bias[0])
    scale = float(np.linalg.norm(cr.C[0]) * np.linalg.norm(ud) + abs(cr.bias[0]))
    return a if a < -INWARD * scale else None


def contact_impact(system, name, t, q, u_minus, restitution, row="normal", friction=None):
    """``(u+, impulses (N s), kinetic energy lost (J), normal speed after (m/s))`` of contact
    ``name`` touching down at ``(t, q, u-)`` on ``system`` (the system before, the contact
    open: its other rows hold through the impact).

    The impact rows are the contact's own: its normal ``row`` with Newton's restitution
    (``C_n u+ = -e C_n u-``), its rolling rows (velocity rows) held, ``B u+ = b``: without
    ``friction`` a rolling contact's impact is perfectly rough (the no-slip rows take
    whatever tangential impulse they need; no tangential restitution). An impulse that would
    pull is dropped (:func:`mbcomp.assembly.impacts.impulse`).

    With ``friction = (mu_s, mu_k)`` the rough impulse stands only inside the cone,
    ``|P_t| <= mu_s P_n``; beyond it the contact slides through the impact: the tangential
    impulse is ``-mu_k P_n s`` against the slip direction before it
    (:func:`~mbcomp.assembly.impacts.sliding_impulse`;
    exact while the slip keeps its direction through the impact, as on a ball)."""
    from ..assembly.impacts import impulse, sliding_impulse

    ev = system.evaluate(t, q, u_minus)
    cr = contact_rows(system, name, t, q, u_minus, row)
    A, ma, k = ev.A, ev.A.shape[0], cr.C.shape[0]
    offset = np.concatenate((ev.Phid - ev.C @ u_minus, ev.Psi - ev.B @ u_minus if ev.B.size else np.zeros(0),
                             cr.offset))
    keep = list(range(ma)) + list(range(ma + 1, ma + k))
    u_plus, lam = impulse(ev.M, np.vstack((A, cr.C)) if ma else cr.C, u_minus, [ma], restitution, keep_rows=keep,
                          offset=offset)
    imp = lam[ma:]
    if friction is not None and k > 1 and np.linalg.norm(imp[1:]) > friction[0] * imp[0]:
        v_t = cr.C[1:] @ u_minus + cr.offset[1:]
        s = v_t / np.linalg.norm(v_t) if np.linalg.norm(v_t) > 0.0 else -imp[1:] / np.linalg.norm(imp[1:])
        u_plus, imp = sliding_impulse(ev.M, ev.A, u_minus, offset[:ma], cr.C[0], cr.C[1:],
                                      cr.C[0] @ u_minus + cr.offset[0], restitution, friction[1], s)
    loss = 0.5 * (u_minus @ ev.M @ u_minus - u_plus @ ev.M @ u_plus)
    return u_plus, imp, float(loss), float(cr.C[0] @ u_plus + cr.offset[0])


def initialize_in_modes(system, t0):
    """:func:`~mbcomp.assembly.initialization.initialize` with the rows of contacts that start
    open left out (their body starts where its start values put it); ``system.row_mask`` is
    then the mask of the assembled rows (an open contact's rows counted independent)."""
    from ..assembly.initialization import initialize

    system.row_mask = None
    in_force = rows_in_force(system, start_modes(system))
    names, sliding = in_force.open, in_force.sliding  # a contact starting to slide: its speeds as given
    if not names and not sliding:
        return initialize(system, t0)
    sub = system_in_force(system, in_force, held=False)
    init = initialize(sub, t0)
    if not names:
        system.row_mask = sub.row_mask
        return init
    keep = np.array([n.rsplit(".", 1)[0] not in names for n in system.constraint_names(all_rows=True)], bool)
    mask = np.ones(keep.size, bool)
    mask[keep] = sub.row_mask
    system.row_mask = mask
    return replace(init, row_mask=mask)


def zero_open(series, system, names, k, units=None):
    """Set the force columns (N or N m) of the open contacts ``names`` to 0 at output ``k``
    (an index, or an array of them)."""
    for col in open_force_columns(series, system, names, units):
        series[col][k] = 0.0


def open_force_columns(series, system, names, units=None):
    """The columns of ``series`` that are force columns (N or N m) of the open contacts
    ``names`` (``units``: ``column_units(system)``, made when not given): what
    :func:`zero_open` sets to 0."""
    if not names:
        return []
    if units is None:
        from ..assembly.column_units import column_units

        units = column_units(system)
    out = []
    for col in series:
        own = [col[len(n) + 1:] for n in names if col.startswith(n + ".")]
        if own and (units.get(col) in ("N", "N m") or own[0] == "N" or own[0].startswith(("F_", "f.", "tau."))):
            out.append(col)
    return out


def touching_at_start(system, modes, t, q, u, tol):
    """``[(contact, event, action, row, gap (m), normal speed (m/s))]`` of the contacts open
    in ``modes`` that touch at the start ``(t, q, u)`` (``action``: the contact's
    ``Modes.action(event)``, its touch-down impact): the gap of their touch event's row
    (:class:`~mbcomp.modeling.events.ContactRow`) within ``tol`` (m) of zero, rounding's
    -1e-17 m included (its event, the gap falling through zero, could never fire from
    there: the body would pass through). An :class:`~mbcomp.errors.InitializationError`
    names every contact that starts inside beyond ``tol``, with its depth and the fix.

    Examples
    --------
    A ball of radius 0.1 m whose centre starts at 0.1 m less rounding's 1.4e-17 m:

    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, PlaneContact, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> b = m.add("ball", PointMass(m=2.0), free=True)
    >>> c = m.add("ground", PlaneContact(r=0.1, unilateral=True, open0=True))
    >>> m.connect(w.frame_b, c.frame_a); m.connect(c.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> q, u = np.array([0.0, 0.0, 0.1 - 1e-17]), np.zeros(3)    # the free ball: r (m), v (m/s)
    >>> [(n, ev, row, gap < 0) for n, ev, _, row, gap, _ in touching_at_start(system, {"ground": "open"}, 0.0, q, u, 1e-9)]
    [('ground', 'touch', 'normal', True)]
    """
    from ..errors import InitializationError, Problem
    from ..modeling.events import ContactRow

    edges = {e.name: e for e in system.topology.edges}
    out, inside = [], []
    for n in open_joints(system, modes):
        e, p = edges[n], system.P[n]
        if e.comp.tree_edge:
            continue
        for name, value, _ in e.comp.modes(p).events(q[e.q], u[e.u], modes[n]):
            if not isinstance(value, ContactRow):
                continue
            cr = contact_rows(system, n, t, q, u, value.name)
            if cr.gap < -tol:
                inside.append(Problem(n, f"starts {-cr.gap:.3g} m inside what it touches (its row {value.name!r} is "
                                         f"{cr.gap:.3g} m at t={t:g} s; touching is within {tol:.3g} m): a one-sided "
                                         "contact cannot start inside, its body would pass through",
                                      f"move the body's start {-cr.gap:.3g} m out along the contact's normal, or "
                                      "start the contact closed (open0=False) with the start position a Guess(...) "
                                      "so the initialization puts it on the surface"))
            elif cr.gap <= tol:
                out.append((n, name, e.comp.modes(p).action(name, modes[n]), value.name, cr.gap, cr.speed))
    if inside:
        raise InitializationError(inside, "a contact starts inside what it touches")
    return out
