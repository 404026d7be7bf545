"""``mbcomp export MODEL.py -o crank.fmu``: the model as an FMU (see :mod:`mbcomp.export`).

Prints what went in: states, parameters, the program's size, the guid and how the binary was
built: FMI 3.0 (the default) or 2.0, Model Exchange and/or Co-Simulation (``--kind both``,
the default).

Examples
--------
>>> from mbcomp.cli.main import make_parser
>>> args = make_parser().parse_args(["export", "models/slider_crank.py", "-o", "crank.fmu"])
>>> args.func.__name__, args.fmi, args.kind
('cmd_export', '3.0', 'both')
"""
from __future__ import annotations

import inspect
import pathlib

from .loader import check_output, load, split_params

__all__ = ["cmd_export", "add_parser", "build_arguments"]


def cmd_export(args):
    """Write the model file's model as an FMU; exit status 0."""
    from ..export import export_fmu

    check_output(args.out, "-o")
    mod, model, runtime = load(args)
    stop = args.stop_time or dict(getattr(mod, "SIMULATION", {})).get("t_end", 1.0)
    info = export_fmu(model, args.out, fmi=args.fmi, kind=args.kind, params=runtime, outputs=args.outputs,
                      name=pathlib.Path(args.out).stem, stop_time=stop, tolerance=args.tolerance)
    kinds = {"me": "Model Exchange", "cs": "Co-Simulation", "both": "Model Exchange + Co-Simulation"}
    print(f"wrote {args.out}: FMI {args.fmi} {kinds[args.kind]}, "
          f"{info['size']} bytes, guid {info['guid']}")
    print(f"states ({len(info['states'])}): {', '.join(info['states'])}")
    print(f"parameters ({len(info['parameters'])}): {', '.join(info['parameters'])}")
    fixed = list(info["fixed"])
    print(f"not tunable ({len(fixed)}): " + (", ".join(fixed[:12]) + (", ..." if len(fixed) > 12 else "")
          + " (zeros folded into the program; export_fmu(..., tunable='all') makes them parameters)" if fixed else "none"))
    shown = ", ".join(info["outputs"][:12]) + (", ..." if len(info["outputs"]) > 12 else "")
    print(f"outputs ({len(info['outputs'])}): {shown or 'none'}")
    print(f"inputs ({len(info['inputs'])}): {', '.join(info['inputs']) or 'none'}")
    built = build_arguments(mod, args.param)
    if built:
        print("fixed at export (build() arguments, which may change the model's structure; export again with "
              f"-p name=value to change them): {', '.join(f'{k}={v!r}' for k, v in built.items())}")
    print(f"default experiment: 0 .. {stop:g} s at tolerance {args.tolerance:g}")
    print(f"program: {info['operations']} operations, built with {info['compiler']} "
          f"(binaries/{'x86_64-linux' if args.fmi == '3.0' else 'linux64'}/{info['model_identifier']}.so)")
    return 0


def build_arguments(mod, pairs):
    """``{name: value}`` of the model file's ``build()`` arguments as the export used them (its
    defaults, those given by ``-p name=value`` instead): baked into the FMU, since a build()
    argument may change the model's structure (a component more or less, a loop), which no FMU
    parameter can.

    Examples
    --------
    >>> import types
    >>> mod = types.SimpleNamespace(build=lambda n=3, length=0.5, *, shape="box": None)
    >>> build_arguments(mod, ["n=5"])
    {'n': 5, 'length': 0.5, 'shape': 'box'}
    """
    given, _ = split_params(pairs, mod.build)
    out = {}
    for name, p in inspect.signature(mod.build).parameters.items():
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            continue
        if name in given:
            out[name] = given[name]
        elif p.default is not p.empty:
            out[name] = p.default
    out.update({k: v for k, v in given.items() if k not in out})  # taken by **kwargs
    return out


def add_parser(sub, common):
    """The ``export`` sub-command on the argparse ``sub``-parsers."""
    e = sub.add_parser("export", help="export the model as an FMU (FMI 3.0 or 2.0, Model Exchange and Co-Simulation)")
    common(e)
    e.add_argument("-o", "--out", required=True, help="the .fmu file to write")
    e.add_argument("--fmi", default="3.0", choices=["3.0", "2.0"], help="FMI version (default 3.0)")
    e.add_argument("--kind", default="both", choices=["me", "cs", "both"],
                   help="Model Exchange, Co-Simulation or both (default)")
    e.add_argument("--outputs", action="append", metavar="PATTERN",
                   help="outputs to include, shell-style (repeatable; default: every result column), e.g. '*.f.*'")
    e.add_argument("--stop-time", dest="stop_time", type=float,
                   help="the FMU's default stop time (s; default: the model file's SIMULATION t_end, else 1)")
    e.add_argument("--tolerance", type=float, default=1e-12,
                   help="the FMU's default relative tolerance (default 1e-12: FMPy's CVODE needs it for 1e-7)")
    e.set_defaults(func=cmd_export)
    return e
