"""Command line: ``mbcomp simulate MODEL.py``, ``mbcomp info MODEL.py`` and ``mbcomp bench MODEL.py``.

A model file defines ``build(**params) -> Model`` and may set ``SIMULATION = dict(t_end=...,
rtol=..., atol=..., method=..., stabilization=..., formulation=...)`` as defaults. ``-p name=value`` passes
``name`` to ``build`` when it has no dot, and sets a component parameter at run time when it
has one (``-p spring.c=200``: nothing is re-derived).

Examples
--------
>>> from mbcomp.cli import parse_value
>>> parse_value("1e-3"), parse_value("(0, 0, 1)"), parse_value("RK45")
(0.001, (0, 0, 1), 'RK45')
"""
from __future__ import annotations

import argparse
import ast
import importlib.util
import inspect
import pathlib
import os
import sys

import numpy as np

from .errors import ModelError

__all__ = ["main", "load_model_file", "parse_value"]


def parse_value(text):
    """A Python literal if ``text`` is one, else the string itself."""
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def load_model_file(path):
    """Import a model file and return the module (must define ``build``)."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise SystemExit(f"mbcomp: model file {path} does not exist")
    spec = importlib.util.spec_from_file_location(path.stem.replace("-", "_"), path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    if not callable(getattr(mod, "build", None)):
        raise SystemExit(f"mbcomp: {path} defines no build(**params) -> Model function")
    return mod


def _split_params(pairs, build):
    build_kw, runtime = {}, {}
    for pair in pairs or []:
        if "=" not in pair:
            raise SystemExit(f"mbcomp: -p expects name=value, got {pair!r}")
        k, v = pair.split("=", 1)
        (runtime if "." in k else build_kw)[k.strip()] = parse_value(v.strip())
    sig = inspect.signature(build)
    accepts_any = any(p.kind == p.VAR_KEYWORD for p in sig.parameters.values())
    unknown = [k for k in build_kw if k not in sig.parameters and not accepts_any]
    if unknown:
        raise SystemExit(f"mbcomp: build() takes no parameter {', '.join(unknown)}; it takes: "
                         f"{', '.join(sig.parameters) or 'none'} (use component.param=value for component parameters)")
    return build_kw, runtime


def _build(args):
    mod = load_model_file(args.model)
    build_kw, runtime = _split_params(args.param, mod.build)
    model = mod.build(**build_kw)
    return mod, model, runtime


def cmd_info(args):
    from .system import assemble

    _, model, runtime = _build(args)
    system = assemble(model, runtime)
    print(system.summary())
    return 0


def cmd_simulate(args):
    from .simulation import simulate

    mod, model, runtime = _build(args)
    opts = dict(getattr(mod, "SIMULATION", {}))
    for key in ("t_end", "rtol", "atol", "method", "stabilization", "formulation", "n_out", "index", "h", "backend"):
        val = getattr(args, key)
        if val is not None:
            opts[key] = val
    res = simulate(model, params=runtime, progress=not args.quiet, **opts)
    E = res["energy.total"]
    print(f"status: {res.status} ({res.message})")
    print(f"t = {res.time[0]:g} .. {res.time[-1]:g} s, {res.stats['steps']} steps, {res.stats['nfev']} f-evals, "
          f"{res.stats['cpu_time']:.2f} s")
    if len(E):
        print(f"energy drift max|E - E0| = {np.nanmax(np.abs(E - E[0])):.3e} J; "
              f"max position residual {np.nanmax(res['residual.position']):.3e}, "
              f"velocity residual {np.nanmax(res['residual.velocity']):.3e}")
    if args.out:
        res.to_csv(args.out)
        print(f"wrote {args.out} ({len(res.names) + 1} columns, {len(res.time)} rows)")
    if args.plot:
        res.plot(path=args.plot, title=pathlib.Path(args.model).name)
        print(f"wrote {args.plot}")
    return 0 if res.success else 1


def cmd_bench(args):
    from . import workprecision as wp

    mod = load_model_file(args.model)
    build_kw, runtime = _split_params(args.param, mod.build)
    combos = wp.default_combos()
    if args.combos:
        keys = [k.strip().lower() for k in args.combos.split(",")]
        exact = [c for c in combos if c.label.lower() in keys]  # a full label selects just that one
        combos = exact or [c for c in combos if any(k in c.label.lower() for k in keys)]
        if not combos:
            raise SystemExit(f"mbcomp: no combination matches --combos {args.combos!r}; labels: "
                             + "; ".join(c.label for c in wp.default_combos()))
    tols = [float(x) for x in args.tols.split(",")] if args.tols else None
    rows = wp.work_precision(mod, combos, tols=tols, build_kw=build_kw, params=runtime or None, t_end=args.t_end,
                             max_cpu=args.max_cpu)
    name = pathlib.Path(args.model).stem
    print("\n" + wp.summary(rows, args.target, title=name))
    out = args.out or f"{name}_work_precision.csv"
    wp.write_csv(rows, out)
    png = args.plot or f"{name}_work_precision.png"
    wp.plot(rows, png, title=name, target=args.target)
    print(f"wrote {out} and {png}")
    return 0


def make_parser():
    ap = argparse.ArgumentParser(prog="mbcomp", description="Modelica-style multibody modelling and simulation")
    sub = ap.add_subparsers(dest="command", required=True)

    def common(p):
        p.add_argument("model", help="model file defining build(**params) -> Model")
        p.add_argument("-p", "--param", action="append", metavar="NAME=VALUE",
                       help="build() argument, or component.param runtime value (repeatable)")

    s = sub.add_parser("simulate", help="simulate a model file")
    common(s)
    s.add_argument("--t-end", dest="t_end", type=float)
    s.add_argument("--rtol", type=float)
    s.add_argument("--atol", type=float)
    s.add_argument("--method", help="ODE forms: RK23, RK45, DOP853, Radau, BDF, LSODA; DAE forms: radau5 "
                   "(index 1-3), ida (index 1-2), genalpha (index 3, fixed step --h)")
    s.add_argument("--index", type=int, choices=[1, 2, 3],
                   help="with a DAE method: constraints at acceleration (1), velocity + GGL (2) or position level (3)")
    s.add_argument("--h", type=float, help="step size (s) of fixed-step methods (genalpha)")
    s.add_argument("--backend", choices=["numeric", "python", "c", "auto"],
                   help="numeric jets (default) or a generated program: python, c (system compiler, cached), auto")
    s.add_argument("--stabilization", choices=["baumgarte", "projection", "none"])
    s.add_argument("--formulation", choices=["lagrange", "dalembert"],
                   help="lagrange: multipliers at index 1 (default); dalembert: ODE in independent speeds")
    s.add_argument("--n-out", dest="n_out", type=int, help="number of output points")
    s.add_argument("--out", help="write results to this CSV file")
    s.add_argument("--plot", help="write a plot to this PNG file")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    s.set_defaults(func=cmd_simulate)
    b = sub.add_parser("bench", help="work-precision study: every formulation x solver over a tolerance sweep")
    common(b)
    b.add_argument("--t-end", dest="t_end", type=float, help="end time (default: the model's REFERENCE or SIMULATION)")
    b.add_argument("--target", type=float, default=1e-6, help="relative position error for the summary table")
    b.add_argument("--tols", help="comma-separated rtol values (default 1e-3 ... 1e-10)")
    b.add_argument("--combos", help="comma-separated substrings selecting combinations, e.g. 'radau5,DOP853'")
    b.add_argument("--max-cpu", dest="max_cpu", type=float, default=60.0,
                   help="stop a combination's sweep after a run slower than this (s)")
    b.add_argument("--out", help="CSV file (default MODEL_work_precision.csv)")
    b.add_argument("--plot", help="PNG file (default MODEL_work_precision.png)")
    b.set_defaults(func=cmd_bench)
    i = sub.add_parser("info", help="print the model summary (bodies, DOF, coordinates, constraints)")
    common(i)
    i.set_defaults(func=cmd_info)
    return ap


def main(argv=None):
    args = make_parser().parse_args(argv)
    try:
        return args.func(args)
    except ModelError as exc:
        print(f"mbcomp: {exc}", file=sys.stderr)
        return 2
    except ValueError as exc:
        print(f"mbcomp: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into e.g. `head`, which closed early
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
