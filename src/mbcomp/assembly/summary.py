"""Model summary: what was modelled, how many degrees of freedom, and why.

Describing a system changes nothing in it: when no initialization is given, the summary
initializes a copy (:func:`observer`: same topology and parameter values), so the
system's ``row_mask`` and caches stay as they were.

Examples
--------
>>> import mbcomp
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("hinge", Revolute())
>>> rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0))); bob = m.add("bob", PointMass(m=2.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> system = mbcomp.assemble(m)
>>> print(summary(system).splitlines()[4])
degrees of freedom: 1   (Gruebler M = 6N - C - L = 6*1 - 5 - 0 = 1)
>>> system.row_mask is None  # described, not initialized
True
"""
from __future__ import annotations

import numpy as np

from ..modeling.lock import Locked

__all__ = ["summary", "dof_report", "observer"]


def observer(system):
    """A numeric copy of ``system`` to initialize and evaluate while describing it.

    Same topology (shared, not re-derived) and parameter values; its own ``row_mask`` and
    caches. A generated-program system (:mod:`mbcomp.codegen`) is described by the numeric
    evaluation it was verified against, so describing it traces nothing.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, Revolute, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute())
    >>> b = m.add("b", PointMass()); m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
    >>> s = mbcomp.assemble(m)
    >>> copy = observer(s)
    >>> copy is not s and copy.topology is s.topology
    True
    """
    return system.with_params({}).with_evaluator()


def dof_report(system, init=None):
    """Degrees of freedom by Gruebler's count ``M = 6N - C - L`` and by rank.

    ``N`` counts rigid groups (frames joined by rigid offsets), ``C`` the constraints of the
    joints between them, ``L`` the prescribed motions. The rank count ``nu - rank(C_cut)`` is the
    true mobility; the difference is the number of redundant constraint rows.

    Parameters
    ----------
    system : MultibodySystem
        The assembled system; not changed (see :func:`observer`).
    init : Initialization, optional
        Its consistent initialization, if already computed; else a copy is initialized.

    Returns
    -------
    dict
        ``N``, ``C``, ``L``, ``gruebler`` (``6N - C - L``), ``mobility`` (``nu - rank``, or
        ``None`` when initialization fails), ``rank`` and ``redundant`` (dropped row names).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute())
    >>> rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0))); b = m.add("b", PointMass())
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, b.frame_a)
    >>> d = dof_report(mbcomp.assemble(m))
    >>> d["gruebler"], d["mobility"]
    (1, 1)
    """
    view = observer(system)  # the names are kept on the copy: the caller's system stays as it was
    return _dof_report(view, init, view.constraint_names(all_rows=True))


def _dof_report(view, init, cut_rows):
    """:func:`dof_report` of an observer copy ``view`` (initialized here when ``init`` is None);
    ``cut_rows``: the names of every constraint row (the system's, kept per structure)."""
    topo = view.topology
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
    C = sum(6 - e.dof for e in topo.edges if e.kind == "joint" and e.dof > 0)  # (a point's free joint: 3)
    # constraint-only joints (the library's contacts) remove as many DOF as they have holonomic rows
    # ... and so do flange constraints (gears: one holonomic row each, assembly/flange_rows.py)
    gears = {fr.name for fr in topo.flange_rows}
    C += sum(1 for name in cut_rows
             if name.rsplit(".", 1)[0] in gears or not topo.edge(name.rsplit(".", 1)[0]).comp.tree_edge)
    L = sum(1 for e in topo.edges if e.drive)
    if init is None:
        init, _ = _initialize(view)
    rank = init.rank if init is not None else None
    mobility = view.nu - rank if rank is not None else None
    return dict(N=N, C=C, L=L, gruebler=6 * N - C - L, mobility=mobility, rank=rank,
                redundant=list(init.dropped) if init is not None else [])


def _excess(d, init, cut_rows):
    """Why the mobility exceeds Gruebler's count (text after it, or ""): rows out of force at
    the start -- a contact starting open (the rows of its joint counted, none in force) -- and
    the rest redundant rows (e.g. a planar loop closed by a spatial joint)."""
    if not (isinstance(d["mobility"], int) and d["mobility"] > d["gruebler"]):
        return ""
    excess = d["mobility"] - d["gruebler"]
    rows = len(cut_rows) + int(init.nonholonomic or 0)
    out = min(excess, max(0, rows - len(d["redundant"]) - int(d["rank"])))  # neither in force nor dropped
    why = ([f"{out} constraint row{'s' if out > 1 else ''} of contacts starting open {'are' if out > 1 else 'is'} "
            "not in force"] if out else [])
    if excess > out:
        why.append(f"{excess - out} constraint rows are redundant, e.g. a planar loop")
    return f"; mobility exceeds it by {excess} because " + " and ".join(why)


def _initialize(view):
    """``(init, None)``, or ``(None, why)`` when the model cannot start (first line of the error)."""
    from .initialization import initialize

    try:
        return initialize(view), None
    except Exception as exc:  # the summary must still describe a model that cannot start
        return None, str(exc).splitlines()[0]


def summary(system, init=None):
    """Multi-line text: bodies, DOF, chosen coordinates, constraints, what was eliminated.

    Parameters
    ----------
    system : MultibodySystem
        The assembled system; not changed (see :func:`observer`).
    init : Initialization, optional
        Its consistent initialization, if already computed; else a copy is initialized.
    """
    topo = system.topology
    view = observer(system)
    why = None
    if init is None:
        init, why = _initialize(view)
    cut_rows = system.row_names()  # kept per structure by a compiled evaluator; nothing kept on the system
    d = _dof_report(view, init, cut_rows)
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
                 f" = {d['gruebler']}" + _excess(d, init, cut_rows) + ")")
    lines.append(f"coordinates ({system.nq} q, {system.nu} speeds): {', '.join(system.q_names) or 'none'}")
    tree = [e.name for e in topo.tree if e.kind == "joint" and e.dof > 0 and not e.drive]
    lines.append(f"tree joints (minimal coordinates): {', '.join(tree) or 'none'}")
    lines.append(f"cut joints (loop closure): {', '.join(topo.cut) or 'none'}; {len(cut_rows)} constraint rows"
                 f"{' with the gears' if topo.flange_rows else ''}, "
                 f"rank {d['rank']}")
    if topo.flange_rows:
        lines.append("flange constraints (gears, holonomic, phase from the start values): " + ", ".join(
            f"{fr.name} ({sum(1 for n in cut_rows if n.rsplit('.', 1)[0] == fr.name)} rows)" for fr in topo.flange_rows))
    if d["redundant"]:
        lines.append(f"redundant constraint rows dropped: {', '.join(d['redundant'])}")
    nh = init.nonholonomic if init is not None else "?"
    lines.append(f"nonholonomic constraints (velocity level): {nh}"
                 + (f"; motion DOF {d['mobility'] - nh}" if init is not None and nh else ""))
    drives = [f"{e.name} by {e.drive}" for e in topo.edges if e.drive]
    if drives:
        lines.append(f"prescribed (eliminated, rheonomic): {', '.join(drives)}")
    constraint_only = [e for e in topo.edges if e.kind == "joint" and not e.comp.tree_edge]
    if constraint_only:
        ev = view.evaluate(0.0, view.default_q(), np.zeros(view.nu), masked=False)
        nh_rows = {e.name: len(rows) for e, rows, _ in ev.local_nh}
        lines.append("constraint-only joints (contacts): " + ", ".join(
            f"{e.name} ({sum(1 for n in cut_rows if n.rsplit('.', 1)[0] == e.name)} holonomic + "
            f"{nh_rows.get(e.name, 0)} nonholonomic rows)" for e in constraint_only))
    rig = [e.name for e in topo.edges if e.kind == "joint" and e.dof == 0 and e.comp.tree_edge
           and not isinstance(e.comp, Locked)]
    if rig:
        lines.append(f"rigid offsets merged into their bodies (no coordinates): {', '.join(rig)}")
    lines += _locked_lines([e for e in topo.edges if isinstance(e.comp, Locked)])
    if topo.floating:
        lines.append("free bodies (implicit free joint from the world: FreeMotion, FreeTranslation for a lone point "
                     f"mass): {', '.join(f'{n} ({type(topo.edge(n).comp).__name__})' for n in topo.floating)}")
    if topo.open_frames:
        lines.append(f"open frames (rigid offsets ending in nothing, kept as marker frames): "
                     f"{', '.join(topo.open_frames)}")
    return "\n".join(lines)


def _locked_lines(edges):
    """``locked: N joints (...)`` and what was dropped with them (:meth:`mbcomp.Model.lock`)."""
    if not edges:
        return []
    held = ", ".join(f"{e.name} ({e.comp.joint_class} at " + ", ".join(f"{n}={v:.6g}" for n, v in e.comp.held) + ")"
                     for e in edges)
    out = [f"locked: {len(edges)} joint{'s' * (len(edges) != 1)} held as rigid connections ({held})"]
    dropped = [d for e in edges for d in e.comp.dropped]
    if dropped:
        out.append(f"dropped with the locks: {'; '.join(dropped)}")
    return out
