"""``mbcomp study MODEL.py --grid NAME=VALUES --metric NAME=EXPR``: many runs, one table.

Runs :func:`mbcomp.study` over the grid (or a Monte Carlo sample) on the chosen executor,
prints a summary (runs, failed, wall time, executor), and writes the table (``--out``, CSV)
and a chart (``--plot``: ``--y`` against ``--x``, by default the first metric against the
first grid parameter).

``--grid`` values (repeatable; several make a full factorial):

* ``crank_joint.w0=2:10:9``: 9 points from 2 to 10 (``numpy.linspace``);
* ``crank.m=0.5,1,2``: a list (``;`` separates values that are themselves lists);
* ``crank.m=U(0.9,1.1)`` / ``crank.m=N(1,0.05)``: uniform / normal, with ``--samples N``
  (and ``--seed S`` to repeat the sample).

A name with a dot is a component parameter (set at run time, nothing recompiled), a name
without one a ``build()`` argument (its values parsed as ``-p`` parses them). ``-p`` fixes a
value for every run. Metrics are text parsed by :mod:`mbcomp.analysis.metrics`
(``peak=max(abs(pin.f.y))``, ``final=last(crank_joint.phi)``), never ``eval``-ed.

The model travels to the workers as its file's path, so a file without an
``if __name__ == "__main__":`` guard works on every executor. Exit status 0 unless every run
failed (1); bad input 2; Ctrl-C 130 and SIGTERM 143, on every executor: the rows of the runs
that finished are written to ``--out`` (and ``--plot``), one line on stderr says so, and no
worker process is left behind (:mod:`mbcomp.analysis.executors`).

Examples
--------
>>> from mbcomp.cli.study import parse_grid
>>> parse_grid("crank_joint.w0=2:10:5")
('crank_joint.w0', [2.0, 4.0, 6.0, 8.0, 10.0])
>>> parse_grid("crank.m=U(0.9, 1.1)"), parse_grid("crank.m=0.5,1,2")
(('crank.m', Uniform(lo=0.9, hi=1.1)), ('crank.m', [0.5, 1, 2]))
>>> parse_grid("crank_joint.w0=2:10")
Traceback (most recent call last):
...
ValueError: --grid 'crank_joint.w0=2:10': a range lo:hi:n needs the number of points n after the second ':' -> fix: e.g. --grid crank_joint.w0=2:10:9 (9 points), or list the values: NAME=v1,v2,...
"""
from __future__ import annotations

import pathlib
import re
import sys

import numpy as np

from ..simulation.endings import sigterm_interrupts
from .loader import check_output, model_module, split_params, takes
from .messages import EXIT_SIGNAL
from .params import build_value, describe_parameters, parse_value
from .robots import is_robot_file, portable_build

__all__ = ["cmd_study", "parse_grid", "add_parser"]

_GRID_HINT = ("write --grid NAME=lo:hi:n (n points), NAME=v1,v2,... , NAME=U(lo,hi) or NAME=N(mu,sigma), "
              "e.g. --grid crank_joint.w0=2:10:9")
_DIST = re.compile(r"^([UN])\s*\(\s*([^,()]+)\s*,\s*([^,()]+)\s*\)$", re.IGNORECASE)
#: simulate() options the command line sets (overriding the model file's SIMULATION)
_OPTIONS = ("rtol", "atol", "method", "n_out", "backend")


def _number(text, spec):
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"--grid {spec!r}: {text.strip()!r} is not a number; {_GRID_HINT}") from None
    if not np.isfinite(value):
        raise ValueError(f"--grid {spec!r}: {text.strip()!r} is not finite; {_GRID_HINT}")
    return value


def _check_range(values, spec):
    """``lo:hi:n`` has three parts, each a number: a forgotten point count (``2:10``) or a
    range with a part too many is no value of the parameter."""
    parts = [p.strip() for p in values.split(":")]
    if len(parts) == 3 and all(parts):
        return
    example = f"{spec.partition('=')[0].strip()}={parts[0] or 2}:{parts[1] if len(parts) > 1 and parts[1] else 10}:9"
    if len(parts) < 3 or (len(parts) == 3 and not parts[2]):
        raise ValueError(f"--grid {spec!r}: a range lo:hi:n needs the number of points n after the second ':' "
                         f"-> fix: e.g. --grid {example} (9 points), or list the values: NAME=v1,v2,...")
    what = f"three parts, not {len(parts)}" if len(parts) > 3 else "a number on each side of the first ':'"
    raise ValueError(f"--grid {spec!r}: a range lo:hi:n needs {what} -> fix: e.g. --grid {example}, or list the "
                     "values: NAME=v1,v2,...")


def parse_grid(spec, build=None):
    """``"NAME=VALUES"`` -> ``(name, values)``: a list of values or a distribution.

    Parameters
    ----------
    spec : str
        See the module notes.
    build : callable, optional
        The model file's ``build``: a name without a dot must be one of its arguments, and
        its listed values are parsed into the kind its default declares.

    Raises
    ------
    ValueError
        Naming the bad part and the fix.
    """
    from ..analysis.study import Normal, Uniform

    text = str(spec).strip()
    name, sep, values = (x.strip() for x in text.partition("="))
    if not sep or not name or not values:
        raise ValueError(f"--grid {text!r}: {_GRID_HINT}")
    if "." not in name and build is not None and not takes(build, name):
        raise ValueError(f"--grid {text}: build() takes no parameter {name}; it takes: {describe_parameters(build)} "
                         "-> fix: use one of these names, or component.param for a component parameter")
    dist = _DIST.match(values)
    if dist:
        a, b = _number(dist.group(2), text), _number(dist.group(3), text)
        if dist.group(1).upper() == "U":
            if not a < b:
                raise ValueError(f"--grid {text!r}: U(lo,hi) needs lo < hi")
            return name, Uniform(a, b)
        if b < 0:
            raise ValueError(f"--grid {text!r}: N(mu,sigma) needs sigma >= 0")
        return name, Normal(a, b)
    if ":" in values and not values.startswith(("(", "[", "'", '"')):
        _check_range(values, text)
        lo, hi, n = values.split(":")
        count = _number(n, text)
        if count < 1 or count != int(count):
            raise ValueError(f"--grid {text!r}: the number of points {n.strip()!r} must be a whole number >= 1; "
                             f"{_GRID_HINT}")
        return name, np.linspace(_number(lo, text), _number(hi, text), int(count)).tolist()
    parts = [p for p in values.split(";" if ";" in values else ",") if p.strip()]
    if "." in name or build is None:
        return name, [parse_value(p) for p in parts]
    try:
        return name, [build_value(build, name, p) for p in parts]
    except ValueError as exc:
        raise ValueError(f"--grid {text}: {exc}") from None


def _grid(args, mod):
    """The study's grid: every ``--grid`` plus the ``-p`` values fixed for every run."""
    build_kw, runtime = split_params(args.param, mod.build)
    grid = {}
    for spec in args.grid:
        name, values = parse_grid(spec, mod.build)
        if name in grid:
            raise ValueError(f"--grid {name} is given twice -> give all its values in one --grid")
        grid[name] = values
    random = [k for k, v in grid.items() if not isinstance(v, list)]
    if random and not args.samples:
        raise ValueError(f"--grid {random[0]} is a distribution: add --samples N (the number of runs) and --seed S "
                         "to repeat the sample")
    if args.samples and not random:
        raise ValueError("--samples is for a Monte Carlo study: give a distribution, e.g. --grid crank.m=U(0.9,1.1)")
    for name, value in {**build_kw, **runtime}.items():
        if name in grid:
            raise ValueError(f"{name} is both fixed (-p) and varied (--grid) -> keep one")
        grid[name] = value if random else [value]
    return grid


def _summary(res, executor):
    st = res.stats
    line = (f"runs {st['runs']}, failed {st['failed']}, wall time {st['wall_time']:.2f} s, executor {executor} "
            f"({st.get('workers', 1)} worker{'s' if st.get('workers', 1) != 1 else ''}, {st.get('chunks', 0)} chunks)")
    print(line)
    status, message = res["status"], res["message"]
    troubles = [i for i in range(len(res)) if status[i] != "success" or "; metric " in str(message[i])]
    for i in troubles[:5]:
        values = ", ".join(f"{k} = {res.runs[i][k]!r}" for k in res.parameters)
        print(f"  run {i} ({values}): {status[i]}: {message[i]}")
    if len(troubles) > 5:
        print(f"  ... and {len(troubles) - 5} more (the table's status and message columns)")


def cmd_study(args):
    """The study of the model file; exit status 1 only when every run failed, 130 / 143 when
    Ctrl-C / SIGTERM stopped it (the finished rows written)."""
    from ..analysis.metrics import parse_metric
    from ..analysis.parallel import executor_of

    check_output(args.out, "--out")
    check_output(args.plot, "--plot")
    metrics = dict(parse_metric(m) for m in args.metric or [])
    mod = model_module(args.model)
    grid = _grid(args, mod)
    x, y = _axes(args, grid, metrics)
    sim = dict(getattr(mod, "SIMULATION", {}))
    t_end = args.t_end or sim.pop("t_end", 1.0)
    sim.pop("t_end", None)
    sim.update({k: getattr(args, k) for k in _OPTIONS if getattr(args, k) is not None})
    with sigterm_interrupts():  # SIGTERM anywhere in the command: the pool's workers are ended all the same
        executor, owned = executor_of(args.executor, args.workers)
        res, stopped = None, None
        try:
            res, stopped = _run(args, grid, t_end, metrics, sim, executor)
        finally:
            if owned and (res is None or stopped):  # a signal, an error: no worker process left behind
                executor.terminate()
            elif owned:
                executor.shutdown()
        return _report(res, stopped, args, executor, x, y)


def _run(args, grid, t_end, metrics, sim, executor):
    """``(table, stopped)``: the study's table, and the :class:`StudyInterrupted` that stopped
    it (its table: the finished runs) or None."""
    from ..analysis.study import StudyInterrupted, study

    try:
        source = portable_build(args.model) if is_robot_file(args.model) else str(pathlib.Path(args.model).resolve())
        res = study(source, grid, t_end=t_end, metrics=metrics, samples=args.samples,
                    seed=args.seed, executor=executor, chunk=args.chunk, progress=not args.quiet, **sim)
    except StudyInterrupted as exc:
        return exc.result, exc
    return res, None


def _axes(args, grid, metrics):
    """The chart's columns ``(x, y)``, checked against the table's columns before any run."""
    x = args.x or next(iter(grid))
    y = args.y or next(iter(metrics), None)
    if (args.x or args.y) and not args.plot:
        raise ValueError("--x and --y choose the chart's columns, and no --plot was given -> fix: add --plot FILE.png")
    if args.plot and y is None:
        raise ValueError("--plot draws a metric against a parameter, and there is no --metric -> add --metric "
                         "NAME=EXPR or choose the column with --y")
    columns = list(grid) + list(metrics) + ["cpu_time"]
    for flag, name in (("--x", x), ("--y", y)):
        if args.plot and name not in columns:
            raise ValueError(f"{flag} {name}: the table has no column {name!r}; its numeric columns are "
                             f"{', '.join(columns)} -> fix: choose one of them (a --grid parameter or a --metric)")
    return x, y


def _report(res, stopped, args, executor, x, y):
    """Summary, ``--out``, ``--plot``; the exit status."""
    from ..analysis.parallel import executor_name

    _summary(res, executor_name(executor))
    if args.out:
        res.to_csv(args.out)
        print(f"wrote {args.out} ({len(res)} rows, {len(res.columns)} columns)")
    if args.plot and len(res):
        res.plot(x, y, args.plot)
        print(f"wrote {args.plot} ({y} against {x})")
    if stopped is not None:
        kept = (f"wrote {args.out} ({len(res)} rows)" if args.out else
                "nothing written (give --out FILE.csv to keep the finished rows)")
        print(f"mbcomp: {stopped}; {kept}", file=sys.stderr)
        return EXIT_SIGNAL[stopped.signal]
    if len(res) and res.stats["failed"] == len(res):
        print("mbcomp: every run failed (the messages above say why)", file=sys.stderr)
        return 1
    return 0


def add_parser(sub, common):
    """The ``study`` sub-command on the argparse ``sub``-parsers."""
    s = sub.add_parser("study", help="many runs over a parameter grid or a Monte Carlo sample, on this machine or "
                       "a Dask cluster: one table row per run")
    common(s)
    s.add_argument("--grid", action="append", required=True, metavar="NAME=VALUES",
                   help="lo:hi:n, v1,v2,..., U(lo,hi) or N(mu,sigma); component.param or a build() argument "
                   "(repeatable: a full factorial)")
    s.add_argument("--metric", action="append", metavar="NAME=EXPR",
                   help="a number per run, e.g. peak=max(abs(pin.f.y)), final=last(crank_joint.phi); functions: "
                   "max min mean std rms first last range abs sqrt at(col,t)")
    s.add_argument("--samples", type=int, help="Monte Carlo: number of runs drawn from the distributions")
    s.add_argument("--seed", type=int, help="Monte Carlo: seed of the sample (the same seed, the same runs)")
    s.add_argument("--executor", default=None, metavar="WHERE",
                   help="serial (default), processes (a process pool), dask (a local Dask cluster) or "
                   "tcp://host:port (a running Dask scheduler)")
    s.add_argument("--workers", type=int, help="processes of --executor processes (default: the cores, at most 4)")
    s.add_argument("--chunk", type=int, help="runs per task (default: about four tasks per worker)")
    s.add_argument("--t-end", dest="t_end", type=float, help="end time of every run (default: the model's SIMULATION)")
    s.add_argument("--rtol", type=float)
    s.add_argument("--atol", type=float)
    s.add_argument("--method")
    s.add_argument("--n-out", dest="n_out", type=int, help="output points per run (what the metrics see)")
    s.add_argument("--backend", choices=["numeric", "python", "c", "auto"])
    s.add_argument("--out", help="CSV file of the table")
    s.add_argument("--plot", help="PNG file: --y against --x")
    s.add_argument("--x", help="column on the chart's x axis (default: the first --grid parameter)")
    s.add_argument("--y", help="column on the chart's y axis (default: the first --metric)")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    s.set_defaults(func=cmd_study)
    return s
