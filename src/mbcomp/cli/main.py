"""Command line: ``mbcomp simulate MODEL.py``, ``mbcomp info MODEL.py``, ``mbcomp bench MODEL.py`` and
``mbcomp stability MODEL.py``.

A model file defines ``build(**params) -> Model`` and may set ``SIMULATION = dict(t_end=...,
rtol=..., atol=..., method=..., stabilization=..., formulation=...)`` as defaults. ``-p name=value`` passes
``name`` to ``build`` when it has no dot, and sets a component parameter at run time when it
has one (``-p spring.c=200``: nothing is re-derived).

``mbcomp stability MODEL.py`` linearizes about the model's start state (or, with
``--steady "a=0, b=lo:hi"``, about every steady state found) and prints the eigenvalues and
their classification; ``--sweep name=start:stop:count`` repeats that over a build() or
component parameter and locates where the classification changes (:mod:`mbcomp.stability`).

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

from ..errors import ModelError, SimulationError

__all__ = ["main", "load_model_file", "parse_value", "parse_sweep"]


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
    from ..assembly.system import assemble

    _, model, runtime = _build(args)
    system = assemble(model, runtime)
    print(system.summary())
    return 0


def cmd_simulate(args):
    from ..simulation.driver import simulate

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
    from ..analysis import workprecision as wp

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


# ------------------------------------------------------------------------------------------
# mbcomp stability
# ------------------------------------------------------------------------------------------
_SWEEP_HINT = "write --sweep name=start:stop:count with start < stop and an integer count >= 2, e.g. spin=1:5:9"


def parse_sweep(spec):
    """``"name=start:stop:count"`` -> ``(name, grid)`` with ``grid = linspace(start, stop, count)``.

    Examples
    --------
    >>> from mbcomp.cli import parse_sweep
    >>> parse_sweep("spin=1:5:5")
    ('spin', array([1., 2., 3., 4., 5.]))
    """
    text = str(spec).strip()
    name, sep, rng = text.partition("=")
    name, parts = name.strip(), rng.split(":")
    if not sep or not name or len(parts) != 3:
        raise ValueError(f"--sweep {text!r}: {_SWEEP_HINT}")
    try:
        start, stop, count = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise ValueError(f"--sweep {text!r}: start and stop must be numbers and count an integer; "
                         f"{_SWEEP_HINT}") from None
    if not (np.isfinite(start) and np.isfinite(stop) and start < stop and count >= 2):
        raise ValueError(f"--sweep {text!r}: {_SWEEP_HINT}")
    return name, np.linspace(start, stop, count)


def _one_line(exc):
    """An error as one line: a ModelError's header and every problem, joined by ``;``."""
    problems = getattr(exc, "problems", None)
    if isinstance(exc, ModelError) and problems:
        head = str(exc).splitlines()[0].rstrip(":")
        head = head.rsplit(" (", 1)[0] if head.endswith(")") else head
        return f"{head}: " + "; ".join(" ".join(str(p).split()) for p in problems)
    return " ".join(str(exc).split())


def _call_build(mod, kw, path):
    try:
        return mod.build(**kw)
    except TypeError as exc:  # e.g. a text value where build() needs a number
        args = ", ".join(f"{k}={v!r}" for k, v in kw.items())
        raise ValueError(f"build({args}) of {path} failed ({exc}) -> fix: give numbers to -p / --sweep") from None


def _complex(z):
    return f"{z.real:+.6g}" if z.imag == 0 else f"{z.real:+.6g}{z.imag:+.6g}j"


def _top(eigs):
    """The eigenvalues whose real part is (within the classification tolerance) the largest."""
    e = np.asarray(eigs, complex)
    e = e[np.isfinite(e)]
    if not e.size:
        return "-"
    tol = 1e-7 * (1.0 + np.abs(e).max())  # the classification's: parts below it print as 0
    sel = e[e.real >= e.real.max() - tol]
    sel = np.where(np.abs(sel.real) <= tol, 0.0, sel.real) + 1j * np.where(np.abs(sel.imag) <= tol, 0.0, sel.imag)
    return ", ".join(_complex(z) for z in sel[:4]) + (", ..." if sel.size > 4 else "")


def _eigen_plot(groups, path, title):
    """Eigenvalues in the complex plane, one marker per group ``(label, eigenvalues)``."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    marks = "oxs^vD+*"
    for k, (label, eigs) in enumerate(groups):
        e = np.asarray(eigs, complex)
        ax.plot(e.real, e.imag, marks[k % len(marks)], ms=7, mfc="none", label=label)
    ax.axhline(0, color="0.5", lw=0.5)
    ax.axvline(0, color="0.5", lw=0.5)
    ax.set_xlabel("Re (1/s)")
    ax.set_ylabel("Im (1/s)")
    ax.set_title(title)
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _steady_record(s, system, lin):
    return dict(values=s.values, residual=s.residual, how=s.how, t=s.t,
                q=dict(zip(system.q_names, map(float, s.q))), u=dict(zip(system.u_names, map(float, s.u))),
                linearization=None if lin is None else lin.to_dict())


def cmd_stability(args):
    try:
        return _stability(args)
    except SystemExit as exc:  # the messages of load_model_file and _split_params
        if isinstance(exc.code, str):
            print(" ".join(exc.code.split()), file=sys.stderr)
            return 2
        raise
    except (ValueError, SimulationError, np.linalg.LinAlgError) as exc:  # ModelError is a ValueError
        print(f"mbcomp: {_one_line(exc)}", file=sys.stderr)
        return 2


def _stability(args):
    from ..analysis import stability as st
    from ..assembly.system import assemble

    mod = load_model_file(args.model)
    build_kw, runtime = _split_params(args.param, mod.build)
    title = pathlib.Path(args.model).name
    steady = None
    if args.steady is not None:
        try:
            steady = st.parse_steady(args.steady)
        except ValueError as exc:
            raise ValueError(f"--steady: {exc}") from None
    if args.sweep:
        return _stability_sweep(args, mod, build_kw, runtime, steady, title)
    system = st._system(_call_build(mod, build_kw, args.model), runtime or None, args.backend)
    if steady is None:
        lin = st.linearize(system)
        print(f"{title}: about the start state")
        print(lin.report())
        if args.out:
            st.to_json(lin, args.out)
            print(f"wrote {args.out}")
        if args.plot:
            _eigen_plot([("start state", lin.eigenvalues)], args.plot, f"{title}: {lin.classification}")
            print(f"wrote {args.plot}")
        return 0
    fixed, unknown = steady
    sols = st.steady_states(system, unknown, fixed)
    fixed_text = ", ".join(f"{k} = {v!r}" for k, v in fixed.items()) or "nothing"
    if not sols:
        ranges = ", ".join(f"{k} in [{a:g}, {b:g}]" for k, (a, b) in unknown.items())
        print(f"{title}: no steady state found with {ranges} (fixed: {fixed_text}) -> widen the ranges, or fix "
              "other values")
        return 1
    print(f"{title}: {len(sols)} steady state{'s' if len(sols) > 1 else ''} (fixed: {fixed_text})")
    print(f"how: {sols[0].how}")
    records, groups = [], []
    for k, s in enumerate(sols, 1):
        vals = ", ".join(f"{n} = {v!r}" for n, v in s.values.items())
        print(f"\nsteady state {k}: {vals}  (residual max|du/dt| = {s.residual:.3g})")
        try:
            lin = st.linearize(system, state=s)
        except SimulationError as exc:
            lin = None
            print(f"linearization failed: {_one_line(exc)}")
        else:
            print(lin.report())
            groups.append((", ".join(f"{n} = {v:.6g}" for n, v in s.values.items()), lin.eigenvalues))
        records.append(_steady_record(s, system, lin))
    if args.out:
        st.to_json(dict(model=title, fixed=fixed, unknown=unknown, steady_states=records), args.out)
        print(f"\nwrote {args.out}")
    if args.plot:
        _eigen_plot(groups, args.plot, f"{title}: eigenvalues of the steady states")
        print(f"wrote {args.plot}")
    return 0


def _stability_sweep(args, mod, build_kw, runtime, steady, title):
    from ..analysis import stability as st
    from ..assembly.initialization import initialize
    from ..assembly.system import MultibodySystem, assemble

    name, grid = parse_sweep(args.sweep)
    current = {}
    if "." in name:  # a component parameter: one model, the value set at run time
        base = st._system(_call_build(mod, build_kw, args.model), runtime or None, args.backend)
        try:
            base.with_params({name: float(grid[0])})
        except ModelError as exc:
            raise ValueError(f"--sweep {name}: {_one_line(exc)}") from None

        def make(v):
            current["v"] = v
            return base.with_params({name: v})
        params = None
    else:  # a build() parameter: the model (and its start state) built at each value
        sig = inspect.signature(mod.build)
        if name not in sig.parameters and not any(p.kind == p.VAR_KEYWORD for p in sig.parameters.values()):
            raise ValueError(f"--sweep {name}: build() of {title} takes no parameter {name!r} -> fix: sweep one of "
                             f"{', '.join(sig.parameters) or 'none'}, or a component parameter as component.param")

        def make(v):
            current["v"] = v
            return _call_build(mod, {**build_kw, name: v}, args.model)
        params = runtime or None

    solved = {}  # parameter value -> the steady state's unknowns followed there
    if steady is None:
        def analyze(mdl):
            return st.linearize(mdl, params=params, backend=args.backend)
    else:
        fixed, unknown = steady
        names = list(unknown)
        width = np.array([unknown[n][1] - unknown[n][0] for n in names])

        def start_values(mdl):
            system = mdl if isinstance(mdl, MultibodySystem) else assemble(mdl, params)
            init = initialize(system, 0.0)
            out = []
            for n in names:
                if n in system.q_names:
                    out.append(init.q[system.q_names.index(n)])
                elif n in system.u_names:
                    out.append(init.u[system.u_names.index(n)])
                else:
                    out.append(0.5 * sum(unknown[n]))  # steady_states names the bad name
            return np.array(out, float)

        def analyze(mdl):
            v = current["v"]
            system = st._system(mdl, params, args.backend)  # traced once for both steps
            sols = st.steady_states(system, unknown, fixed)
            if not sols:
                raise SimulationError(f"no steady state with {args.steady} at {name} = {v!r}")
            if solved:  # continuation: the branch followed at the nearest value solved so far
                ref = solved[min(solved, key=lambda x: abs(x - v))]
            else:  # first value: the branch nearest the model's start values
                ref = start_values(mdl)
            pick = min(sols, key=lambda s: np.abs((np.array([s.values[n] for n in names]) - ref) / width).max())
            solved[v] = np.array([pick.values[n] for n in names])
            return st.linearize(system, state=pick)

    if steady is not None:  # check the names of --steady once, before the sweep records failures as "failed"
        st.steady_states(make(float(grid[0])), unknown, fixed, params=params, starts=2)
    sw = st.sweep(make, name, grid, analyze=analyze)

    print(f"{title}: stability against {name} = {grid[0]:g} .. {grid[-1]:g} ({len(grid)} values)"
          + (f", steady state {args.steady} solved at each value" if steady else ""))
    head = f"{name:>12}  {'classification':<22}"
    if steady is not None:
        head += "  " + "  ".join(f"{n:>14}" for n in names)
    print(head + "  eigenvalues with the largest real part (1/s)")
    for k, v in enumerate(sw.values):
        row = f"{v:>12.6g}  {sw.classifications[k]:<22}"
        if steady is not None:
            z = solved.get(float(v))
            row += "  " + "  ".join(f"{x:>14.8g}" if z is not None else f"{'-':>14}" for x in
                                    (z if z is not None else names))
        print(row + "  " + (_top(sw.eigenvalues[k]) if sw.classifications[k] != "failed" else "-"))
    print()
    if sw.changes:
        for c in sw.changes:
            print(f"stability changes at {name} = {c['value']!r} ({c['from']} -> {c['to']}, {c['kind']}, "
                  f"{c['method']})")
    else:
        print(f"no stability change for {name} in [{grid[0]:g}, {grid[-1]:g}]")
    segs = sw.ranges()
    for lo, hi, cls in segs:
        print(f"  {name} in [{lo!r}, {hi!r}]: {cls}")
    stable = [(lo, hi) for lo, hi, cls in segs if cls == "asymptotically stable"]
    marginal = [(lo, hi) for lo, hi, cls in segs if cls == "marginally stable"]
    print("stable ranges (asymptotically stable): "
          + (", ".join(f"[{lo!r}, {hi!r}]" for lo, hi in stable) or "none"))
    if marginal:
        print("marginally stable ranges: " + ", ".join(f"[{lo!r}, {hi!r}]" for lo, hi in marginal))
    if args.out:
        data = sw.to_dict()
        data.update(model=title, ranges=[dict(lo=lo, hi=hi, classification=c) for lo, hi, c in segs],
                    stable_ranges=stable, marginally_stable_ranges=marginal)
        if steady is not None:
            data["steady"] = [None if float(v) not in solved else dict(zip(names, map(float, solved[float(v)])))
                              for v in sw.values]
        st.to_json(data, args.out)
        print(f"wrote {args.out}")
    if args.plot:
        sw.plot(args.plot, title=f"{title}: eigenvalues against {name}")
        print(f"wrote {args.plot}")
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
    st = sub.add_parser("stability", help="linearize about the start state or steady states: eigenvalues, "
                        "classification, parameter sweeps with the stability changes located")
    common(st)
    st.add_argument("--steady", metavar="SPEC",
                    help="solve for steady states first: comma-separated name=value (fixed) and name=lo:hi "
                    "(searched) coordinates or speeds, e.g. 'hinge.w=0, hinge.phi=-3.2:3.2'")
    st.add_argument("--sweep", metavar="NAME=START:STOP:COUNT",
                    help="repeat over a build() parameter (no dot) or a component parameter (component.param) "
                    "and locate where the classification changes")
    st.add_argument("--out", help="write the results to this JSON file")
    st.add_argument("--plot", help="PNG: eigenvalues against the swept parameter, else in the complex plane")
    st.add_argument("--backend", choices=["python", "numeric", "c", "auto"], default="python",
                    help="what evaluates the model: the generated Python program (default; 10-20x faster "
                    "than numeric for a linearization) or the numeric path")
    st.set_defaults(func=cmd_stability)
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
