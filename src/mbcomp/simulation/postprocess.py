"""Post-processing: the named result columns at every kept output time.

From the kept states ``[q, u]`` the post-processing evaluates the system once per output
time and writes the columns described in :mod:`mbcomp.simulation.result`: coordinates and
speeds, their rates, reactions and drive efforts, joints' own outputs, body poses and
velocities, energies, constraint residuals and multipliers. Then each joint may add notes
to the result's message (:meth:`mbcomp.modeling.roles.Joint.result_notes`: a contact that
pulls where a real one would lift off), and the model's aliases and output functions are
added. A column that cannot be computed is reported in the message; every other result is
kept.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Prismatic, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
>>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> r = mbcomp.simulate(m, t_end=1.0, n_out=3)
>>> round(float(r["s.v.der"][0]), 9), round(float(r["energy.potential"][0]), 9)   # free fall; V = 0 at z = 0
(-9.81, 0.0)
"""
from __future__ import annotations

from functools import partial
from types import SimpleNamespace

import numpy as np

from ..assembly.column_units import column_units
from ..assembly.conservation import momenta, momentum_conserved, nonconservative
from ..assembly.outputs import HIDDEN, output_values, result_columns
from ..assembly.recursive import SingularTree
from ..assembly.summary import summary
from ..assembly.topology import no_gravity_note
from ..geometry.kinematics import matrix_to_quat
from ..modeling.roles import Joint
from .accuracy import balance_alarm, energy_alarm, momentum_alarm, tolerance_energy
from .balance import energy_balance, momentum_columns
from .result import Result

__all__ = ["postprocess"]


class _Columns:
    """Result columns of ``n`` output times, created full of NaN when first written, and the
    bodies' orientation quaternions (``(n, 4)`` per body; from the rotation matrices kept
    point by point, converted in one pass when read)."""

    def __init__(self, n):
        self.n, self.series, self._quat, self.matrices = n, {}, {}, {}

    def put(self, name, k, val):
        arr = self.series.get(name)
        if arr is None:
            arr = self.series[name] = np.full(self.n, np.nan)
        arr[k] = val

    def rotation(self, path, k, R):
        kept = self.matrices.get(path)
        if kept is None:
            kept = self.matrices[path] = {}
        kept[k] = R

    @property
    def quat(self):
        """``{body: (n, 4) quaternions}`` of the rotations kept so far."""
        self._quaternions()
        return self._quat

    def _quaternions(self):
        """The kept rotation matrices into ``quat`` (elementwise, so one stacked pass gives each
        point's quaternion as a call per point would)."""
        where = [(path, k) for path, kept in self.matrices.items() for k in kept]
        if where:
            Q = matrix_to_quat(np.stack([np.asarray(self.matrices[path][k], float) for path, k in where]))
            for (path, k), row in zip(where, Q):
                arr = self._quat.get(path)
                if arr is None:
                    arr = self._quat[path] = np.full((self.n, 4), np.nan)
                arr[k] = row
        self.matrices = {}

    def finished(self):
        """The series with every body's quaternion ``<body>.Q.w/x/y/z`` after its position."""
        quats = self.quat
        after = {f"{path}.r.z": path for path in quats}
        out = {}
        for name, arr in self.series.items():
            out[name] = arr
            if name in after:
                quat = quats[after[name]]
                for j, ax in enumerate("wxyz"):
                    out[f"{after[name]}.Q.{ax}"] = quat[:, j].copy()
        return out


def postprocess(system, form, t, Y, status, message, stats, init, body_momenta=False, fix=None):
    """The :class:`Result` of a run: every column at the output times ``t`` from the kept
    states ``Y`` (rows ``[q, u]``), the joints' notes, aliases and output functions.

    The columns come from the recursive algorithms (:func:`~mbcomp.assembly.outputs.output_values`):
    for a whole grid in one compiled call when the system's evaluator offers it (capability
    ``"outputs"``), else point by point in numpy; a point where the recursive solve is singular
    or a compiled guard fails is computed by the dense route (evaluation, the formulation's
    own ``solve``, reactions on the full jets).

    Parameters
    ----------
    system : MultibodySystem
    form : Formulation
        Gives the multipliers' Baumgarte gains (``output_gains``) and, on the dense route,
        accelerations and multipliers (``solve``).
    t : ndarray (n,)
        Output times (s).
    Y : ndarray (n, nq + nu)
    status, message : str
        Of the run; notes are appended to ``message``. A conservative system whose energy
        drifted more than ``stats["rtol"]`` promises turns ``"success"`` into
        ``"inaccurate"`` (:func:`mbcomp.simulation.accuracy.energy_alarm`).
    stats : dict
    init : Initialization
        For the model summary.
    body_momenta : bool
        Also each body's momenta (:func:`mbcomp.simulation.balance.momentum_columns`).
    fix : callable, optional
        ``fix(series)`` corrects the columns in place before the balances and notes (a run
        with modes: :func:`mbcomp.simulation.hybrid_columns.segment_columns`).
    """
    nq = system.nq
    cols = _Columns(len(t))
    gains = form.output_gains()
    todo = range(len(t))
    evaluator = system.evaluator
    terms = None  # the output program's f and M u at every point (tolerance_energy's weights)
    if len(t) and "outputs" in evaluator.capabilities:
        grid = evaluator.output_grid(t, Y, gains)
        if grid is not None:
            names, values, quaternions, ok = grid
            shown, fp = _grid_layout(names, system.nu)
            rows = list(values)
            cols.series.update((n, rows[i]) for n, i in shown)  # NaN where not ok
            cols.quat.update(quaternions)
            todo = np.flatnonzero(~ok)
            if fp is not None:
                terms = (values[fp[0]].T, values[fp[1]].T, ok)
    for k in todo:
        q, u = Y[k, :nq], Y[k, nq:]
        try:
            values, rotations = output_values(system, t[k], q, u, *(gains or (0.0, 0.0)), baumgarte=gains is not None)
        except (SingularTree, ArithmeticError, np.linalg.LinAlgError):
            _sample(system, form, cols, k, t[k], q, u)
            continue
        for name, val in values.items():
            cols.put(name, k, val)
        for path, R in rotations.items():
            cols.rotation(path, k, R)
    series = cols.finished()
    if fix is not None:
        fix(series)
    series.update(momentum_columns(system, series, per_body=body_momenta))
    balance, quadrature = energy_balance(system, t, series)
    series.update(balance)
    notes = _joint_notes(system, t, series) + _derived(system, t, series) + [n for n in [no_gravity_note(system.topology)] if n]
    loop = open_loop(system, series, stats)
    if loop:
        import warnings

        warnings.warn(f"mbcomp: {loop}", RuntimeWarning, stacklevel=3)
        notes.append(loop)
    if status == "success" and "rtol" in stats:  # the energy the tolerances leave open (J) scales the alarms
        start = getattr(init, "start", None)  # the start's evaluation, if of this system
        known = start[1] if start is not None and start[0] is system else None
        stats = dict(stats, energy_tolerance=tolerance_energy(system, t, Y, stats["rtol"], stats.get("atol", 0.0),
                                                              known, terms))
        alarm, text = _alarms(system, t, Y, series, stats["rtol"], quadrature, stats["energy_tolerance"])
        if alarm:
            status, notes = alarm, [text] + notes
        elif text:  # no alarm, but something the alarm could not judge
            notes = [text] + notes
    message = "; ".join([message] + notes)
    stats = dict(stats)
    stats["coordinates"] = list(system.q_names)
    return Result(t, series, status, message, stats, partial(summary, system, init), units=_units(system, series),
                  system=system)


_LAYOUTS = {}  # id of an output program's names -> (the names, what _grid_layout says of them)


def _grid_layout(names, nu):
    """``(shown, fp)`` of an output program's column ``names`` (its own list, so the answer is
    kept for it): ``shown``, ``[(name, row)]`` of the result columns; ``fp``, the rows of the
    hidden generalized forces and momenta (:data:`~mbcomp.assembly.outputs.HIDDEN`, ``nu``
    each) as two index arrays, or None when the program has none."""
    got = _LAYOUTS.get(id(names))
    if got is not None and got[0] is names:
        return got[1]
    shown = [(n, i) for i, n in enumerate(names) if not n.startswith(HIDDEN)]
    row = {n: i for i, n in enumerate(names)}
    fp = None
    if f"{HIDDEN}f.0" in row:
        fp = tuple(np.array([row[f"{HIDDEN}{x}.{i}"] for i in range(nu)], int) for x in "fp")
    if len(_LAYOUTS) >= 64:  # a process running many structures: forget the oldest answers
        _LAYOUTS.pop(next(iter(_LAYOUTS)))
    _LAYOUTS[id(names)] = (names, (shown, fp))
    return shown, fp


#: output points at most on which the momenta are computed for their alarm (evenly spaced)
MOMENTUM_POINTS = 1000


def _alarms(system, t, Y, series, rtol, quadrature=0.0, floor=0.0):
    """The first accuracy alarm (:mod:`mbcomp.simulation.accuracy`) a successful run raises,
    ``(status, message)``: the energy of a conservative system, the energy balance of a
    driven or damped one (unless the output grid's ``quadrature`` may explain it), the momenta
    of one that nothing outside loads; ``(None, "")`` for none. ``floor``: the energy (J) the
    tolerances leave open (:func:`~mbcomp.simulation.accuracy.tolerance_energy`)."""
    if not nonconservative(system) and "energy.kinetic" in series:
        alarm = energy_alarm(series["energy.kinetic"], series["energy.potential"], rtol, floor)
        if alarm[0]:
            return alarm
    elif "energy.balance" in series:
        alarm = balance_alarm(series["energy.balance"], series["energy.kinetic"], series["energy.potential"],
                              series["energy.work"], series["energy.dissipated"], quadrature, rtol, floor)
        if alarm[0] or alarm[1]:
            return alarm
    if len(t) > 1 and momentum_conserved(system):
        nq = system.nq
        ks = np.unique(np.linspace(0, len(t) - 1, min(len(t), MOMENTUM_POINTS)).astype(int))
        m = [momenta(system, t[k], Y[k, :nq], Y[k, nq:]) for k in ks]
        return momentum_alarm(np.array([x[0] for x in m]), np.array([x[1] for x in m]), max(x[2] for x in m),
                              max(x[3] for x in m), rtol)
    return None, ""


#: how far beyond the integration tolerance (``atol + rtol L``) the position constraints may
#: be open at the end of a run before :func:`open_loop` warns
OPEN_LOOP_FACTOR = 10.0


def open_loop(system, series, stats):
    """A warning text when the position constraints are open at the end of the run by more
    than :data:`OPEN_LOOP_FACTOR` times the integration tolerance ``atol + rtol L`` (``L``:
    the largest distance of a body from the origin, at least 1 m), else ``None``."""
    res = series.get("residual.position")
    if res is None or not len(res) or "rtol" not in stats or not np.isfinite(res[-1]):
        return None
    L = 1.0
    for path, _comp, _node in system.topology.bodies:
        if f"{path}.r.x" in series:
            L = max(L, float(np.sqrt(sum(series[f"{path}.r.{ax}"][-1] ** 2 for ax in "xyz"))))
    limit = OPEN_LOOP_FACTOR * (float(np.max(stats.get("atol", 0.0))) + stats["rtol"] * L)
    if res[-1] <= limit:
        return None
    return (f"the position constraints are open by {res[-1]:.2g} at the end of the run (residual.position), beyond "
            f"the integration tolerance (about {limit / OPEN_LOOP_FACTOR:.1g}) -> use stabilization='projection' or "
            "formulation='dalembert' (both keep the loops closed), or tighten rtol")


def _sample(system, form, cols, k, t, q, u):
    """Every column at output ``k`` (time ``t``, state ``q, u``) by the dense route."""
    ev = system.evaluate(t, q, u)
    try:
        ud, lam = form.solve(ev, stabilize=True)
    except Exception:  # noqa: BLE001 - a singular solve leaves these columns NaN, the others stand
        ud, lam = np.full(system.nu, np.nan), np.full(ev.A.shape[0], np.nan)
    evf = system.evaluate(t, q, u, masked=False) if ev.local else ev
    rows = SimpleNamespace(t=t, q=q, u=u, jets=ev.jets, local_nh=ev.local_nh, B=ev.B, Phi_all=evf.Phi,
                           Phid_all=evf.Phid, Psi=ev.Psi)
    values, rotations = result_columns(system, rows, ud, lam, system.reactions(ev, ud, lam))
    for name, val in values.items():
        cols.put(name, k, val)
    for path, R in rotations.items():
        cols.rotation(path, k, R)


def _joint_notes(system, t, series):
    """What each joint says about its own results (:meth:`Joint.result_notes`): asked of the
    joints whose class has its own (the base says nothing), each with its columns."""
    joints = [e for e in system.topology.edges if e.kind == "joint" and type(e.comp).result_notes is not Joint.result_notes]
    if not joints:
        return []
    own = {e.name: {} for e in joints}
    for name, arr in series.items():  # one pass: a column belongs to the joint named by a prefix of it
        i = name.find(".")
        while i >= 0:
            if name[:i] in own:
                own[name[:i]][name[i + 1:]] = arr
            i = name.find(".", i + 1)
    notes = []
    for e in joints:
        notes.extend(e.comp.result_notes(e.name, t, own[e.name]))
    return notes


def _derived(system, t, series):
    """Add the model's aliases and output functions to ``series``; notes on those that fail."""
    flat, notes = system.topology.flat, []
    for alias, var in flat.aliases.items():
        if var in series:
            series[alias] = series[var]
        else:
            notes.append(f"alias {alias!r} -> {var!r} names no variable")
    for name, (fn, variables) in flat.outputs.items():
        missing = [v for v in variables if v not in series]
        if missing:
            notes.append(f"output {name!r} needs {', '.join(map(repr, missing))}, which name no variable")
            continue
        try:
            val = np.broadcast_to(np.asarray(fn(*(series[v] for v in variables)), float), t.shape).copy()
        except Exception as exc:  # noqa: BLE001 - a user's function: report, keep every other result
            notes.append(f"output {name!r} failed ({type(exc).__name__}: {exc})")
            continue
        series[name] = val
    return notes


def _units(system, series):
    """``{column: unit}`` of the columns in ``series`` whose unit is declared (an alias has
    its variable's). The table of the structure's columns is made once per structure (the
    evaluator's ``structure_memo``: a third of the post-processing of a short run)."""
    memo = getattr(system.evaluator, "structure_memo", None)
    memo = memo() if memo is not None else None
    units = memo.get("column_units") if memo is not None else None
    if units is None:
        units = column_units(system)
        if memo is not None:
            memo["column_units"] = units
    units = dict(units)
    units.update({a: units[v] for a, v in system.topology.flat.aliases.items() if v in units})
    return {name: units[name] for name in series if name in units}
