"""``mbcomp stability MODEL.py``: eigenvalues and their classification.

Linearizes about the model's start state (or, with ``--steady "a=0, b=lo:hi"``, about every
steady state found) and prints the eigenvalues and their classification; ``--sweep
name=start:stop:count`` repeats that over a build() or component parameter and locates where
the classification changes (:mod:`mbcomp.analysis.stability`). With ``--steady`` and
``--sweep`` together the steady state is solved at each value, following the branch it
starts on. ``--executor processes|dask|tcp://host:port`` sends the grid's linearizations
(about the start states) to workers; the results equal the serial sweep's.

Every error is one line ``mbcomp: ...`` on stderr and exit status 2; "no steady state found"
is exit status 1.

Examples
--------
>>> from mbcomp.cli.main import make_parser
>>> args = make_parser().parse_args(["stability", "models/bicycle.py", "--steady", "hinge.w=0"])
>>> args.steady, args.func.__name__
('hinge.w=0', 'cmd_stability')
"""
from __future__ import annotations

import pathlib
import sys

import numpy as np

from ..errors import SimulationError
from .loader import call_build, check_output, model_module, split_params
from .messages import one_line
from .sweep import stability_sweep, sweep_on_executor

__all__ = ["cmd_stability", "add_parser"]



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
    """The stability analysis of the model file; errors as one line and exit status 2."""
    try:
        return _stability(args)
    except (ValueError, SimulationError, np.linalg.LinAlgError) as exc:  # ModelError is a ValueError
        print(f"mbcomp: {one_line(exc)}", file=sys.stderr)
        return 2


def _stability(args):
    from ..analysis import stability as st

    check_output(args.out, "--out")
    check_output(args.plot, "--plot")
    mod = model_module(args.model)
    build_kw, runtime = split_params(args.param, mod.build)
    title = pathlib.Path(args.model).name
    steady = None
    if args.steady is not None:
        try:
            steady = st.parse_steady(args.steady)
        except ValueError as exc:
            raise ValueError(f"--steady: {exc}") from None
    if args.sweep:
        if args.executor:
            return sweep_on_executor(args, mod, build_kw, runtime, steady, title)
        return stability_sweep(args, mod, build_kw, runtime, steady, title)
    if args.executor:
        raise ValueError("--executor spreads the values of a --sweep over workers, and there is no --sweep -> add "
                         "--sweep NAME=START:STOP:COUNT or drop --executor")
    system = st.system_for(call_build(mod, build_kw, args.model), runtime or None, args.backend)
    if steady is None:
        return _start_state(args, system, title)
    return _steady_states(args, system, steady, title)


def _start_state(args, system, title):
    """Linearize about the start state: report, JSON, plot."""
    from ..analysis import stability as st

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


def _steady_states(args, system, steady, title):
    """Find the steady states, linearize about each: report, JSON, plot."""
    from ..analysis import stability as st

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
            print(f"linearization failed: {one_line(exc)}")
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


def add_parser(sub, common):
    """The ``stability`` sub-command on the argparse ``sub``-parsers."""
    st = sub.add_parser("stability", help="linearize about the start state or steady states: eigenvalues, "
                        "classification, parameter sweeps with the stability changes located")
    common(st)
    st.add_argument("--steady", metavar="SPEC",
                    help="solve for steady states first: comma-separated name=value (fixed) and name=lo:hi "
                    "(searched) coordinates or speeds, e.g. 'hinge.w=0, hinge.phi=-3.2:3.2'")
    st.add_argument("--sweep", metavar="NAME=START:STOP:COUNT",
                    help="repeat over a build() parameter (no dot) or a component parameter (component.param) "
                    "and locate where the classification changes")
    st.add_argument("--executor", metavar="WHERE",
                    help="with --sweep: the grid's values as tasks on serial (default), processes (a process pool), "
                    "dask (a local Dask cluster) or tcp://host:port (a running Dask scheduler)")
    st.add_argument("--workers", type=int, help="processes of --executor processes (default: the cores, at most 4)")
    st.add_argument("--out", help="write the results to this JSON file")
    st.add_argument("--plot", help="PNG: eigenvalues against the swept parameter, else in the complex plane")
    st.add_argument("--backend", choices=["python", "numeric", "c", "auto"], default="python",
                    help="what evaluates the model: the generated Python program (default; 10-20x faster "
                    "than numeric for a linearization) or the numeric path")
    st.set_defaults(func=cmd_stability)
    return st
