"""``mbcomp simulate MODEL.py``: integrate, report, write the CSV and the plot.

The model file may set ``SIMULATION = dict(t_end=..., rtol=..., atol=..., method=...,
stabilization=..., formulation=...)`` as defaults, and ``SIMULATE_PARAMS = dict(...)`` as
build() values this command uses where no ``-p`` gives them (the bicycle's push, so that
``mbcomp simulate models/bicycle.py`` shows it weave; ``build()`` and the other commands
keep build()'s own defaults); options given on the command line win.

``--out FILE`` writes the results in the kind its suffix names: ``.csv``, ``.mat`` (a Modelica
result file: OMEdit, Dymola, DyMat; :meth:`mbcomp.result.Result.to_mat`) or ``.nc`` (netCDF
through xarray; :meth:`mbcomp.result.Result.to_xarray`); another suffix is bad input.

Results are never lost: ``--out`` (its suffix too) and ``--plot`` are checked before the model is even
loaded (:func:`~mbcomp.cli.loader.check_output`), so a mistyped directory fails at once, not
after an hour of integration; a run that stops early (failed, or interrupted by Ctrl-C /
SIGTERM: ``status == "interrupted"``; or a budget, ``--max-time`` / ``--max-steps``, that ran
out: ``status == "budget"``) still writes what it computed. Exit status: 0 success, 1 the run
failed, 3 a budget ran out, 130 interrupted by Ctrl-C, 143 by SIGTERM (the partial results
written in each case, and an interruption says so in one line on stderr), 2 bad input.

``--animate FILE`` writes the run as a self-contained HTML 3-D player (``.html``) or a film
(``.gif``, ``.mp4``); ``--trails``, ``--color-by COMP=COLUMN`` and ``--hide`` shape it
(:meth:`mbcomp.result.Result.animate`). Its suffix is checked before the run.

``--plot-vars PATTERN...`` chooses the columns ``--plot`` draws (names or shell-style globs,
``"crank_joint.*" "*.tau.z"``; :meth:`mbcomp.result.Result.plot`); by default it draws the
coordinates, the energy and the constraint residuals. The summary prints the energy drift of a
conservative system, and the energy balance error (``energy.balance``: the total energy less
the work done on the system plus the energy dissipated) of a driven or damped one.

Examples
--------
>>> from mbcomp.cli.main import make_parser
>>> args = make_parser().parse_args(["simulate", "model.py", "--t-end", "0.5", "--method", "radau5", "--index", "3"])
>>> {k: getattr(args, k) for k in OPTIONS if getattr(args, k) is not None}
{'t_end': 0.5, 'method': 'radau5', 'index': 3}
"""
from __future__ import annotations

import pathlib
import sys

import numpy as np

from ..errors import SimulationInterrupted
from .loader import check_output, load
from .messages import EXIT_SIGNAL

__all__ = ["cmd_simulate", "add_parser", "OPTIONS", "EXIT_INTERRUPTED", "EXIT_BUDGET", "OUT_KINDS", "out_kind",
           "write_out"]

#: command-line options passed on to :func:`mbcomp.simulate` (overriding the file's SIMULATION)
OPTIONS = ("t_end", "rtol", "atol", "method", "stabilization", "formulation", "n_out", "index", "h", "backend",
           "singular", "max_wall_time", "max_steps", "error_estimate")
#: exit status of a run interrupted by Ctrl-C (128 + SIGINT, the shell's convention; SIGTERM: 143)
EXIT_INTERRUPTED = EXIT_SIGNAL["SIGINT"]
#: exit status of a run whose wall-time or step budget ran out (the partial results written)
EXIT_BUDGET = 3
#: exit status of a bad --plot-vars pattern (bad input; the CSV is written first)
EXIT_USAGE = 2


def cmd_simulate(args):
    """Simulate the model file; print status, statistics and drift; write ``--out``/``--plot``."""
    from ..codegen.compiler import prepare_runtime

    prepare_runtime()  # a machine's first run: the runtime compiles on threads while the rest imports
    from ..simulation.driver import simulate

    check_output(args.out, "--out")
    out_kind(args.out)
    check_output(args.plot, "--plot")
    check_output(args.animate, "--animate")
    look = _look_options(args)
    if args.plot_vars and not args.plot:
        raise ValueError("--plot-vars chooses the columns --plot draws, and no --plot was given -> fix: add "
                         "--plot FILE.png")
    mod, model, runtime = load(args, defaults="SIMULATE_PARAMS")
    opts = dict(getattr(mod, "SIMULATION", {}))
    opts.update({key: getattr(args, key) for key in OPTIONS if getattr(args, key) is not None})
    if args.sensitivity:
        opts["sensitivities"] = list(args.sensitivity)
    stopped = None
    try:
        res = simulate(model, params=runtime, progress=not args.quiet, **opts)
    except SimulationInterrupted as exc:  # Ctrl-C or SIGTERM: the results up to the last accepted step
        res, stopped = exc.result, exc.signal
    _report(res)
    if args.sensitivity:
        _sensitivity_columns(res)
    if args.out:
        write_out(res, args.out, csv_units=args.csv_units)
    if args.plot:
        try:
            res.plot(args.plot_vars, path=args.plot, title=pathlib.Path(args.model).name)
        except ValueError as exc:  # a pattern matching nothing: the run's results are kept all the same
            print(f"mbcomp: --plot-vars: {exc}" + (f" ({args.out} is written)" if args.out else ""), file=sys.stderr)
            return EXIT_USAGE
        print(f"wrote {args.plot}")
    if args.animate:
        try:
            res.animate(args.animate, title=pathlib.Path(args.model).name, **look)
        except (ValueError, RuntimeError) as exc:  # a trail or column that does not exist, no film writer
            print(f"mbcomp: --animate: {exc}" + (f" ({args.out} is written)" if args.out else ""), file=sys.stderr)
            return EXIT_USAGE
        print(f"wrote {args.animate}")
    return _stopped_early(res, args, stopped)


#: what ``--out`` writes, by the file's suffix
OUT_KINDS = {".csv": "CSV", ".mat": "Modelica result file", ".nc": "netCDF"}


def out_kind(path):
    """The kind of file ``--out`` writes to ``path``, by its suffix (checked before the run): ``".csv"``,
    ``".mat"`` (a Modelica result file: :meth:`mbcomp.result.Result.to_mat`) or ``".nc"`` (netCDF through
    xarray, which must be installed: checked here too).

    Examples
    --------
    >>> out_kind("run.MAT"), out_kind(None)
    ('.mat', None)
    >>> try:
    ...     out_kind("run.txt")
    ... except ValueError as exc:
    ...     print(exc)
    --out run.txt: unknown suffix '.txt' -> fix: name the file .csv, .mat or .nc (CSV, Modelica result file, netCDF)
    """
    if path is None:
        return None
    suffix = pathlib.Path(path).suffix.lower()
    if suffix not in OUT_KINDS:
        *first, last = OUT_KINDS
        raise ValueError(f"--out {path}: unknown suffix {suffix or '(none)'!r} -> fix: name the file "
                         f"{', '.join(first)} or {last} ({', '.join(OUT_KINDS.values())})")
    if suffix == ".nc":
        from ..simulation.result_tables import need

        try:
            need("xarray")
        except ImportError as exc:
            raise ValueError(f"--out {path}: {exc}") from None
    return suffix


def write_out(res, path, csv_units=False):
    """Write the run to ``path`` in the kind its suffix names (:func:`out_kind`) and say so."""
    kind = out_kind(path)
    if kind == ".mat":
        res.to_mat(path)
    elif kind == ".nc":
        from ..simulation.result_tables import write_netcdf

        write_netcdf(res.to_xarray(), path)
    else:
        res.to_csv(path, units=csv_units)
    print(f"wrote {path} ({OUT_KINDS[kind]}: {len(res.names) + 1} columns, {len(res.time)} rows)")


def _sensitivity_columns(res):
    """Add ``d(<coordinate or speed>)/d(<param>)`` columns for every requested parameter (what
    ``--out`` then writes) and say so; a note where the sensitivities ended early."""
    table = res.sensitivities
    if table is None:
        return
    for param in table.params:
        for name in table.state_names:
            res.set_column(f"d({name})/d({param})", res.sensitivity(name, param))
    print(f"sensitivities with respect to {', '.join(table.params)}: {len(table.params) * len(table.state_names)} "
          "columns d(<coordinate or speed>)/d(<parameter>)" + (f" (they end at t = {table.stopped[0]:.6g} s: "
                                                               f"{table.stopped[1]})" if table.stopped else ""))


def _look_options(args):
    """``--trails``, ``--color-by COMP=COLUMN``, ``--hide`` as :meth:`Result.animate`'s keywords,
    checked before the run (an animation file of a known kind; ``=`` in every colouring)."""
    if not args.animate:
        if args.trails or args.color_by or args.hide:
            raise ValueError("--trails, --color-by and --hide shape the animation, and no --animate was given -> "
                             "fix: add --animate FILE.html")
        return {}
    from ..visual.animation import suffix_kind

    if suffix_kind(args.animate) == "picture":
        raise ValueError(f"--animate {args.animate}: a picture is one frame -> animate to .html, .gif or .mp4")
    color_by = {}
    for item in args.color_by or []:
        comp, eq, column = item.partition("=")
        if not eq or not comp or not column:
            raise ValueError(f"--color-by {item!r} must be COMPONENT=COLUMN, e.g. rod=pin.f")
        color_by[comp] = column
    return {"trails": args.trails or (), "color_by": color_by or None, "hide": args.hide or ()}


def _stopped_early(res, args, stopped=None):
    """The exit status; for an interrupted run (``stopped``: the signal) or a spent budget,
    says where the results are (an interruption also as one line on stderr: 130 after Ctrl-C,
    143 after SIGTERM)."""
    if res.status not in ("interrupted", "budget"):
        return 0 if res.success else 1
    end = f"t = {res.time[-1]:g} s" if len(res.time) else "the start"
    kept = (f"{args.out} holds the partial results up to then" if args.out else
            "nothing written (give --out FILE.csv to keep the partial results)")
    if res.status == "budget":
        print(f"budget spent at {end}: {kept}")
        return EXIT_BUDGET
    signal = stopped or ("SIGTERM" if "SIGTERM" in res.message else "SIGINT")
    print(f"interrupted at {end}: {kept}")
    written = [f"{args.out} ({len(res.time)} rows)"] if args.out else []
    written += [path for path in (args.plot, args.animate) if path]
    print(f"mbcomp: interrupted by {signal} at {end}; " + (f"wrote {', '.join(written)} up to then" if written else
                                                          "nothing written (give --out FILE.csv)"), file=sys.stderr)
    return EXIT_SIGNAL[signal]


def _report(res):
    """Status, time span, work, and the drift of energy and constraints."""
    print(f"status: {res.status} ({res.message})")
    if not len(res.time):
        return
    print(f"t = {res.time[0]:g} .. {res.time[-1]:g} s, {res.stats['steps']} steps, {res.stats['nfev']} f-evals, "
          f"{res.stats['cpu_time']:.2f} s")
    for p in res.stats.get("singular_passages", ()):
        print(f"passed a singular position at t = {p['t']:.6g} s (rank drop {p['rank_drop']}, relative sigma "
              f"{p['sigma']:.2g}; joints {', '.join(p['joints'])})")
    if res.events:  # impacts, stops engaging and releasing (mbcomp.hybrid.events)
        first = ", ".join(f"{e.kind} {e.component}.{e.name} at {e.time:.9g} s" for e in res.events[:5])
        print(f"{len(res.events)} events: {first}" + (", ..." if len(res.events) > 5 else ""))
    for c in res.stats.get("row_changes", ()):
        print(f"constraint rows chosen again at t = {c['t']:.6g} s (the kept rows' relative sigma_min "
              f"{c['sigma_before']:.2g} -> {c['sigma_after']:.2g}): dropped {', '.join(c['dropped'])} "
              f"instead of {', '.join(c['was'])}")
    if "global_error" in res.stats:  # simulate(error_estimate=True): mbcomp.simulation.error_estimate
        col = res.stats["global_error_column"]
        unit = f" {res.units[col]}" if col in res.units else ""
        print(f"estimated global error {res.stats['global_error']:.3e}{unit} (in {col}; against a run at rtol="
              f"{res.stats['error_estimate_rtol']:g})" + (f"; {res.stats['error_estimate_note']}"
                                                          if "error_estimate_note" in res.stats else ""))
    E = res["energy.total"]
    if len(E):
        print(f"{_energy_line(res)}; max position residual {np.nanmax(res['residual.position']):.3e}, "
              f"velocity residual {np.nanmax(res['residual.velocity']):.3e}")


def _energy_line(res):
    """The energy drift max|E - E0| of a conservative run; for a run with an ``energy.balance``
    column (driven or damped), its largest magnitude relative to the energy the motion exchanges."""
    if "energy.balance" not in res:
        E = res["energy.total"] + (res["energy.impacts"] if "energy.impacts" in res else 0.0)
        lost = " (E counts the impacts' losses)" if "energy.impacts" in res else ""
        return f"energy drift max|E - E0| = {np.nanmax(np.abs(E - E[0])):.3e} J{lost}"
    err = float(np.nanmax(np.abs(res["energy.balance"])))
    T, V = res["energy.kinetic"], res["energy.potential"]
    scale = float(np.nanmax([np.nanmax(T) + np.nanmax(V) - np.nanmin(V)]
                            + [np.nanmax(np.abs(res[n])) for n in ("energy.work", "energy.dissipated") if n in res]))
    rel = f" ({err / scale:.1e} of the {scale:.3g} J exchanged)" if scale > 0 else ""
    return f"energy balance error max|E - E0 - W + D| = {err:.3e} J{rel}"


def add_parser(sub, common):
    """The ``simulate`` sub-command on the argparse ``sub``-parsers."""
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
    s.add_argument("--singular", choices=["stop", "pass"],
                   help="at a singular position (the constraint Jacobian losing rank): stop there (default) or "
                        "pass through it and report each passage")
    s.add_argument("--n-out", dest="n_out", type=int, help="number of output points")
    s.add_argument("--out", help="write results to this file, the kind by its suffix: .csv, .mat (a Modelica "
                   "result file that OMEdit, Dymola and DyMat read) or .nc (netCDF, needs xarray); also the partial "
                   "results of a run that stops early")
    s.add_argument("--csv-units", action="store_true",
                   help="write each CSV column's unit in its header: 'crank.phi [rad]'")
    s.add_argument("--plot", help="write a plot to this PNG file")
    s.add_argument("--plot-vars", dest="plot_vars", nargs="+", metavar="PATTERN",
                   help="columns --plot draws: names or shell-style globs, e.g. 'crank_joint.*' '*.tau.z' (default: "
                        "coordinates, energy, constraint residuals)")
    s.add_argument("--animate", metavar="FILE",
                   help="write an animation: .html (a 3-D player, opens offline), .gif or .mp4 (matplotlib)")
    s.add_argument("--trails", nargs="+", metavar="POINT",
                   help="points whose path the animation draws: port paths (rod_tip.frame_b) or components")
    s.add_argument("--color-by", dest="color_by", nargs="+", metavar="COMP=COLUMN",
                   help="colour a component by a result column, e.g. rod=pin.f (a vector's magnitude)")
    s.add_argument("--hide", nargs="+", metavar="PATTERN", help="components the animation does not draw (globs)")
    s.add_argument("--max-time", dest="max_wall_time", type=float, metavar="SECONDS",
                   help="wall-time budget: stop after this many seconds, keep and write the results so far (exit 3)")
    s.add_argument("--max-steps", dest="max_steps", type=int, metavar="N",
                   help="step budget: stop after N integrator steps, keep and write the results so far (exit 3)")
    s.add_argument("--error-estimate", dest="error_estimate", action="store_true", default=None,
                   help="also run at 100x tighter tolerances on the same outputs and print the difference: the "
                        "global error (phase error included, which no energy alarm sees)")
    s.add_argument("--sensitivity", action="append", metavar="PARAM",
                   help="differentiate the motion with respect to PARAM (component.param, component.param[i] or a "
                        "start value such as crank_joint.phi0; repeatable): --out gets d(<coordinate or speed>)/"
                        "d(PARAM) columns (mbcomp.simulate(..., sensitivities=[...]))")
    s.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    s.set_defaults(func=cmd_simulate)
    return s
