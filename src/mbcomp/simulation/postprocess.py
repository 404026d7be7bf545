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

import numpy as np

from ..assembly.summary import summary
from ..geometry.kinematics import matrix_to_quat
from ..modeling.roles import Joint
from .result import Result

__all__ = ["postprocess"]

_XYZ = ("x", "y", "z")


class _Columns:
    """Result columns of ``n`` output times, created full of NaN when first written."""

    def __init__(self, n):
        self.n, self.series = n, {}

    def put(self, name, k, val):
        arr = self.series.get(name)
        if arr is None:
            arr = self.series[name] = np.full(self.n, np.nan)
        arr[k] = val

    def vector(self, prefix, k, vec, axes=_XYZ):
        for j, ax in enumerate(axes):
            self.put(f"{prefix}.{ax}", k, vec[j])


def postprocess(system, form, t, Y, status, message, stats, init):
    """The :class:`Result` of a run: every column at the output times ``t`` from the kept
    states ``Y`` (rows ``[q, u]``), the joints' notes, aliases and output functions.

    Parameters
    ----------
    system : MultibodySystem
    form : Formulation
        Gives accelerations and multipliers at each output time (``solve``).
    t : ndarray (n,)
        Output times (s).
    Y : ndarray (n, nq + nu)
    status, message : str
        Of the run; notes are appended to ``message``.
    stats : dict
    init : Initialization
        For the model summary.
    """
    cols = _Columns(len(t))
    for k in range(len(t)):
        _sample(system, form, cols, k, t[k], Y[k, : system.nq], Y[k, system.nq:])
    notes = _joint_notes(system, t, cols.series) + _derived(system, t, cols.series)
    message = "; ".join([message] + notes)
    stats = dict(stats)
    stats["coordinates"] = list(system.q_names)
    return Result(t, cols.series, status, message, stats, summary(system, init))


def _sample(system, form, cols, k, t, q, u):
    """Every column at output ``k`` (time ``t``, state ``q, u``)."""
    ev = system.evaluate(t, q, u)
    try:
        ud, lam = form.solve(ev, stabilize=True)
    except Exception:  # noqa: BLE001 - a singular solve leaves these columns NaN, the others stand
        ud, lam = np.full(system.nu, np.nan), np.full(ev.A.shape[0], np.nan)
    _joint_columns(system, cols, k, t, q, u, ev, ud)
    reac = system.reactions(ev, ud, lam)
    _reaction_columns(system, cols, k, ev, lam, reac)
    _body_columns(system, cols, k, ev)
    T, V = system.energies(ev)
    cols.put("energy.kinetic", k, T)
    cols.put("energy.potential", k, V)
    cols.put("energy.total", k, T + V)
    evf = system.evaluate(t, q, u, masked=False) if ev.local else ev
    cols.put("residual.position", k, np.linalg.norm(evf.Phi) if evf.Phi.size else 0.0)
    cols.put("residual.velocity", k, np.linalg.norm(evf.Phid) if evf.Phid.size else 0.0)
    cols.put("residual.nonholonomic", k, np.linalg.norm(ev.Psi) if ev.Psi.size else 0.0)
    rows = system.constraint_names() + [f"{e.name}.{rr}" for e, names, _ in ev.local_nh for rr in names]
    for i, name in enumerate(rows):
        cols.put(f"lambda.{name}", k, lam[i] if i < lam.size else np.nan)


def _joint_columns(system, cols, k, t, q, u, ev, ud):
    """Coordinates, speeds and their rates; the measured coordinate of 1-DOF joints without
    coordinates of their own (cut or driven)."""
    topo = system.topology
    for i, name in enumerate(system.q_names):
        cols.put(name, k, q[i])
    for i, name in enumerate(system.u_names):
        cols.put(name, k, u[i])
    for e in topo.edges:
        if e.kind != "joint" or e.dof != 1 or e.q.stop > e.q.start:
            continue
        if e.drive:
            s, v, _ = topo.flat.components[e.drive].motion(t, system.P[e.drive])
        else:
            s, v = e.comp.measure(ev.jets[e.node_a], ev.jets[e.node_b], system.P[e.name])
        cols.put(f"{e.name}.{e.comp.coordinates[0][0]}", k, s)
        cols.put(f"{e.name}.{e.comp.speeds[0][0]}", k, v)
    for i, name in enumerate(system.u_names):
        cols.put(f"{name}.der", k, ud[i])


def _reaction_columns(system, cols, k, ev, lam, reac):
    """Joint reactions, joints' own outputs (from their rows' multipliers), drive efforts."""
    topo = system.topology
    for ename, (fb, tb) in reac.items():
        cols.vector(f"{ename}.f", k, fb)
        cols.vector(f"{ename}.tau", k, tb)
    own = [e for e in topo.edges if e.kind == "joint" and type(e.comp).outputs is not Joint.outputs]
    if own:
        lam_rows = system.row_multipliers(ev, lam)
        for e in own:
            extra = e.comp.outputs(ev.jets[e.node_a], ev.jets[e.node_b], system.P[e.name], lam_rows.get(e.name, {}))
            for key, val in extra.items():
                cols.put(f"{e.name}.{key}", k, val)
    for e in topo.edges:
        if not e.drive:
            continue
        fb, tb = reac[e.name]
        axis_b = ev.jets[e.node_b].R.T @ e.comp.axis_world(ev.jets[e.node_a].R, system.P[e.name])
        if e.comp.axis_kind == "rotational":
            cols.put(f"{e.drive}.tau", k, tb @ axis_b)
        else:
            cols.put(f"{e.drive}.f", k, fb @ axis_b)


def _body_columns(system, cols, k, ev):
    """Position, orientation quaternion, velocity and angular velocity of every body (world)."""
    for path, _comp, node in system.topology.bodies:
        J = ev.jets[node]
        cols.vector(f"{path}.r", k, J.r)
        cols.vector(f"{path}.Q", k, matrix_to_quat(J.R), "wxyz")
        cols.vector(f"{path}.v", k, J.v)
        cols.vector(f"{path}.w", k, J.w)


def _joint_notes(system, t, series):
    """What each joint says about its own results (:meth:`Joint.result_notes`)."""
    notes = []
    for e in system.topology.edges:
        if e.kind != "joint":
            continue
        prefix = f"{e.name}."
        own = {n[len(prefix):]: v for n, v in series.items() if n.startswith(prefix)}
        notes.extend(e.comp.result_notes(e.name, t, own))
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
