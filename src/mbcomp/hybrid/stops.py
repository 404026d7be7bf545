"""Rows held on a tree joint's own coordinate: an engaged end stop's (or a stuck friction's)
values, pushes and impacts, and the state made consistent with a new active set.

The system of an active set (:func:`~mbcomp.hybrid.active.mode_system`) holds the rows its
modes hold (:class:`~mbcomp.modeling.events.AxisRow`: ``sign (s - at)`` on a tree joint's
coordinate: an engaged stop, a stuck friction) appended after its holonomic rows; the
formulation is built again over it at every change of mode, so every formulation and every
backend steps every mode. Here are the rows' values (:func:`row_values`), their pushes (the
multipliers, :func:`row_push`), the impact closing them (:func:`impact_speeds`), the move of
a state onto a new mode's rows (:func:`consistent`) and, after the run, the columns at an
output where rows hold or forces act (:func:`engaged_values`, for
:func:`mbcomp.simulation.hybrid_columns.segment_columns`).

At an impact the speeds jump by the impulse equations (:func:`impact_speeds`), the rows
kept closed throughout (loops, engaged stops) staying closed; a change of mode moves
positions and speeds onto the new mode's rows (:func:`consistent`).

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute(limits=(-0.1, 0.1)))
>>> rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0))); bob = m.add("bob", PointMass(m=2.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> from mbcomp.hybrid.active import mode_system
>>> system = mbcomp.assemble(m)
>>> held = mode_system(system, {"j": "lo"})
>>> ev = held.evaluate(0.0, np.array([-0.05]), np.array([0.3]))
>>> ev.Phi.tolist(), ev.C.tolist()        # the row phi - lo, 0.05 rad on the allowed side
([0.05], [[1.0]])
"""
from __future__ import annotations

import numpy as np

from ..assembly.kkt import accelerations, project_state
from .active import evaluation_within, mode_rows, rows_in_force, system_in_force

__all__ = ["row_values", "impact_speeds", "consistent", "row_push", "stop_joints", "stop_units", "changes_dynamics",
           "engaged_values"]


def row_values(system, rows, q, u):
    """``(values, speeds, C)`` of ``rows`` (``[(joint, AxisRow, iq, iu)]``) at ``(q, u)``."""
    C = np.zeros((len(rows), system.nu))
    for i, (_, row, _, iu) in enumerate(rows):
        C[i, iu] = row.sign
    vals = np.array([row.value(q[iq]) for _, row, iq, _ in rows])
    return vals, C @ u, C


def impact_speeds(system, t, q, u_minus, rows, restitution):
    """``(u+, impulses (N s or N m s), kinetic energy lost (J))`` of an impact closing ``rows``
    on ``system`` (the system of the modes before the impact: its rows hold through it).

    :func:`mbcomp.assembly.impacts.impulse`: ``M (u+ - u-) = C^T Lambda`` with Newton's
    restitution ``C_i u+ = -e C_i u-`` on the impact's rows and the kept rows (loops,
    engaged stops, velocity rows) holding; an impulse that would pull is dropped."""
    from ..assembly.impacts import impulse

    ev = system.evaluate(t, q, u_minus)
    _, _, Ci = row_values(system, rows, q, u_minus)
    A = ev.A
    ma = A.shape[0]
    offset = np.concatenate((ev.Phid - ev.C @ u_minus, ev.Psi - ev.B @ u_minus if ev.B.size else np.zeros(0),
                             np.zeros(len(rows))))
    u_plus, lam = impulse(ev.M, np.vstack((A, Ci)), u_minus, list(range(ma, ma + len(rows))), restitution,
                          keep_rows=list(range(ma)), offset=offset)
    loss = 0.5 * (u_minus @ ev.M @ u_minus - u_plus @ ev.M @ u_plus)
    return u_plus, lam[ma:], float(loss)


def consistent(system, t, q, u):
    """``(q, u)`` moved onto ``system``'s rows (positions by Newton, speeds by least squares;
    as the Lagrange projection does)."""
    y = project_state(system, t, np.concatenate((q, u)))
    return y[: system.nq], y[system.nq:]


def row_push(system, t, q, u, first, k):
    """The push (N or N m, >= 0 while the rows press) of the ``k`` mode rows appended at
    ``first`` among ``system``'s holonomic rows: minus their multipliers in the index-1
    solve without stabilization."""
    ev = system.evaluate(t, q, u)
    _, lam = accelerations(ev)
    return -lam[first:first + k]


def stop_joints(system, segments):
    """The joints whose stop is engaged in some segment of ``segments`` (the run's
    :class:`~mbcomp.hybrid.active.SegmentStart` list; a sticking friction's row is no stop)."""
    return sorted({n for seg in segments for n, *_ in _stop_rows(system, seg.modes)})


def stop_units(system, names):
    """``{"<joint>.stop": unit}`` of the stops of ``names``: N m on a rotational axis, else N."""
    return {f"{n}.stop": "N m" if system.edge(n).comp.axis_kind == "rotational" else "N" for n in names}


def changes_dynamics(system, modes):
    """Whether ``modes`` hold rows (engaged stops, a stuck friction's row) or apply forces
    (a slipping friction's) the assembled system lacks: their columns (the speeds' rates, the
    reactions and drive efforts carrying them) are solved again over the mode's system
    (:func:`engaged_values`)."""
    in_force = rows_in_force(system, modes)
    return bool(in_force.held or in_force.forces)


def _stop_rows(system, modes):
    """The engaged stops' rows of ``modes`` (:func:`mode_rows`, a sticking friction's
    :class:`~mbcomp.modeling.events.StickRow` left out)."""
    return [r for r in mode_rows(system, modes) if not _is_stick(r[1])]


def engaged_values(system, sysm, modes, t, q, u, *, in_force=None, base=None):
    """``(columns, {joint: push})`` at ``(t, q, u)`` in the active set ``modes`` whose rows
    hold or forces act (:func:`changes_dynamics`): the speeds' rates and multipliers of the
    mode's system ``sysm`` (index-1 solve without stabilization), every column written again
    from them over the system without the stops' rows (its reactions, by the backward pass,
    then carry a stop's force or torque: it acts across the joint), and each engaged stop's
    push along its axis (N or N m, minus its row's multiplier, positive pushing the joint away
    from the limit into the allowed range).

    ``in_force`` (``rows_in_force(system, modes)``) and ``base`` (``system_in_force(system,
    in_force, held=False)``) may be passed in, made once for many outputs of one segment."""
    from types import SimpleNamespace

    from ..assembly.outputs import result_columns

    # a sliding contact's rolling rows are out here too (its friction is then in no reaction)
    in_force = rows_in_force(system, modes) if in_force is None else in_force
    base = system_in_force(system, in_force, held=False) if base is None else base
    rows = list(in_force.held)
    ev = sysm.evaluate(t, q, u)
    ud, lam = accelerations(ev)
    first = ev.Phi.size - len(rows)  # the mode's rows follow the holonomic rows
    pushes = {n: -float(lam[first + i]) for i, (n, row, _, _) in enumerate(rows) if not _is_stick(row)}
    lam_b = np.concatenate((lam[:first], lam[first + len(rows):]))
    evb = evaluation_within(sysm, ev, base)  # the mode's evaluation wraps the base's
    evb = base.evaluate(t, q, u) if evb is None else evb
    evf = base.evaluate(t, q, u, masked=False) if evb.local else evb
    cols = SimpleNamespace(t=t, q=q, u=u, jets=evb.jets, local_nh=evb.local_nh, B=evb.B, Phi_all=evf.Phi,
                           Phid_all=evf.Phid, Psi=evb.Psi)
    values, _ = result_columns(base, cols, ud, lam_b, base.reactions(evb, ud, lam_b))
    return values, pushes


def _is_stick(row):
    from ..modeling.events import StickRow

    return isinstance(row, StickRow)
