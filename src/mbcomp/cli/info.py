"""``mbcomp info MODEL.py``: the model summary (bodies, DOF, coordinates, constraints).

The summary describes the assembled system without changing it
(:func:`mbcomp.assembly.summary.summary`). ``--graph topo.svg`` also draws it: the spanning
tree, the cut joints with their rows, the coordinates
(:func:`mbcomp.visual.topology_drawing.draw_topology`; ``.svg``, ``.png`` or ``.pdf``).
A robot file (``mbcomp info robot.urdf``, :mod:`mbcomp.cli.robots`) also gets a short list of
what its import left out or renamed (``model.urdf_notes``).

Examples
--------
>>> from mbcomp.cli.main import make_parser
>>> make_parser().parse_args(["info", "models/slider_crank.py"]).func.__name__
'cmd_info'
>>> make_parser().parse_args(["info", "models/andrews.py", "--graph", "andrews.svg"]).graph
'andrews.svg'
"""
from __future__ import annotations

import pathlib

from .loader import check_output, load
from .robots import import_notes

__all__ = ["cmd_info", "add_parser"]


def cmd_info(args):
    """Print the summary of the model file's system (and draw it with ``--graph``); exit status 0."""
    from ..assembly.system import assemble
    from ..visual.topology_drawing import check_suffix, draw_topology

    graph = getattr(args, "graph", None)
    if graph is not None:  # a bad file name fails before any work
        check_suffix(graph)
        check_output(graph, "--graph")
    _, model, runtime = load(args)
    system = assemble(model, runtime)
    print(system.summary())
    for line in import_notes(model):
        print(line)
    if graph is not None:
        draw_topology(system, graph, title=pathlib.Path(args.model).stem)
        print(f"topology drawn to {graph}")
    return 0


def add_parser(sub, common):
    """The ``info`` sub-command on the argparse ``sub``-parsers."""
    i = sub.add_parser("info", help="print the model summary (bodies, DOF, coordinates, constraints)")
    common(i)
    i.add_argument("--graph", metavar="PATH", help="also draw the topology (spanning tree, cut joints and their "
                                                    "rows, coordinates) to PATH: .svg, .png or .pdf")
    i.set_defaults(func=cmd_info)
    return i
