"""Simulation results: named time series, reactions, energies, residuals, statistics.

Variable names are ``<component>.<variable>``:

* joints: coordinates and speeds (``crank.phi``, ``crank.w``; ``slider.s``, ``slider.v``;
  ``ball.Q.w``.., ``ball.w.x``..), reactions ``<joint>.f.x|y|z`` (N) and
  ``<joint>.tau.x|y|z`` (N m): the force and torque exerted on frame_b through the joint,
  resolved in frame_b, torque about frame_b's origin (flange-element forces excluded);
* joints with outputs of their own (:meth:`mbcomp.roles.Joint.outputs`), e.g. rolling
  contacts: ``<contact>.N`` (normal force), ``<contact>.F_long``, ``<contact>.F_lat``;
* drives: ``<drive>.tau`` (rotational) or ``<drive>.f`` (translational), the effort needed to
  impose the motion;
* bodies: ``<body>.r.x|y|z`` (m, origin of frame_a, world), ``<body>.Q.w|x|y|z`` (orientation
  quaternion, frame_a -> world), ``<body>.v.*`` (m/s), ``<body>.w.*`` (rad/s, world);
* ``energy.kinetic``, ``energy.potential``, ``energy.total`` (J);
* ``residual.position`` (norm of Phi, m or 1), ``residual.velocity`` (norm of dPhi/dt),
  ``residual.nonholonomic`` (norm of B u - b);
* model aliases under their alias name.

Examples
--------
>>> import numpy as np
>>> from mbcomp.result import Result
>>> r = Result(np.array([0.0, 1.0]), {"a.phi": np.array([0.0, 2.0])})
>>> float(r["a.phi"][-1])
2.0
"""
from __future__ import annotations

import csv

import numpy as np

from ..geometry.kinematics import matrix_to_quat
from ..modeling.roles import Joint

__all__ = ["Result", "postprocess"]

_XYZ = ("x", "y", "z")


class Result:
    """Named time series of one simulation, plus status and statistics.

    Attributes
    ----------
    time : ndarray (n,)
    status : {"success", "failed"}
    message : str
    stats : dict
        Solver statistics: steps, nfev, nlu, restarts, projections, cpu_time, method, ...
    summary : str
        The model summary (bodies, DOF, coordinates, constraints).
    """

    def __init__(self, time, series, status="success", message="", stats=None, summary=""):
        self.time = np.asarray(time)
        self._series = dict(series)
        self.status, self.message = status, message
        self.stats = dict(stats or {})
        self.summary = summary

    @property
    def names(self):
        """Every variable name, in CSV column order (after ``time``)."""
        return list(self._series)

    def __getitem__(self, name):
        if name == "time":
            return self.time
        try:
            return self._series[name]
        except KeyError:
            close = [n for n in self._series if name.split(".")[0] in n][:8]
            raise KeyError(f"no variable {name!r} in the result; similar: {', '.join(close) or 'none'} "
                           f"(see Result.names)") from None

    def __contains__(self, name):
        return name == "time" or name in self._series

    @property
    def success(self):
        return self.status == "success"

    def to_csv(self, path):
        """Write ``time`` and every variable as columns to ``path``."""
        names = self.names
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["time"] + names)
            cols = [self.time] + [self._series[n] for n in names]
            for row in zip(*cols):
                w.writerow([f"{x:.12g}" for x in row])
        return path

    def plot(self, names=None, path=None, title=None):
        """Plot variables against time (default: joint coordinates and energy); save to ``path``."""
        import matplotlib

        if path is not None:
            matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt

        names = names or self.default_plot_names()
        fig, axes = plt.subplots(len(names), 1, sharex=True, figsize=(7, 1.8 * len(names) + 0.6), squeeze=False)
        for ax, n in zip(axes[:, 0], names):
            ax.plot(self.time, self[n])
            ax.set_ylabel(n, fontsize=8)
            ax.grid(True, alpha=0.3)
        axes[-1, 0].set_xlabel("time [s]")
        fig.suptitle(title or f"mbcomp ({self.status})", fontsize=10)
        fig.tight_layout()
        if path is not None:
            fig.savefig(path, dpi=110)
            plt.close(fig)
        return fig

    def default_plot_names(self):
        coords = self.stats.get("coordinates", [])[:4]
        return coords + ["energy.total", "residual.position"]


def postprocess(system, form, t, Y, status, message, stats, init):
    """Evaluate outputs at every output time (accelerations, multipliers, reactions, energies)."""
    topo = system.topology
    series = {}
    n = len(t)

    def put(name, k, val):
        arr = series.get(name)
        if arr is None:
            arr = series[name] = np.full(n, np.nan)
        arr[k] = val

    one_dof = [e for e in topo.edges if e.kind == "joint" and e.dof == 1]
    drives = {e.drive: e for e in topo.edges if e.drive}
    joint_outputs = [e for e in topo.edges if e.kind == "joint" and type(e.comp).outputs is not Joint.outputs]
    for k in range(n):
        q, u = Y[k, : system.nq], Y[k, system.nq:]
        ev = system.evaluate(t[k], q, u)
        try:
            ud, lam = form.solve(ev, stabilize=True)
        except Exception:
            ud, lam = np.full(system.nu, np.nan), np.full(ev.A.shape[0], np.nan)
        for i, name in enumerate(system.q_names):
            put(name, k, q[i])
        for i, name in enumerate(system.u_names):
            put(name, k, u[i])
        for e in one_dof:
            if e.q.stop > e.q.start:
                continue
            if e.drive:
                s, v, _ = topo.flat.components[e.drive].motion(t[k], system.P[e.drive])
            else:
                s, v = e.comp.measure(ev.jets[e.node_a], ev.jets[e.node_b], system.P[e.name])
            put(f"{e.name}.{e.comp.coordinates[0][0]}", k, s)
            put(f"{e.name}.{e.comp.speeds[0][0]}", k, v)
        for i, name in enumerate(system.u_names):
            put(f"{name}.der", k, ud[i])
        reac = system.reactions(ev, ud, lam)
        for ename, (fb, tb) in reac.items():
            for j, ax in enumerate(_XYZ):
                put(f"{ename}.f.{ax}", k, fb[j])
            for j, ax in enumerate(_XYZ):
                put(f"{ename}.tau.{ax}", k, tb[j])
        if joint_outputs:
            lam_rows = system.row_multipliers(ev, lam)
            for e in joint_outputs:
                extra = e.comp.outputs(ev.jets[e.node_a], ev.jets[e.node_b], system.P[e.name], lam_rows.get(e.name, {}))
                for key, val in extra.items():
                    put(f"{e.name}.{key}", k, val)
        for dname, e in drives.items():
            fb, tb = reac[e.name]
            axis_b = ev.jets[e.node_b].R.T @ e.comp.axis_world(ev.jets[e.node_a].R, system.P[e.name])
            if e.comp.axis_kind == "rotational":
                put(f"{dname}.tau", k, tb @ axis_b)
            else:
                put(f"{dname}.f", k, fb @ axis_b)
        for path, comp, node in topo.bodies:
            J = ev.jets[node]
            Q = matrix_to_quat(J.R)
            for j, ax in enumerate(_XYZ):
                put(f"{path}.r.{ax}", k, J.r[j])
            for j, ax in enumerate("wxyz"):
                put(f"{path}.Q.{ax}", k, Q[j])
            for j, ax in enumerate(_XYZ):
                put(f"{path}.v.{ax}", k, J.v[j])
            for j, ax in enumerate(_XYZ):
                put(f"{path}.w.{ax}", k, J.w[j])
        T, V = system.energies(ev)
        put("energy.kinetic", k, T)
        put("energy.potential", k, V)
        put("energy.total", k, T + V)
        evf = system.evaluate(t[k], q, u, masked=False) if ev.local else ev
        put("residual.position", k, np.linalg.norm(evf.Phi) if evf.Phi.size else 0.0)
        put("residual.velocity", k, np.linalg.norm(evf.Phid) if evf.Phid.size else 0.0)
        put("residual.nonholonomic", k, np.linalg.norm(ev.Psi) if ev.Psi.size else 0.0)
        for i, name in enumerate(system.constraint_names() + [f"{e.name}.{rr}" for e, rows, _ in ev.local_nh for rr in rows]):
            put(f"lambda.{name}", k, lam[i] if i < lam.size else np.nan)
    for e in joint_outputs:  # contacts hold bodies bilaterally: say where a real one would let go
        N = series.get(f"{e.name}.N")
        if not e.comp.tree_edge and N is not None and np.nanmin(N, initial=0.0) < 0.0:
            k = int(np.argmax(N < 0.0))
            message += (f"; {e.name}.N < 0 from t = {t[k]:.4g} s: the contact pulls the body onto the plane there "
                        f"(contacts are bilateral; a real wheel or ball would lift off)")
    for alias, var in topo.flat.aliases.items():
        if var in series:
            series[alias] = series[var]
        else:
            message += f"; alias {alias!r} -> {var!r} names no variable"
    for name, (fn, variables) in topo.flat.outputs.items():
        missing = [v for v in variables if v not in series]
        if missing:
            message += f"; output {name!r} needs {', '.join(map(repr, missing))}, which name no variable"
            continue
        try:
            val = np.broadcast_to(np.asarray(fn(*(series[v] for v in variables)), float), t.shape).copy()
        except Exception as exc:  # a user's function: report, keep every other result
            message += f"; output {name!r} failed ({type(exc).__name__}: {exc})"
            continue
        series[name] = val
    stats = dict(stats)
    stats["coordinates"] = list(system.q_names)
    from ..assembly.summary import summary

    return Result(t, series, status, message, stats, summary(system, init))
