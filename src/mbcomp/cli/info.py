"""``mbcomp info MODEL.py``: the model summary (bodies, DOF, coordinates, constraints).

The summary describes the assembled system without changing it
(:func:`mbcomp.assembly.summary.summary`).

Examples
--------
>>> from mbcomp.cli.main import make_parser
>>> make_parser().parse_args(["info", "models/slider_crank.py"]).func.__name__
'cmd_info'
"""
from __future__ import annotations

from .loader import load

__all__ = ["cmd_info", "add_parser"]


def cmd_info(args):
    """Print the summary of the model file's system; exit status 0."""
    from ..assembly.system import assemble

    _, model, runtime = load(args)
    system = assemble(model, runtime)
    print(system.summary())
    return 0


def add_parser(sub, common):
    """The ``info`` sub-command on the argparse ``sub``-parsers."""
    i = sub.add_parser("info", help="print the model summary (bodies, DOF, coordinates, constraints)")
    common(i)
    i.set_defaults(func=cmd_info)
    return i
