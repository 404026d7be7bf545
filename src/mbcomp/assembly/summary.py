"""Model summary: what was modelled, how many degrees of freedom, and why.

Examples
--------
>>> # mbcomp info models/slider_crank.py prints this summary
"""
from __future__ import annotations

import numpy as np

__all__ = ["summary", "dof_report"]


def dof_report(system, init=None):
    """Degrees of freedom by Gruebler's count ``M = 6N - C - L`` and by rank.

    ``N`` counts rigid groups (frames joined by rigid offsets), ``C`` the constraints of the
    joints between them, ``L`` the prescribed motions. The rank count ``nu - rank(C_cut)`` is the
    true mobility; the difference is the number of redundant constraint rows.
    """
    topo = system.topology
    parent = {}

    def find(x):
        parent.setdefault(x, x)
        while parent[x] != x:
            x = parent[x]
        return x

    for e in topo.edges:
        if e.kind == "ground" or (e.dof == 0 and e.comp.tree_edge):
            parent[find(e.node_a)] = find(e.node_b)
    groups = {find(n) for n in range(topo.n_nodes)} - {find(-1)}
    N = len(groups)
    C = sum(6 - e.dof for e in topo.edges if e.kind == "joint" and e.dof > 0 and not e.implicit)
    # constraint-only joints (contacts) remove as many DOF as they have holonomic rows
    C += sum(1 for name in system.constraint_names(all_rows=True)
             if not topo.edge(name.rsplit(".", 1)[0]).comp.tree_edge)
    L = sum(1 for e in topo.edges if e.drive)
    if init is None:
        from ..assembly.initialization import initialize


        try:
            init = initialize(system)
        except Exception:
            init = None
    rank = init.rank if init is not None else None
    mobility = system.nu - rank if rank is not None else None
    return dict(N=N, C=C, L=L, gruebler=6 * N - C - L, mobility=mobility, rank=rank,
                redundant=list(init.dropped) if init is not None else [])


def summary(system, init=None):
    """Multi-line text: bodies, DOF, chosen coordinates, constraints, what was eliminated."""
    topo = system.topology
    if init is None:
        from ..assembly.initialization import initialize

        try:
            init = initialize(system)
        except Exception as exc:  # the summary must still describe a model that cannot start
            init = None
            why = str(exc).splitlines()[0]
    d = dof_report(system, init)
    lines = ["mbcomp model summary", "===================="]
    if init is None:
        lines.append(f"initialization failed: {why}")
    lines.append(f"bodies ({len(topo.bodies)}): " + ", ".join(
        f"{p} (m={system.P[p].m:g} kg)" if hasattr(system.P[p], "m") else p for p, _, _ in topo.bodies))
    g = system.g
    lines.append(f"gravity: {np.array2string(g, precision=4)} m/s^2" + (f" from {topo.gravity_source}"
                                                                        if topo.gravity_source else " (no World)"))
    dof = d["mobility"] if d["mobility"] is not None else "unknown (initialization failed)"
    lines.append(f"degrees of freedom: {dof}   (Gruebler M = 6N - C - L = 6*{d['N']} - {d['C']} - {d['L']}"
                 f" = {d['gruebler']}"
                 + (f"; mobility exceeds it by {d['mobility'] - d['gruebler']} because "
                    f"{d['mobility'] - d['gruebler']} constraint rows are redundant, e.g. a planar loop"
                    if isinstance(d["mobility"], int) and d["mobility"] > d["gruebler"] else "") + ")")
    lines.append(f"coordinates ({system.nq} q, {system.nu} speeds): {', '.join(system.q_names) or 'none'}")
    tree = [e.name for e in topo.tree if e.kind == "joint" and e.dof > 0 and not e.drive]
    lines.append(f"tree joints (minimal coordinates): {', '.join(tree) or 'none'}")
    cut_rows = system.constraint_names(all_rows=True)
    lines.append(f"cut joints (loop closure): {', '.join(topo.cut) or 'none'}; {len(cut_rows)} constraint rows, "
                 f"rank {d['rank']}")
    if d["redundant"]:
        lines.append(f"redundant constraint rows dropped: {', '.join(d['redundant'])}")
    nh = init.nonholonomic if init is not None else "?"
    lines.append(f"nonholonomic constraints (velocity level): {nh}"
                 + (f"; motion DOF {d['mobility'] - nh}" if init is not None and nh else ""))
    drives = [f"{e.name} by {e.drive}" for e in topo.edges if e.drive]
    if drives:
        lines.append(f"prescribed (eliminated, rheonomic): {', '.join(drives)}")
    contacts = [e for e in topo.edges if e.kind == "joint" and not e.comp.tree_edge]
    if contacts:
        ev = system.evaluate(0.0, system.default_q(), np.zeros(system.nu), masked=False)
        nh_rows = {e.name: len(rows) for e, rows, _ in ev.local_nh}
        lines.append("contacts (constraint-only joints): " + ", ".join(
            f"{e.name} ({sum(1 for n in cut_rows if n.rsplit('.', 1)[0] == e.name)} holonomic + "
            f"{nh_rows.get(e.name, 0)} nonholonomic rows)" for e in contacts))
    rig = [e.name for e in topo.edges if e.kind == "joint" and e.dof == 0 and e.comp.tree_edge]
    if rig:
        lines.append(f"rigid offsets merged into their bodies (no coordinates): {', '.join(rig)}")
    if topo.floating:
        lines.append(f"free bodies (implicit FreeMotion from the world): {', '.join(topo.floating)}")
    return "\n".join(lines)
