"""Model files: a Python file whose ``build(**params)`` returns a :class:`~mbcomp.Model`.

A model file may also set ``SIMULATION = dict(t_end=..., rtol=..., ...)`` (defaults for
``mbcomp simulate``) and anything else its users need (analytic solutions, reference data).
:func:`load_model_file` imports the file and returns the module; :func:`load_model` also
calls ``build`` and returns the model. Both are ``mbcomp.load_model_file`` and
``mbcomp.load_model``; the command line (:mod:`mbcomp.cli`) loads its models with them.

Each call executes the file afresh (a new module object, not entered in ``sys.modules``),
so two loads never share module-level state.

Examples
--------
>>> import pathlib, tempfile, mbcomp
>>> src = '''
... from mbcomp import Model
... from mbcomp.library import World, Revolute, FixedTranslation, PointMass
... def build(L=1.0):
...     m = Model(); w = m.add("world", World()); j = m.add("hinge", Revolute(phi0=0.3))
...     rod = m.add("rod", FixedTranslation(r=(0, -L, 0))); bob = m.add("bob", PointMass(m=1.0))
...     m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
...     return m
... '''
>>> path = pathlib.Path(tempfile.mkdtemp()) / "pendulum.py"
>>> _ = path.write_text(src)
>>> model = mbcomp.load_model(path, L=2.0)
>>> mbcomp.assemble(model).q_names
['hinge.phi']
"""
from __future__ import annotations

import importlib.util
import os
import pathlib

from ..errors import ModelError, Problem
from .model import Model

__all__ = ["load_model_file", "build_model", "load_model", "import_file"]

_HEADER = "cannot load the model file"
_BUILD = "def build(**params): ... return model  (model: the mbcomp.Model it assembles)"


def load_model_file(path):
    """Import a model file and return it as a module (it defines ``build(**params) -> Model``).

    Parameters
    ----------
    path : str or path-like
        The ``.py`` file, relative to the current directory or absolute.

    Returns
    -------
    module
        The executed file; ``module.build`` is callable.

    Raises
    ------
    ModelError
        When the file does not exist, is not a Python file, or defines no ``build``; the
        problem names the file and the fix. Errors raised while the file runs (a syntax
        error, a failed import) propagate unchanged, pointing at the line in the file.

    Examples
    --------
    >>> import mbcomp
    >>> try:
    ...     mbcomp.load_model_file("no/such/model.py")
    ... except mbcomp.ModelError as exc:
    ...     print(exc.problems[0].what)
    the model file does not exist
    """
    mod = import_file(path)
    if not callable(getattr(mod, "build", None)):
        raise ModelError([Problem(str(path), "defines no build(**params) -> Model function",
                                  f"add one to the file: {_BUILD}")], _HEADER)
    return mod


def import_file(path):
    """Execute the Python file ``path`` as a new module (not entered in ``sys.modules``).

    :func:`load_model_file` without the check for ``build``: for files that are not model
    files but are loaded the same way (e.g. a derivation shared between tests).

    Raises
    ------
    ModelError
        When the file does not exist or is not a Python file.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from mbcomp.modeling.loader import import_file
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "constants.py"
    >>> _ = path.write_text("g = 9.81")
    >>> import_file(path).g
    9.81
    """
    if not isinstance(path, (str, os.PathLike)):
        raise ModelError([Problem(repr(path)[:60], f"is a {type(path).__name__}, not the path of a model file",
                                  "give the path of a .py file defining build(**params) -> Model, e.g. "
                                  "'models/pendulum.py' (a Model itself goes to mbcomp.simulate directly)")], _HEADER)
    path = pathlib.Path(path)
    if not path.is_file():
        what = "is a directory, not a model file" if path.is_dir() else "the model file does not exist"
        raise ModelError([Problem(str(path), what, f"give the path of a .py file defining build(**params) -> Model "
                                                   f"(relative paths start at {pathlib.Path.cwd()})")], _HEADER)
    spec = importlib.util.spec_from_file_location(path.stem.replace("-", "_").replace(".", "_"), path)
    if spec is None:
        raise ModelError([Problem(str(path), "is not a Python file",
                                  "give a .py file defining build(**params) -> Model")], _HEADER)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def build_model(module, **build_kwargs):
    """``module.build(**build_kwargs)``, checked to be a :class:`~mbcomp.Model`.

    Parameters
    ----------
    module : module
        A loaded model file (:func:`load_model_file`).
    **build_kwargs
        Passed to ``build``.

    Raises
    ------
    ModelError
        When ``build`` returns something that is not a Model (naming the file and the type).

    Examples
    --------
    >>> import types, mbcomp
    >>> from mbcomp.modeling.loader import build_model
    >>> broken = types.ModuleType("broken"); broken.build = lambda: None
    >>> try:
    ...     build_model(broken)
    ... except mbcomp.ModelError as exc:
    ...     print(exc.problems[0].what)
    build() returned None; it must return an mbcomp.Model
    """
    model = module.build(**build_kwargs)
    if not isinstance(model, Model):
        where = getattr(module, "__file__", None) or module.__name__
        got = "None" if model is None else f"a {type(model).__name__} ({_short(model)})"
        fix = ("add 'return m' at its end (m: the Model it builds)" if model is None else
               f"return the mbcomp.Model itself: {_BUILD}")
        raise ModelError([Problem(str(where), f"build() returned {got}; it must return an mbcomp.Model", fix)],
                         _HEADER)
    return model


def _short(value, limit=50):
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def load_model(path, **build_kwargs):
    """The :class:`~mbcomp.Model` that the model file at ``path`` builds: ``build(**build_kwargs)``.

    Parameters
    ----------
    path : str or path-like
        The model file (see :func:`load_model_file`).
    **build_kwargs
        Arguments of the file's ``build``, e.g. ``mbcomp.load_model("models/slider_crank.py",
        m_slider=1.5)``.

    Raises
    ------
    ModelError
        See :func:`load_model_file` and :func:`build_model`.

    Examples
    --------
    >>> import mbcomp
    >>> try:
    ...     mbcomp.load_model("no/such/model.py")
    ... except mbcomp.ModelError as exc:
    ...     print(str(exc).splitlines()[0])
    cannot load the model file (1):
    """
    return build_model(load_model_file(path), **build_kwargs)
