"""The assembled topology, drawn: what ``mbcomp info`` prints, as a picture.

Rigid groups (frames joined by rigid offsets and ground frames, as Gruebler's count groups
them) are the nodes, labelled with their bodies (or ``world``); joints with freedom are the
edges. The spanning tree is drawn solid, layered by its depth from the world and labelled
with each joint's independent coordinates; cut joints are dashed curves labelled with the
constraint rows they keep and the rows initialization dropped as redundant; joints with
nonholonomic (velocity-level) rows are dash-dotted in another colour and name those rows;
flange constraints (gears, belts, racks: rows over joint-axis coordinates) are dotted green
paths from one geared joint's line to the next, one per row, labelled with the gear's type,
numbers and rows.

:func:`topology_graph` is the plain description (dicts and lists: nodes, edges, rows,
coordinates) the drawing is made from; :func:`draw_topology` writes it to ``.svg``, ``.png``
or ``.pdf`` with matplotlib (imported on call, no pyplot). Describing a system changes
nothing in it (:func:`mbcomp.assembly.summary.observer`).

Examples
--------
>>> import mbcomp
>>> m = mbcomp.load_model_file("models/slider_crank.py").build()
>>> d = topology_graph(mbcomp.assemble(m))
>>> [(e["name"], e["kept"], e["dropped"]) for e in d["edges"] if e["kind"] == "cut"]
[('rod_joint', ['x', 'y'], ['z', 'tilt_1', 'tilt_2'])]
"""
from __future__ import annotations

import pathlib
import textwrap

import numpy as np

from ..assembly.topology import ROOT
from .topology_layout import gear_routes, layout, routes, tree_label_points

__all__ = ["topology_graph", "draw_topology", "topology_svg", "check_suffix", "SUFFIXES"]

#: the file formats :func:`draw_topology` writes (matplotlib's, chosen by the suffix)
SUFFIXES = (".svg", ".png", ".pdf")

#: colours: tree joints, cut joints (holonomic loop closure), joints with nonholonomic rows, driven joints
COLOURS = dict(tree="#222222", cut="#d62728", nonholonomic="#7b3fb5", driven="#1f77b4", rigid="#707070",
               gear="#2a8a2a")
#: dash patterns (matplotlib line styles): cut joints, joints with nonholonomic rows, gear rows
DASHES = dict(cut=(0, (6, 3)), nonholonomic=(0, (7, 2.5, 1.5, 2.5)), gear=(0, (1, 2.2)))


def check_suffix(path):
    """The suffix of ``path`` if :func:`draw_topology` can write it, else a ``ValueError``.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write.

    Returns
    -------
    str
        The suffix, lower case (``".svg"``, ``".png"`` or ``".pdf"``).

    Examples
    --------
    >>> check_suffix("topo.SVG")
    '.svg'
    >>> try:
    ...     check_suffix("topo.txt")
    ... except ValueError as exc:
    ...     print(exc)
    cannot draw the topology to topo.txt: unsupported suffix '.txt' -> fix: name the file with one of .svg, .png, .pdf
    """
    suffix = pathlib.Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        raise ValueError(f"cannot draw the topology to {path}: unsupported suffix {suffix or '(none)'!r} -> fix: "
                         f"name the file with one of {', '.join(SUFFIXES)}")
    return suffix


# --- the description ------------------------------------------------------------------------
def _edge_kind(e, cut):
    """``"cut"``, ``"ground"`` (a ground frame in the tree), ``"rigid"`` (a 0-DOF tree edge) or ``"tree"``."""
    if e.name in cut:
        return "cut"
    if e.kind == "ground":
        return "ground"
    return "rigid" if e.dof == 0 else "tree"


def _groups(topo):
    """``{frame node: group}``: frames joined by non-cut rigid offsets and ground frames are
    one group, named by its smallest frame node (``ROOT`` for the world's group)."""
    parent = {n: n for n in [ROOT, *range(topo.n_nodes)]}

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    cut = set(topo.cut)
    for e in topo.edges:
        if _edge_kind(e, cut) in ("ground", "rigid"):
            a, b = sorted((find(e.node_a), find(e.node_b)))
            parent[b] = a
    return {n: find(n) for n in parent}


def _rows(view):
    """``({joint: [holonomic row]}, {joint: [nonholonomic row]})`` at the default coordinates."""
    holonomic = {}
    for name in view.constraint_names(all_rows=True):
        joint, row = name.rsplit(".", 1)
        holonomic.setdefault(joint, []).append(row)
    ev = view.evaluate(0.0, view.default_q(), np.zeros(view.nu), masked=False)
    return holonomic, {e.name: list(rows) for e, rows, _ in ev.local_nh}


def _edge_entry(e, topo, group, kinds, rows, dropped):
    """One edge of the description (see :func:`topology_graph`)."""
    holonomic, nonholonomic = rows
    kind = kinds[e.name]
    a, b = (e.parent, e.child) if e.parent is not None else (e.node_a, e.node_b)
    coords = [n[len(e.name) + 1:] for n in topo.q_names[e.q]] if kind == "tree" else []
    mine = holonomic.get(e.name, [])
    gone = [r for r in mine if f"{e.name}.{r}" in dropped]
    return dict(name=e.name, type=type(e.comp).__name__, kind=kind, a=group[a], b=group[b], dof=e.dof,
                coordinates=coords, drive=e.drive, implicit=e.implicit, rows=list(mine),
                kept=[r for r in mine if r not in gone], dropped=gone,
                nonholonomic=list(nonholonomic.get(e.name, [])))


def _node_entries(topo, group, edges):
    """The nodes of the description: one per rigid group, the world's first."""
    members = {}
    for n, g in group.items():
        members.setdefault(g, []).append(n)
    nodes = []
    for g in sorted(members, key=lambda g: (g != ROOT, g)):
        frames = sorted(members[g])
        bodies = [path for path, _, n in topo.bodies if group[n] == g]
        offsets = [e["name"] for e in edges if e["kind"] in ("rigid", "ground") and e["b"] == g
                   and e["type"] != "World"]
        if g == ROOT:
            kind, label = "world", "world"
        elif bodies:
            kind, label = "body", "\n".join(bodies)
        else:
            ports = [p for n in frames for p in topo.node_ports.get(n, [])]
            kind, label = "frame", f"frame {ports[0] if ports else g}"
        nodes.append(dict(id=g, label=label, kind=kind, bodies=bodies, frames=frames, offsets=offsets))
    return nodes


def _gear_entries(system, rows, dropped):
    """The flange constraints (gears): ``name``, ``type``, ``params`` (its numbers, e.g.
    ``"ratio 3"``), ``rows`` (each ``{"name", "joints"}``: the joints whose axis coordinates
    the row ties, in the order of its terms), ``dropped`` rows."""
    from ..modeling.roles import FlangeSum

    out = []
    for fr in system.topology.flange_rows:
        p = system.P[fr.name]
        forms = fr.comp.rows({pn: FlangeSum({pn: 1.0}) for pn in fr.ports}, p)
        gear_rows = [dict(name=rname, joints=list(dict.fromkeys(fr.ports[pn][0] for pn, c in form.terms.items()
                                                                if fr.ports.get(pn) is not None and c != 0)))
                     for rname, form in forms]
        names = rows[0].get(fr.name, [r["name"] for r in gear_rows])
        out.append(dict(name=fr.name, type=type(fr.comp).__name__, params=_numbers(fr.comp, p), rows=gear_rows,
                        dropped=[r for r in names if f"{fr.name}.{r}" in dropped]))
    return out


def _numbers(comp, p):
    """``"ratio 3"``, ``"r_a 0.1 m, r_b 0.2 m"``: a component's numeric scalar parameters."""
    out = []
    for name, par in type(comp).params().items():
        v = getattr(p, name, None)
        if isinstance(v, (int, float, np.floating, np.integer)) and not isinstance(v, bool):
            unit = "" if getattr(par, "unit", "1") in ("1", "", None) else f" {par.unit}"
            out.append(f"{name} {float(v):g}{unit}")
    return ", ".join(out)


def topology_graph(system, init=None):
    """The plain description of an assembled system's topology that :func:`draw_topology` draws.

    Parameters
    ----------
    system : MultibodySystem
        The assembled system; not changed (it is described through an observer copy).
    init : InitialState, optional
        Its consistent initialization, if already computed (it says which rows are
        redundant); else a copy is initialized, as ``mbcomp info`` does.

    Returns
    -------
    dict
        ``nodes``: one dict per rigid group (``id`` -- ``ROOT`` for the world's --, ``label``,
        ``kind`` ``"world"``/``"body"``/``"frame"``, ``bodies``, ``frames`` (frame nodes),
        ``offsets`` (rigid offsets and ground frames merged into it)). ``edges``: one dict per
        joint and ground frame (``name``, ``type``, ``kind`` ``"tree"``/``"cut"``/``"rigid"``/
        ``"ground"``, ``a``/``b`` the groups (parent, child for tree edges), ``dof``,
        ``coordinates`` (tree joints' q names without the joint's prefix), ``drive``,
        ``rows``/``kept``/``dropped`` (holonomic constraint rows), ``nonholonomic`` rows).
        ``gears``: one dict per flange constraint (``name``, ``type``, ``params``, ``rows``:
        ``{"name", "joints"}`` -- the joints whose axes each row ties --, ``dropped``).
        ``coordinates`` (every q name), ``dropped`` (full names of the redundant rows),
        ``nonholonomic`` (full names), ``dof`` (mobility, ``None`` when initialization
        fails), ``gruebler``, ``N``, ``C``, ``L``, ``rank``, ``nq``, ``nu``.

    Examples
    --------
    >>> import mbcomp
    >>> d = topology_graph(mbcomp.assemble(mbcomp.load_model_file("models/andrews.py").build()))
    >>> sorted(e["name"] for e in d["edges"] if e["kind"] == "cut"), d["dof"], len(d["dropped"])
    (['pin_E_EG', 'pin_E_HE', 'pin_E_triangle'], 1, 9)
    """
    from ..assembly.summary import dof_report, observer

    topo = system.topology
    report = dof_report(system, init)
    rows = _rows(observer(system))
    group = _groups(topo)
    cut = set(topo.cut)
    kinds = {e.name: _edge_kind(e, cut) for e in topo.edges}
    dropped = set(report["redundant"])
    edges = [_edge_entry(e, topo, group, kinds, rows, dropped) for e in topo.edges]
    return dict(nodes=_node_entries(topo, group, edges), edges=edges, gears=_gear_entries(system, rows, dropped),
                coordinates=list(topo.q_names),
                dropped=list(report["redundant"]),
                nonholonomic=[f"{j}.{r}" for j, rs in rows[1].items() for r in rs],
                dof=report["mobility"], gruebler=report["gruebler"], N=report["N"], C=report["C"],
                L=report["L"], rank=report["rank"], nq=topo.nq, nu=topo.nu)


# --- the drawing ----------------------------------------------------------------------------
def _system(model_or_system, params):
    """The assembled system of a ``Model`` (assembled here) or a ``MultibodySystem``."""
    from ..assembly.system import MultibodySystem, assemble

    if isinstance(model_or_system, MultibodySystem):
        return model_or_system.with_params(params) if params else model_or_system
    if hasattr(model_or_system, "validate"):
        return assemble(model_or_system, params)
    raise ValueError(f"draw_topology draws a Model or an assembled MultibodySystem, not a "
                     f"{type(model_or_system).__name__} -> fix: pass the model (or mbcomp.assemble(model))")


def _wrap(text, width=34):
    return "\n".join(textwrap.wrap(text, width, break_on_hyphens=False))


def _cut_label(e):
    """The label of a cut joint: its name, the rows it keeps, those dropped, its velocity rows."""
    lines = [f"{e['name']} ({e['type']}, cut)"]
    if e["rows"]:
        lines.append(_wrap("keeps " + (", ".join(e["kept"]) or "none")))
    if e["dropped"]:
        lines.append(_wrap("dropped " + ", ".join(e["dropped"])))
    if e["nonholonomic"]:
        lines.append(_wrap("nonholonomic " + ", ".join(e["nonholonomic"])))
    return "\n".join(lines)


def _tree_label(e):
    """The label of a tree joint: its name, type and independent coordinates (or its drive)."""
    what = f"driven by {e['drive']}" if e["drive"] else ", ".join(e["coordinates"])
    lines = [e["name"], _wrap(f"{e['type']}: {what}", 30)]
    if e["nonholonomic"]:
        lines.append(_wrap("nonholonomic " + ", ".join(e["nonholonomic"]), 30))
    return "\n".join(lines)


def _draw_nodes(ax, desc, pos, renderer):
    """Each rigid group a rounded box: its bodies (bold), its rigid offsets (small, grey) below."""
    from matplotlib.patches import FancyBboxPatch

    faces = dict(world="#e4e4e4", body="#fff3c4", frame="#ffffff")
    to_data = ax.transData.inverted()
    for n in desc["nodes"]:
        x, y = pos[n["id"]]
        what = "ground frames" if n["kind"] == "world" else "+"
        small = _wrap(f"{what} {', '.join(n['offsets'])}", 26) if n["offsets"] else ""
        shift = 0.09 * (len(small.splitlines()) if small else 0)
        texts = [ax.text(x, y + shift, n["label"], ha="center", va="center", fontsize=10, zorder=6,
                         fontweight="normal" if n["kind"] == "frame" else "bold")]
        if small:
            texts.append(ax.text(x, texts[0].get_window_extent(renderer).transformed(to_data).y0 - 0.04, small,
                                 ha="center", va="top", fontsize=6.5, color=COLOURS["rigid"], zorder=6))
        (x0, y0), (x1, y1) = to_data.transform([[min(t.get_window_extent(renderer).x0 for t in texts),
                                                 min(t.get_window_extent(renderer).y0 for t in texts)],
                                                [max(t.get_window_extent(renderer).x1 for t in texts),
                                                 max(t.get_window_extent(renderer).y1 for t in texts)]])
        box = FancyBboxPatch((x0, y0), x1 - x0, y1 - y0, boxstyle="round,pad=0.08", fc=faces[n["kind"]],
                             ec="#505050", lw=1.2, zorder=5)
        box.set_gid(f"node-{n['id']}")
        ax.add_patch(box)


def _draw_tree_edges(ax, desc, pos):
    """The spanning tree's joints: solid lines, labelled with their coordinates."""
    at = tree_label_points(desc, pos)
    for e in desc["edges"]:
        if e["kind"] != "tree":
            continue
        (xa, ya), (xb, yb) = pos[e["a"]], pos[e["b"]]
        colour = COLOURS["driven"] if e["drive"] else COLOURS["tree"]
        line, = ax.plot([xa, xb], [ya, yb], color=colour, lw=1.8, zorder=1, solid_capstyle="round")
        line.set_gid(f"tree-{e['name']}")
        label = ax.text(*at[e["name"]], _tree_label(e), ha="center", va="center", fontsize=7.5, color=colour,
                        zorder=3, bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="none", alpha=0.9))
        label.set_gid(f"label-tree-{e['name']}")


def _draw_cut_edges(ax, desc, curves):
    """The cut joints: dashed curves (dash-dotted for nonholonomic rows), labelled with their rows."""
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path

    for e in desc["edges"]:
        if e["kind"] != "cut":
            continue
        nh = "nonholonomic" if e["nonholonomic"] else "cut"
        route = curves[e["name"]]
        patch = PathPatch(Path(route["ctrl"], [Path.MOVETO, Path.CURVE4, Path.CURVE4, Path.CURVE4]), fc="none",
                          ec=COLOURS[nh], lw=1.7, ls=DASHES[nh], zorder=2)
        patch.set_gid(f"cut-{e['name']}")
        ax.add_patch(patch)
        label = ax.text(*route["label"], _cut_label(e), ha="center", va="center", fontsize=7.5, color=COLOURS[nh],
                        zorder=4, bbox=dict(boxstyle="round,pad=0.25", fc="white", ec=COLOURS[nh], lw=0.6, alpha=0.95))
        label.set_gid(f"label-cut-{e['name']}")


def _gear_label(g):
    """``gear: IdealGear ratio 3 (1 row)``, and the rows dropped as redundant."""
    what = " ".join(x for x in (g["type"], g["params"]) if x)
    text = f"{g['name']}: {what} ({_count(len(g['rows']), 'row')})"
    return text + (f"; dropped {', '.join(g['dropped'])}" if g["dropped"] else "")


def _draw_gears(ax, desc, paths):
    """The flange constraints: a dotted path per row between the joints it ties, one label per gear."""
    for g in desc.get("gears", []):
        drawn = [(row, paths[(g["name"], row["name"])]) for row in g["rows"] if (g["name"], row["name"]) in paths]
        for row, path in drawn:
            line, = ax.plot(path["points"][:, 0], path["points"][:, 1], color=COLOURS["gear"], lw=1.6,
                            ls=DASHES["gear"], zorder=2, dash_capstyle="round")
            line.set_gid(f"gear-{g['name']}-{row['name']}")
        if drawn:
            label = ax.text(*drawn[0][1]["label"], _gear_label(g), ha="center", va="center", fontsize=6.5,
                            color=COLOURS["gear"], zorder=4,
                            bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.85))
            label.set_gid(f"label-gear-{g['name']}")


def _legend(fig, desc):
    """The legend: which line is which (the tree always, the rest when drawn)."""
    from matplotlib.lines import Line2D

    edges = desc["edges"]
    items = [(COLOURS["tree"], "-", "tree joint: its independent coordinates")]
    if any(e["kind"] == "cut" and not e["nonholonomic"] for e in edges):
        items.append((COLOURS["cut"], DASHES["cut"], "cut joint (loop closure): rows kept, redundant rows dropped"))
    if any(e["nonholonomic"] for e in edges):
        items.append((COLOURS["nonholonomic"], DASHES["nonholonomic"], "joint with nonholonomic (velocity) rows"))
    if any(e["drive"] for e in edges):
        items.append((COLOURS["driven"], "-", "driven joint (prescribed, no coordinate)"))
    if desc.get("gears"):
        items.append((COLOURS["gear"], DASHES["gear"], "gear row (flange constraint) between joint axes"))
    handles = [Line2D([], [], color=c, ls=ls, lw=1.6, label=t) for c, ls, t in items]
    legend = fig.legend(handles=handles, loc="lower right", fontsize=7.5, frameon=False, handlelength=4.5,
                        bbox_to_anchor=(0.99, 0.01))
    legend.set_gid("legend")


def _count(n, what):
    return f"{n} {what}{'' if n == 1 else 's'}"


def _header(desc, title):
    """The title line (DOF) and the counting line (Gruebler, rank, dropped and nonholonomic rows)."""
    dof = desc["dof"] if desc["dof"] is not None else "unknown (initialization failed)"
    gears = desc.get("gears", [])
    rows = sum(len(e["rows"]) for e in desc["edges"]) + sum(len(g["rows"]) for g in gears)
    head = f"{title + ': ' if title else ''}{dof} degree{'' if dof == 1 else 's'} of freedom"
    cuts = sum(e["kind"] == "cut" for e in desc["edges"])
    count = (f"Grübler M = 6N − C − L = 6·{desc['N']} − {desc['C']} − {desc['L']} = {desc['gruebler']};   "
             f"{_count(cuts, 'cut joint')}, " + (f"{_count(len(gears), 'gear')}, " if gears else "")
             + f"{_count(rows, 'constraint row')} of rank {desc['rank']}, "
             f"{len(desc['dropped'])} redundant dropped, {len(desc['nonholonomic'])} nonholonomic")
    return head, count


def _bounds(pos, curves, gears=()):
    """``(x0, x1, y0, y1)`` (inches) holding every group, curve and label, with margins."""
    pts = [np.asarray(p, float) for p in pos.values()]
    for g in gears:
        pts += [*g["points"], np.asarray(g["label"], float)]
    for r in curves.values():
        pts += [np.asarray(r["label"], float), *np.asarray(r["ctrl"], float)[[0, 3]]]
        pts.append(0.125 * (r["ctrl"][0] + 3 * r["ctrl"][1] + 3 * r["ctrl"][2] + r["ctrl"][3]))
    xy = np.array(pts)
    return xy[:, 0].min() - 1.6, xy[:, 0].max() + 1.6, xy[:, 1].min() - 0.9, xy[:, 1].max() + 0.6


def _figure(desc, title):
    """The matplotlib ``Figure`` of the description: 1 data unit = 1 inch."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    pos = layout(desc)
    curves = routes(desc, pos)
    gears = gear_routes(desc, pos, curves)
    x0, x1, y0, y1 = _bounds(pos, curves, gears.values())
    width, top, foot = max(x1 - x0, 9.0), 0.8, 1.2
    height = (y1 - y0) + top + foot
    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0, foot / height, 1, (y1 - y0) / height))
    cx = 0.5 * (x0 + x1)
    ax.set_xlim(cx - width / 2, cx + width / 2)
    ax.set_ylim(y0, y1)
    ax.set_axis_off()
    _draw_cut_edges(ax, desc, curves)
    _draw_gears(ax, desc, gears)
    _draw_tree_edges(ax, desc, pos)
    _draw_nodes(ax, desc, pos, fig.canvas.get_renderer())
    head, count = _header(desc, title)
    fig.text(0.5, 1 - 0.3 / height, head, ha="center", va="center", fontsize=13, fontweight="bold")
    fig.text(0.5, 1 - 0.62 / height, count, ha="center", va="center", fontsize=8.5, color="#333333")
    coords = f"independent coordinates ({desc['nq']} q, {desc['nu']} speeds): " + (
        ", ".join(desc["coordinates"]) or "none")
    fig.text(0.01, (foot - 0.15) / height, textwrap.fill(coords, int(width * 7), break_on_hyphens=False),
             ha="left", va="top", fontsize=7.5)
    _legend(fig, desc)
    return fig


def draw_topology(model_or_system, path, params=None, title=None, init=None):
    """Draw the assembled topology to ``path`` (``.svg``, ``.png`` or ``.pdf``).

    Rigid groups are nodes labelled with their bodies (``world`` for the ground); the
    spanning tree's joints are solid edges labelled with their independent coordinates, layered by
    depth from the world; cut joints are dashed curves labelled with the constraint rows they
    keep and those dropped as redundant; joints with nonholonomic rows are dash-dotted and
    name them; each gear row is a dotted path between the joints it ties. The title gives the
    DOF and Gruebler's count (gears and their rows included); the foot lists the coordinates.
    Texts stay text in an SVG (each cut edge is the group ``cut-<joint>``, its label
    ``label-cut-<joint>``; each tree edge ``tree-<joint>``, its label ``label-tree-<joint>``;
    each gear row ``gear-<gear>-<row>``, the gear's label ``label-gear-<gear>``).

    Parameters
    ----------
    model_or_system : Model or MultibodySystem
        A model (assembled here) or an assembled system (not changed).
    path : str or os.PathLike
        The file to write; its suffix picks the format (:data:`SUFFIXES`).
    params : dict, optional
        Parameter overrides ``{"comp.param": value}`` for the assembly.
    title : str, optional
        Put before the DOF in the title (e.g. the model file's name).
    init : InitialState, optional
        The system's consistent initialization, if already computed.

    Returns
    -------
    str or os.PathLike
        ``path``.

    Raises
    ------
    ValueError
        An unsupported suffix (checked before any work), or something that is no model.

    Examples
    --------
    >>> import os, tempfile, mbcomp
    >>> m = mbcomp.load_model_file("models/slider_crank.py").build()
    >>> out = draw_topology(m, os.path.join(tempfile.mkdtemp(), "slider_crank.svg"), title="slider_crank")
    >>> text = open(out).read()
    >>> 'id="cut-rod_joint"' in text and "crank_joint" in text
    True
    """
    import matplotlib

    suffix = check_suffix(path)
    system = _system(model_or_system, params)
    fig = _figure(topology_graph(system, init), title)
    metadata = {"svg": {"Date": None}, "pdf": {"CreationDate": None}}.get(suffix[1:])
    with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": "mbcomp-topology"}):
        fig.savefig(path, format=suffix[1:], dpi=130, metadata=metadata)
    return path


def topology_svg(model_or_system, params=None, title=None):
    """The drawing of :func:`draw_topology` as SVG text, made in memory (no file): what a
    notebook shows for a model (:meth:`mbcomp.Model._repr_html_`). The text starts at the
    ``<svg`` element (no XML prolog), so it can be put inline in an HTML page.

    Parameters
    ----------
    model_or_system : Model or MultibodySystem
        A model (assembled here) or an assembled system (not changed).
    params : dict, optional
        Parameter overrides ``{"comp.param": value}`` for the assembly.
    title : str, optional
        Put before the DOF in the title.

    Returns
    -------
    str

    Examples
    --------
    >>> import mbcomp
    >>> svg = topology_svg(mbcomp.load_model_file("models/slider_crank.py").build())
    >>> svg.startswith("<svg") and 'id="cut-rod_joint"' in svg
    True
    """
    import io

    import matplotlib

    fig = _figure(topology_graph(_system(model_or_system, params)), title)
    buffer = io.StringIO()
    with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": "mbcomp-topology"}):
        fig.savefig(buffer, format="svg", dpi=130, metadata={"Date": None})
    text = buffer.getvalue()
    return text[text.index("<svg"):]
