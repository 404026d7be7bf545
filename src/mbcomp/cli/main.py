"""Command line: ``mbcomp simulate MODEL.py``, ``mbcomp info MODEL.py``, ``mbcomp bench MODEL.py``,
``mbcomp stability MODEL.py``, ``mbcomp study MODEL.py`` and ``mbcomp fit MODEL.py --data meas.csv``.

A model file defines ``build(**params) -> Model`` and may set ``SIMULATION = dict(t_end=...,
rtol=..., atol=..., method=..., stabilization=..., formulation=...)`` as defaults. ``-p name=value`` passes
``name`` to ``build`` when it has no dot, and sets a component parameter at run time when it
has one (``-p spring.c=200``: nothing is re-derived).

One module per command (:mod:`~mbcomp.cli.simulate`, :mod:`~mbcomp.cli.info`,
:mod:`~mbcomp.cli.bench`, :mod:`~mbcomp.cli.stability` with :mod:`~mbcomp.cli.sweep`, :mod:`~mbcomp.cli.study`,
:mod:`~mbcomp.cli.fit`), sharing
:mod:`~mbcomp.cli.loader` (the model file, ``-p``, output paths); this module holds the parser
and :func:`main`.

``mbcomp stability MODEL.py`` linearizes about the model's start state (or, with
``--steady "a=0, b=lo:hi"``, about every steady state found) and prints the eigenvalues and
their classification; ``--sweep name=start:stop:count`` repeats that over a build() or
component parameter and locates where the classification changes (:mod:`mbcomp.stability`).

Exit status: 0 success; 1 the run or the analysis did not succeed; 2 bad input (a model
file, a parameter or an option; the message names the fix); 130 interrupted by Ctrl-C, 143 by
SIGTERM (``simulate`` and ``study`` write what they finished first).

Examples
--------
>>> from mbcomp.cli import parse_value
>>> parse_value("1e-3"), parse_value("(0, 0, 1)"), parse_value("RK45")
(0.001, (0, 0, 1), 'RK45')
>>> from mbcomp.cli.main import make_parser
>>> args = make_parser().parse_args(["simulate", "m.py", "-p", "m_slider=1.5", "--t-end", "2"])
>>> args.func.__name__, args.param, args.t_end
('cmd_simulate', ['m_slider=1.5'], 2.0)
"""
from __future__ import annotations

import argparse
import os
import sys

from ..errors import SimulationError
from ..simulation.endings import Terminated
from . import bench, export, fit, info, simulate, stability, study
from .loader import load_model_file, parse_value
from .messages import EXIT_SIGNAL
from .sweep import parse_sweep

__all__ = ["main", "make_parser", "load_model_file", "parse_value", "parse_sweep"]

#: exit status of bad input (argparse's)
EXIT_USAGE = 2
#: exit status of a run that failed or could not start
EXIT_FAILED = 1


def _common(p):
    """The arguments every command takes: the model file and ``-p NAME=VALUE``."""
    p.add_argument("model", help="model file defining build(**params) -> Model, or a robot file (.urdf, MJCF .xml) "
                                 "whose loader's keywords -p sets (mbcomp.cli.robots)")
    p.add_argument("-p", "--param", action="append", metavar="NAME=VALUE",
                   help="build() argument, or component.param runtime value (repeatable)")


def make_parser():
    """The ``mbcomp`` argument parser: one sub-command per command module."""
    ap = argparse.ArgumentParser(prog="mbcomp", description="Modelica-style multibody modelling and simulation")
    sub = ap.add_subparsers(dest="command", required=True)
    for command in (simulate, bench, info, stability, study, export, fit):
        command.add_parser(sub, _common)
    return ap


def main(argv=None):
    """Run the command line ``argv`` (default ``sys.argv[1:]``); return the exit status."""
    args = make_parser().parse_args(argv)
    try:
        return args.func(args)
    except ValueError as exc:  # ModelError is a ValueError; every input error names its fix
        print(f"mbcomp: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except (SimulationError, ConnectionError) as exc:  # a run that could not start (e.g. a law raising at
        print(f"mbcomp: {exc}", file=sys.stderr)           # t_start), a Dask scheduler that does not answer
        return EXIT_FAILED
    except (KeyboardInterrupt, Terminated) as exc:  # outside a run (whose command writes its results itself)
        name = "SIGTERM" if isinstance(exc, Terminated) else getattr(exc, "signal", None) or "SIGINT"
        print(f"mbcomp: interrupted by {name}", file=sys.stderr)
        return EXIT_SIGNAL[name]
    except BrokenPipeError:  # output piped into e.g. `head`, which closed early
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
