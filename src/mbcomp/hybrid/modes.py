"""Modes of a run: the system with the engaged unilateral rows, impacts, consistent restarts.

A run with components that have modes (:meth:`mbcomp.modeling.roles.Joint.start_mode`)
carries a dict ``{component: mode}``. The system stepped in a mode is the assembled system
with the rows its modes hold (:class:`~mbcomp.modeling.events.AxisRow`: ``sign (s - at)`` on
a tree joint's coordinate) appended after its holonomic rows: :func:`mode_system` makes it
as a :meth:`~mbcomp.assembly.system.MultibodySystem.variant` whose evaluator is the original
one (numeric or a generated program, unchanged) wrapped by :class:`ModeEvaluator`. The
formulation is built again over it at every change of mode, so every formulation and every
backend steps every mode.

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
>>> system = mbcomp.assemble(m)
>>> held = mode_system(system, {"j": "lo"})
>>> ev = held.evaluate(0.0, np.array([-0.05]), np.array([0.3]))
>>> ev.Phi.tolist(), ev.C.tolist()        # the row phi - lo, 0.05 rad on the allowed side
([0.05], [[1.0]])
"""
from __future__ import annotations

import numpy as np

from ..assembly.kkt import accelerations, project_state
from ..errors import ModelError, Problem
from ..modeling.events import ContactRow
from .contacts import contact_impact, contact_rows, initialize_in_modes, open_joints, without_rows

__all__ = ["mode_system", "ModeEvaluator", "start_modes", "row_values", "impact_speeds", "consistent",
           "row_push", "open_joints", "without_rows", "contact_rows", "contact_impact", "initialize_in_modes",
           "stop_columns"]


def start_modes(system):
    """``{joint: mode}`` of every joint of ``system`` that has modes (``start_mode`` not None);
    a ``ModelError`` for one that is driven or not a 1-DOF tree joint (no coordinate of its own)."""
    out = {}
    for e in system.topology.edges:
        if e.kind == "joint" and e.comp.has_events:
            mode = e.comp.start_mode(system.P[e.name])
            if mode is not None:
                if e.comp.tree_edge:  # a stop: its events and rows are of its own coordinate
                    _axis_index(system, e.name)
                out[e.name] = mode
    return out


def _axis_index(system, name):
    """``(q index, u index)`` of tree joint ``name``'s one coordinate; a problem otherwise."""
    e = system.edge(name)
    if e.drive or e.q.stop - e.q.start != 1 or e.u.stop - e.u.start != 1:
        why = "is driven (its motion is prescribed)" if e.drive else "is no 1-DOF joint in the spanning tree"
        raise ModelError([Problem(name, f"a stop needs the joint's own coordinate, but {name} {why}",
                                  "put the stop on a free 1-DOF joint, or cut another joint of the loop")])
    return e.q.start, e.u.start


def mode_rows(system, modes):
    """``[(joint, AxisRow, q index, u index)]`` held by ``modes``."""
    out = []
    for name, mode in sorted(modes.items()):
        e = system.edge(name)
        for row in e.comp.mode_rows(system.P[name], mode):
            if not isinstance(row, ContactRow):  # a contact's rows are its own: see open_joints
                out.append((name, row, *_axis_index(system, name)))
    return out


class _RowsAdded:
    """An evaluation with the mode's rows appended to the holonomic ones (everything else
    is the wrapped evaluation's)."""

    def __init__(self, ev, Phi, Phid, C, cb):
        self._ev, self.Phi, self.Phid, self.C, self.cb = ev, Phi, Phid, C, cb

    def __getattr__(self, name):
        return getattr(self._ev, name)

    @property
    def A(self):
        return np.vstack((self.C, self.B)) if self.B.size else self.C


class WrappingEvaluator:
    """An evaluator that changes another's evaluations (a mode's rows, a mode's forces): the
    backend, statistics and coordinate rates are the wrapped one's; it offers no one-call
    programs, so the formulations assemble their equations from ``evaluate``. Subclasses
    implement ``evaluate`` and ``rebind``."""

    capabilities = frozenset()

    def __init__(self, inner):
        self.inner = inner

    @property
    def backend(self):
        return self.inner.backend

    @property
    def stats(self):
        return self.inner.stats

    def q_rate(self, q, u):
        return self.inner.q_rate(q, u)


class ModeEvaluator(WrappingEvaluator):
    """The evaluator of a system in a mode: the original evaluator's evaluation with the
    engaged rows appended (masked evaluations only: an unmasked one lists the assembled
    rows, as ``constraint_names(all_rows=True)`` does)."""

    def __init__(self, inner, rows, nu):
        super().__init__(inner)
        self.rows, self.nu = rows, nu

    def evaluate(self, t, q, u, masked=True):
        ev = self.inner.evaluate(t, q, u, masked)
        if not masked or not self.rows:
            return ev
        k = len(self.rows)
        C = np.zeros((k, self.nu))
        Phi, Phid = np.zeros(k), np.zeros(k)
        for i, (_, row, iq, iu) in enumerate(self.rows):
            Phi[i], Phid[i], C[i, iu] = row.value(q[iq]), row.sign * u[iu], row.sign
        return _RowsAdded(ev, np.concatenate((ev.Phi, Phi)), np.concatenate((ev.Phid, Phid)),
                          np.vstack((ev.C, C)), np.concatenate((ev.cb, np.zeros(k))))

    def rebind(self, system, laws=False):
        return ModeEvaluator(self.inner.rebind(system, laws), self.rows, self.nu)


def mode_system(system, modes):
    """``system`` with the rows ``modes`` hold (the system itself when they hold none): the
    rows of open contacts out (:func:`without_rows`), the rolling rows of sliding contacts out
    (:func:`~mbcomp.hybrid.slip.without_rolling`; their friction is added by
    :func:`~mbcomp.hybrid.slip.with_slip_friction`), engaged stops' rows appended."""
    from .slip import slipping_joints, without_rolling

    base = without_rolling(without_rows(system, open_joints(system, modes)), slipping_joints(system, modes))
    rows = mode_rows(base, modes)
    if not rows:
        return base
    return base.with_evaluator(lambda new: ModeEvaluator(base.evaluator, rows, base.nu))


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


def stop_columns(series, system, log, t, Y, system_for=None):
    """Correct the result's ``series`` at output times ``t`` (s) where a stop is engaged
    (``log``: ``[(time, modes from then on)]``; ``Y`` the outputs' states ``[q, u]``) and add
    ``<joint>.stop`` (N or N m) for every joint engaged in some mode of the run: the stop's
    push along the axis, minus its row's multiplier, positive pushing the joint away from
    the limit into the allowed range, 0 where not engaged.

    The post-processing solves the assembled system, which lacks the stop's row: at engaged
    times the speeds' rates and multipliers come from the mode's system (``system_for(modes)``,
    default :func:`mode_system`; index-1 solve without stabilization) and every column is
    written again from them over the system without the stop (its reactions, by the backward
    pass, then carry the stop's force or torque: it acts across the joint). Returns
    ``{column: unit}`` of the added columns. An open contact's force columns are 0 again
    (:func:`~mbcomp.hybrid.contacts.zero_open`).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, -9.81, 0)))
    >>> s = m.add("s", Prismatic(n=(0, 1, 0), s0=0.1, limits=(0.0, 1.0))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> r = mbcomp.simulate(m, t_end=0.5, n_out=3)     # lands on the lower stop at 0.14 s
    >>> float(r["s.stop"][0]), round(float(r["s.stop"][-1]), 6), r.units["s.stop"]
    (0.0, 19.62, 'N')
    """
    from .contacts import zero_open

    times = np.array([tt for tt, _ in log])
    engaged = sorted({n for _, modes in log for n, *_ in _stop_rows(system, modes)})
    for n in engaged:
        series[f"{n}.stop"] = np.zeros(len(t))
    for k, tk in enumerate(t):
        modes = log[max(int(np.searchsorted(times, tk, side="left")) - 1, 0)][1]
        if not _changes_dynamics(system, modes):
            continue
        q, u = Y[k, :system.nq], Y[k, system.nq:]
        vals, pushes = _engaged_values(system, (system_for or (lambda m: mode_system(system, m)))(modes), modes, tk, q,
                                       u)
        for col, val in vals.items():
            if col in series:
                series[col][k] = val
        for n, push in pushes.items():
            if f"{n}.stop" in series:
                series[f"{n}.stop"][k] = push
        zero_open(series, system, open_joints(system, modes), k)
    return {f"{n}.stop": "N m" if system.edge(n).comp.axis_kind == "rotational" else "N" for n in engaged}


def _changes_dynamics(system, modes):
    """Whether ``modes`` hold rows (engaged stops, a stuck friction's row) or apply forces
    (a slipping friction's) the assembled system lacks: their columns (the speeds' rates, the
    reactions and drive efforts carrying them) are solved again over the mode's system."""
    return bool(mode_rows(system, modes)) or any(
        system.edge(n).comp.has_mode_force and system.edge(n).comp.mode_force(system.P[n], m) for n, m in modes.items())


def _stop_rows(system, modes):
    """The engaged stops' rows of ``modes`` (:func:`mode_rows`, a sticking friction's
    :class:`~mbcomp.modeling.events.StickRow` left out)."""
    return [r for r in mode_rows(system, modes) if not _is_stick(r[1])]


def _engaged_values(system, sysm, modes, t, q, u):
    """``(columns, {joint: push})`` at ``(t, q, u)``: the speeds' rates and multipliers of
    the mode's system ``sysm``, the columns over the system without the stops' rows."""
    from types import SimpleNamespace

    from ..assembly.outputs import result_columns
    from .slip import slipping_joints, without_rolling

    # a sliding contact's rolling rows are out here too (its friction is then in no reaction)
    base = without_rolling(without_rows(system, open_joints(system, modes)), slipping_joints(system, modes))
    rows = mode_rows(base, modes)
    ev = sysm.evaluate(t, q, u)
    ud, lam = accelerations(ev)
    first = ev.Phi.size - len(rows)  # the mode's rows follow the holonomic rows
    pushes = {n: -float(lam[first + i]) for i, (n, row, _, _) in enumerate(rows) if not _is_stick(row)}
    lam_b = np.concatenate((lam[:first], lam[first + len(rows):]))
    evb = base.evaluate(t, q, u)
    evf = base.evaluate(t, q, u, masked=False) if evb.local else evb
    cols = SimpleNamespace(t=t, q=q, u=u, jets=evb.jets, local_nh=evb.local_nh, B=evb.B, Phi_all=evf.Phi,
                           Phid_all=evf.Phid, Psi=evb.Psi)
    values, _ = result_columns(base, cols, ud, lam_b, base.reactions(evb, ud, lam_b))
    return values, pushes


def _is_stick(row):
    from ..modeling.events import StickRow

    return isinstance(row, StickRow)
