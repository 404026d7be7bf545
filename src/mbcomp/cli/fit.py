"""``mbcomp fit MODEL.py --data meas.csv --param rod.m ...``: fit parameters to measurements.

Runs :func:`mbcomp.fit` (least squares with the exact trajectory sensitivities as the Jacobian)
and prints the fitted values with their standard errors; ``--out FILE.json`` writes them
(:meth:`mbcomp.analysis.fit.FitResult.to_json`).

* ``--data FILE.csv``: a header row of column names (``name [unit]`` headers, as
  ``mbcomp simulate --out ... --csv-units`` writes them, are read as ``name``), one row per
  time; the time column is ``time`` (``--time-column`` names another).
* ``--param NAME`` (repeatable): a parameter to fit, ``component.param`` or an array entry
  (``"rod.I[2, 2]"``). ``--param NAME=VALUE`` is what it is in every command (a build()
  argument, or a component value at run time); given for a fitted parameter, it is where the
  fit starts (else at the model's value).
* ``--column NAME`` (repeatable): the data columns to fit (default: all but the time).
* ``--bounds NAME=LO:HI`` (repeatable; either side may be empty: unbounded).
* ``--weight COLUMN=W``: the weight of a column's residuals (``1/sigma``, default 1).

Exit status 0 when the fit converged, 1 when it did not (the table is printed all the same),
2 bad input (a file, a column, a parameter; the message names the fix).

Examples
--------
>>> from mbcomp.cli.fit import parse_bounds
>>> parse_bounds(["rod.m=0.5:5", "damper.d=0:", "rod.I[2, 2]=:0.1"])
{'rod.m': (0.5, 5.0), 'damper.d': (0.0, None), 'rod.I[2, 2]': (None, 0.1)}
"""
from __future__ import annotations

import argparse
import csv
import re

import numpy as np

from .loader import check_output, load

__all__ = ["cmd_fit", "add_parser", "parse_bounds", "read_csv"]

_UNIT = re.compile(r"\s*\[[^\[\]]*\]\s*$")


def parse_bounds(specs):
    """``["NAME=LO:HI", ...]`` -> ``{name: (lo, hi)}`` (``None`` where a side is empty)."""
    out = {}
    for spec in specs or []:
        name, eq, rng = (x.strip() for x in spec.rpartition("="))
        if not eq or not name or rng.count(":") != 1:
            raise ValueError(f"--bounds {spec!r}: write NAME=LO:HI (a side may be empty), e.g. --bounds rod.m=0.5:5")
        sides = []
        for text in rng.split(":"):
            try:
                sides.append(float(text) if text.strip() else None)
            except ValueError:
                raise ValueError(f"--bounds {spec!r}: {text.strip()!r} is not a number") from None
        if name in out:
            raise ValueError(f"--bounds {name} is given twice -> give it once")
        out[name] = tuple(sides)
    return out


def read_csv(path):
    """``{column: values}`` of a CSV file with a header row (``name [unit]`` read as ``name``).

    Raises
    ------
    ValueError
        The file cannot be read, has no rows, a row of another length, or a cell that is
        not a number (naming its row and column); an empty cell is NaN (which :func:`mbcomp.fit`
        refuses, naming it).
    """
    try:
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
    except OSError as exc:
        raise ValueError(f"--data {path}: cannot read it ({exc.strerror}) -> give the measurements' CSV file") from None
    rows = [r for r in rows if any(c.strip() for c in r)]
    if len(rows) < 2:
        raise ValueError(f"--data {path}: needs a header row of column names and at least one row of numbers")
    names = [_UNIT.sub("", c).strip() for c in rows[0]]
    values = np.empty((len(rows) - 1, len(names)))
    for i, row in enumerate(rows[1:], start=2):
        if len(row) != len(names):
            raise ValueError(f"--data {path}: line {i} has {len(row)} cells for {len(names)} columns")
        for j, cell in enumerate(row):
            try:
                values[i - 2, j] = float(cell) if cell.strip() else np.nan
            except ValueError:
                raise ValueError(f"--data {path}: line {i}, column {names[j]!r}: {cell!r} is not a number") from None
    return {n: values[:, j] for j, n in enumerate(names)}


def _weights(specs):
    out = {}
    for spec in specs or []:
        name, eq, value = (x.strip() for x in spec.rpartition("="))
        try:
            out[name] = float(value)
        except ValueError:
            raise ValueError(f"--weight {spec!r}: write COLUMN=W with W a number (1/sigma), e.g. "
                             "--weight crank_angle=1000") from None
        if not eq or not name:
            raise ValueError(f"--weight {spec!r}: write COLUMN=W, e.g. --weight crank_angle=1000")
    return out


def cmd_fit(args):
    """Fit the model file's parameters to ``--data``; print the table, write ``--out``."""
    from ..analysis.fit import fit

    check_output(args.out, "--out")
    fitted = [p.strip() for p in args.param or [] if "=" not in p]
    if not fitted:
        raise ValueError("mbcomp fit: no parameter to fit -> name them with --param, e.g. --param rod.m "
                         "(--param NAME=VALUE sets a value, as in every command)")
    plain = [p for p in fitted if "." not in p]
    if plain:
        raise ValueError(f"--param {plain[0]}: a build() argument cannot be fitted (build() runs once) -> fit the "
                         "component parameter it sets, e.g. --param rod.m")
    bounds, weights = parse_bounds(args.bounds), _weights(args.weight) or None  # cheap checks first
    data = read_csv(args.data)
    given = argparse.Namespace(**{**vars(args), "param": [p for p in args.param if "=" in p]})
    mod, model, runtime = load(given)
    starts = {k: v for k, v in runtime.items() if k in fitted}
    fixed = {k: v for k, v in runtime.items() if k not in fitted}
    sim = dict(getattr(mod, "SIMULATION", {}))
    options = {k: sim[k] for k in ("rtol", "atol", "method") if k in sim}
    options.update({k: getattr(args, k) for k in ("rtol", "atol", "method", "backend", "n_out")
                    if getattr(args, k) is not None})
    params = {p: starts.get(p) for p in fitted}  # None: start at the model's value
    res = fit(model, data, params, columns=args.column, bounds=bounds, weights=weights, time=args.time_column,
              values=fixed, t_start=args.t_start, **options)
    print(f"{'converged' if res.success else 'NOT converged'}: {res.message}")
    rms = ", ".join(f"{c} {np.sqrt(np.mean(r ** 2)):.3g}" for c, r in res.residual.items())
    print(f"{len(next(iter(res.residual.values())))} times, {res.runs} runs; cost {res.cost:.6g}; rms residual {rms}")
    print(res.table())
    if args.out:
        res.to_json(args.out)
        print(f"wrote {args.out}")
    return 0 if res.success else 1


def add_parser(sub, common):
    """The ``fit`` sub-command on the argparse ``sub``-parsers (``common``'s model file and ``-p``
    with ``-p NAME`` alone naming a parameter to fit)."""
    s = sub.add_parser("fit", help="fit parameters to measured time series (least squares, exact sensitivities)")
    s.add_argument("model", help="model file defining build(**params) -> Model")
    s.add_argument("-p", "--param", action="append", metavar="NAME[=VALUE]",  # common()'s -p, plus NAME alone
                   help="NAME: a parameter to fit (component.param or an entry, 'rod.I[2, 2]'); NAME=VALUE: a "
                   "build() argument or component value, for a fitted parameter its start (repeatable)")
    s.add_argument("--data", required=True, metavar="FILE.csv", help="measurements: a time column and result columns")
    s.add_argument("--column", action="append", metavar="NAME", help="a data column to fit (default: all but time)")
    s.add_argument("--bounds", action="append", metavar="NAME=LO:HI", help="bounds of a fitted parameter")
    s.add_argument("--weight", action="append", metavar="COLUMN=W", help="weight (1/sigma) of a column's residuals")
    s.add_argument("--time-column", dest="time_column", default="time", help="the time column (default: time)")
    s.add_argument("--t-start", dest="t_start", type=float, default=0.0, help="start of the runs, s (default 0)")
    s.add_argument("--rtol", type=float)
    s.add_argument("--atol", type=float)
    s.add_argument("--method")
    s.add_argument("--backend", choices=["numeric", "python", "c", "auto"])
    s.add_argument("--n-out", dest="n_out", type=int, help="output points of a run for irregular times")
    s.add_argument("--out", help="JSON file of the fitted values, standard errors and covariance")
    s.set_defaults(func=cmd_fit)
    return s
