"""What every command shares: loading the model file, ``-p name=value``, checking output paths.

``-p name=value`` passes ``name`` to the file's ``build`` when it has no dot, and sets a
component parameter at run time when it has one (``-p spring.c=200``: nothing is
re-derived). A build() value is parsed into the kind its default declares (a number, a
boolean, a list of numbers, a string; :mod:`mbcomp.cli.params`), a component value into a
number, boolean, list or the text itself (:func:`parse_value`); the component checks it.
A robot description (``.urdf``, MJCF ``.xml``) is a model file whose build() is its loader
(:mod:`mbcomp.cli.robots`): ``-p floating=true`` goes to ``load_urdf`` as ``-p m=2`` to a build().

Errors are ``ValueError`` (a :class:`~mbcomp.errors.ModelError` is one) with the fix in the
message; :func:`mbcomp.cli.main.main` prints them as ``mbcomp: ...`` and exits 2.

Examples
--------
>>> from mbcomp.cli.loader import split_params
>>> def build(m=1.0, L=2.0): ...
>>> split_params(["m=2.5", "spring.c=200"], build)
({'m': 2.5}, {'spring.c': 200})
"""
from __future__ import annotations

import inspect
import os
import pathlib

from ..modeling.loader import build_model, load_model_file
from .params import build_value, describe_parameters, parse_value
from .robots import is_robot_file, robot_module

__all__ = ["parse_value", "load_model_file", "model_module", "split_params", "load", "call_build", "check_output"]


def model_module(path):
    """What every command loads: the model file ``path`` as a module
    (:func:`mbcomp.load_model_file`), or the robot description ``path`` (``.urdf``, MJCF
    ``.xml``) as one whose ``build`` is its loader (:func:`mbcomp.cli.robots.robot_module`)."""
    if is_robot_file(path):
        return robot_module(path)
    return load_model_file(path)


def takes(build, name):
    """Whether ``build`` accepts the keyword ``name`` (by name or through ``**kwargs``)."""
    sig = inspect.signature(build)
    return name in sig.parameters or any(p.kind == p.VAR_KEYWORD for p in sig.parameters.values())


def split_params(pairs, build):
    """``-p`` pairs -> ``(build_kw, runtime)``: names without a dot go to ``build``, dotted
    names (``component.param``) are runtime parameter values.

    Raises
    ------
    ValueError
        A pair without ``=``, a build() parameter that ``build`` does not take (the message
        lists the ones it takes), or a value not of the kind the parameter's default declares.
    """
    build_kw, runtime = {}, {}
    for pair in pairs or []:
        if "=" not in pair:
            raise ValueError(f"-p expects name=value, got {pair!r}")
        k, v = (x.strip() for x in pair.split("=", 1))
        if "." in k:
            runtime[k] = parse_value(v)
        elif not takes(build, k):
            who = getattr(build, "who", "build()")  # a robot file's: its loader, e.g. load_urdf()
            raise ValueError(f"-p {k}={v}: {who} takes no parameter {k}; it takes: {describe_parameters(build)} "
                             "-> fix: use one of these names, or component.param=value for a component parameter")
        else:
            build_kw[k] = build_value(build, k, v)
    return build_kw, runtime


def load(args, defaults=None):
    """``(module, model, runtime)`` of the command's model file and ``-p`` values.

    ``defaults`` names a dict the model file may set of build() values the command uses where
    ``-p`` gives none (``SIMULATE_PARAMS``: what ``mbcomp simulate`` shows, e.g. the bicycle
    with a push, while ``build()`` itself and the other commands keep the file's defaults)."""
    mod = model_module(args.model)
    build_kw, runtime = split_params(args.param, mod.build)
    if defaults:
        given = dict(getattr(mod, defaults, None) or {})
        bad = [k for k in given if not takes(mod.build, k)]
        if bad:
            raise ValueError(f"{args.model}: {defaults} sets {', '.join(bad)}, which build() does not take; it takes: "
                             f"{describe_parameters(mod.build)} -> fix {defaults} in the model file")
        build_kw = {**given, **build_kw}
    return mod, build_model(mod, **build_kw), runtime


def call_build(mod, kw, path):
    """The model ``mod.build(**kw)``; a ``TypeError`` (e.g. a text value where build() needs a
    number) becomes a ``ValueError`` naming the call and the fix."""
    try:
        return build_model(mod, **kw)
    except TypeError as exc:
        args = ", ".join(f"{k}={v!r}" for k, v in kw.items())
        raise ValueError(f"build({args}) of {path} failed ({exc}) -> fix: give numbers to -p / --sweep") from None


def check_output(path, option):
    """Fail before any work when the file ``path`` (given as ``option``) cannot be written.

    A long run must not end in "directory does not exist" with its results lost: every
    command checks its output files before it loads the model.

    Raises
    ------
    ValueError
        Naming the path, what is wrong and the fix.

    Examples
    --------
    >>> from mbcomp.cli.loader import check_output
    >>> check_output(None, "--out")  # nothing asked for: nothing to check
    >>> try:
    ...     check_output("no/such/dir/x.csv", "--out")
    ... except ValueError as exc:
    ...     print(exc)
    --out no/such/dir/x.csv: the directory no/such/dir does not exist -> fix: create it first (mkdir -p no/such/dir) or write elsewhere
    """
    if path is None:
        return
    p = pathlib.Path(path)
    head = f"{option} {path}:"
    if p.is_dir():
        raise ValueError(f"{head} is a directory -> fix: give the name of a file (inside it, or elsewhere)")
    parent = p.parent
    if not parent.exists():
        raise ValueError(f"{head} the directory {parent} does not exist -> fix: create it first "
                         f"(mkdir -p {parent}) or write elsewhere")
    if not parent.is_dir():
        raise ValueError(f"{head} {parent} is a file, not a directory -> fix: choose another path")
    if not os.access(parent, os.W_OK):
        raise ValueError(f"{head} the directory {parent} is not writable -> fix: write to a directory you may write to")
