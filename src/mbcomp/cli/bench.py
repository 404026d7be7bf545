"""``mbcomp bench MODEL.py``: a work-precision study of every formulation x solver.

Runs :func:`mbcomp.analysis.workprecision.work_precision` over a tolerance sweep, prints the
summary table (fastest CPU time reaching ``--target``), and writes the CSV and the plot
(checked before the study starts). ``--executor processes|dask|tcp://host:port`` runs each
combination's sweep as one task there (:func:`mbcomp.analysis.parallel.map_on`).

Examples
--------
>>> from mbcomp.cli.main import make_parser
>>> args = make_parser().parse_args(["bench", "models/andrews.py", "--tols", "1e-6,1e-8"])
>>> args.func.__name__, args.tols, args.max_cpu
('cmd_bench', '1e-6,1e-8', 60.0)
"""
from __future__ import annotations

import pathlib

from .loader import check_output, model_module, split_params

__all__ = ["cmd_bench", "add_parser"]


def _select(combos, spec):
    """The combinations ``spec`` selects: a full label selects just that one, else substrings."""
    keys = [k.strip().lower() for k in spec.split(",")]
    exact = [c for c in combos if c.label.lower() in keys]
    chosen = exact or [c for c in combos if any(k in c.label.lower() for k in keys)]
    if not chosen:
        raise ValueError(f"no combination matches --combos {spec!r}; labels: " + "; ".join(c.label for c in combos))
    return chosen


def cmd_bench(args):
    """The work-precision study of the model file; exit status 0."""
    from ..analysis import workprecision as wp

    name = pathlib.Path(args.model).stem
    out = args.out or f"{name}_work_precision.csv"
    png = args.plot or f"{name}_work_precision.png"
    check_output(out, "--out")
    check_output(png, "--plot")
    mod = model_module(args.model)
    if args.executor not in (None, "serial") and getattr(mod, "ROBOT_FORMAT", None):
        raise ValueError(f"--executor {args.executor}: the workers read the model file by its path, and a robot file "
                         f"({mod.ROBOT_FORMAT}) is no Python model file -> run without --executor, or write a model "
                         "file whose build() returns mbcomp.load_urdf(...) / load_mjcf(...)")
    build_kw, runtime = split_params(args.param, mod.build)
    combos = _select(wp.default_combos(), args.combos) if args.combos else wp.default_combos()
    tols = [float(x) for x in args.tols.split(",")] if args.tols else None
    from ..analysis.parallel import running_on

    with running_on(args.executor, args.workers) as executor:  # Ctrl-C, SIGTERM: no worker left behind
        rows = wp.work_precision(args.model if executor is not None else mod, combos, tols=tols, build_kw=build_kw,
                                 params=runtime or None, t_end=args.t_end, max_cpu=args.max_cpu, executor=executor,
                                 progress=executor is not None)
    print("\n" + wp.summary(rows, args.target, title=name))
    wp.write_csv(rows, out)
    wp.plot(rows, png, title=name, target=args.target)
    print(f"wrote {out} and {png}")
    return 0


def add_parser(sub, common):
    """The ``bench`` sub-command on the argparse ``sub``-parsers."""
    b = sub.add_parser("bench", help="work-precision study: every formulation x solver over a tolerance sweep")
    common(b)
    b.add_argument("--t-end", dest="t_end", type=float, help="end time (default: the model's REFERENCE or SIMULATION)")
    b.add_argument("--target", type=float, default=1e-6, help="relative position error for the summary table")
    b.add_argument("--tols", help="comma-separated rtol values (default 1e-3 ... 1e-10)")
    b.add_argument("--combos", help="comma-separated substrings selecting combinations, e.g. 'radau5,DOP853'")
    b.add_argument("--max-cpu", dest="max_cpu", type=float, default=60.0,
                   help="stop a combination's sweep after a run slower than this (s)")
    b.add_argument("--executor", metavar="WHERE",
                   help="where the combinations run, one task each: serial (default), processes, dask (a local "
                   "Dask cluster) or tcp://host:port; CPU times are measured per run in its worker")
    b.add_argument("--workers", type=int, help="processes of --executor processes (default: the cores, at most 4)")
    b.add_argument("--out", help="CSV file (default MODEL_work_precision.csv)")
    b.add_argument("--plot", help="PNG file (default MODEL_work_precision.png)")
    b.set_defaults(func=cmd_bench)
    return b
