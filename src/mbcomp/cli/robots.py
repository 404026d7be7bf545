"""Robot description files as model files: ``mbcomp info robot.urdf``, ``mbcomp simulate robot.xml``.

A ``.urdf`` file is read by :func:`mbcomp.io.urdf.load_urdf`, an MJCF ``.xml`` file (root
element ``<mujoco>``) by ``mbcomp.io.mjcf.load_mjcf`` (a ``.xml`` whose root is ``<robot>`` is
a URDF). The loader with the file bound is the file's ``build()``: its keywords are the
``-p name=value`` of the command line, parsed as any model file's build() parameters
(:mod:`mbcomp.cli.params`: ``-p floating=true -p limits=true -p gravity=0,0,-9.81``), and a
dotted ``-p joint_damping.d=0.5`` sets a component parameter at run time, as for a model
file. Whatever every command does with a model file it does with a robot file.

Examples
--------
>>> import os, tempfile
>>> from mbcomp.cli.robots import robot_module
>>> text = '''<robot name="pendulum"><link name="base"/>
... <link name="arm"><inertial><mass value="2"/><origin xyz="0 0 -0.5"/>
... <inertia ixx="0.1" iyy="0.1" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
... <joint name="hinge" type="continuous"><parent link="base"/><child link="arm"/>
... <axis xyz="0 1 0"/></joint></robot>'''
>>> path = os.path.join(tempfile.mkdtemp(), "pendulum.urdf")
>>> _ = open(path, "w").write(text)
>>> import inspect
>>> list(inspect.signature(robot_module(path).build).parameters)
['floating', 'gravity', 'limits', 'damping', 'friction', 'mimic', 'inertia', 'visuals', 'package_dirs']
>>> robot_module(path).build(gravity=(0, 0, -1.62)).components()["world"].p.g.tolist()
[0.0, 0.0, -1.62]
"""
from __future__ import annotations

from collections import Counter
import inspect
import pathlib
import sys
import types
import warnings
import xml.etree.ElementTree as ET

from ..errors import ModelError, Problem
from ..io.mjcf import load_mjcf
from ..io.urdf import load_urdf

__all__ = ["SUFFIXES", "is_robot_file", "robot_module", "portable_build", "import_notes"]

#: the file suffixes read as robot descriptions instead of Python model files
SUFFIXES = (".urdf", ".xml")
#: the attributes a loaded robot model lists its notes of what was not imported in
NOTES = ("urdf_notes", "mjcf_notes")
_HEADER = "cannot load the robot file"


def is_robot_file(path):
    """Whether ``path`` names a robot description (``.urdf`` or ``.xml``), not a Python model file."""
    return isinstance(path, (str, pathlib.PurePath)) and pathlib.Path(path).suffix.lower() in SUFFIXES


def _root_tag(path):
    """The tag of the XML file's root element (read up to it, not the whole file)."""
    try:
        for _, el in ET.iterparse(str(path), events=("start",)):
            return el.tag
    except ET.ParseError as exc:
        raise ModelError([Problem(str(path), f"is not well-formed XML ({exc})", "fix the file")], _HEADER) from None
    raise ModelError([Problem(str(path), "is empty", "give a URDF or MJCF file")], _HEADER)


def _loader(path):
    """``(loader, kind)`` of the robot file: ``load_urdf`` or ``load_mjcf`` by its root element."""
    tag = _root_tag(path)
    if tag == "robot":
        return load_urdf, "URDF"
    if tag == "mujoco":
        return load_mjcf, "MJCF"
    raise ModelError([Problem(str(path), f"has the root element <{tag}>: neither a URDF (<robot>) nor an MJCF "
                                         "(<mujoco>) file", "give a URDF or MJCF robot description, or a .py "
                                                            "model file defining build(**params) -> Model")], _HEADER)


def robot_module(path):
    """The robot file ``path`` as a model file: a module whose ``build(**keywords)`` is its loader
    (``load_urdf`` or ``load_mjcf``) with the file bound, with the loader's keywords as its
    signature (what ``-p`` checks and parses against).

    Parameters
    ----------
    path : str or path-like
        A ``.urdf`` file, or an ``.xml`` file whose root element is ``<mujoco>`` (MJCF) or
        ``<robot>`` (URDF).

    Returns
    -------
    module
        ``build``, ``__file__`` (the path) and ``ROBOT_FORMAT`` (``"URDF"`` or ``"MJCF"``).

    Raises
    ------
    ModelError
        The file does not exist, is not well-formed XML, or is neither URDF nor MJCF; the
        problem names the file and the fix.
    """
    p = pathlib.Path(path)
    if not p.is_file():
        what = "is a directory, not a robot file" if p.is_dir() else "the robot file does not exist"
        raise ModelError([Problem(str(path), what, f"give the path of a .urdf or MJCF .xml file (relative paths "
                                                   f"start at {pathlib.Path.cwd()})")], _HEADER)
    load, kind = _loader(p)
    mod = types.ModuleType(p.stem.replace("-", "_").replace(".", "_"))
    mod.__file__, mod.ROBOT_FORMAT = str(p), kind
    mod.__doc__ = f"The {kind} robot {p.name}, read by {load.__module__}.{load.__name__}."
    mod.build = _bound(load, str(p))
    return mod


def portable_build(path):
    """The robot file's ``build(**kw)`` as an object that pickles (the file's absolute path and
    nothing else), for what runs in worker processes (``mbcomp study``); the loader's summary
    warning is not repeated in every worker (the notes stay on the model)."""
    _loader(path)  # a file that is no robot description fails here, before any worker starts
    return _PortableBuild(str(pathlib.Path(path).resolve()))


class _PortableBuild:
    def __init__(self, path):
        self.path = path

    def __call__(self, **kw):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            return _loader(self.path)[0](self.path, **kw)


def _bound(load, path):
    """``build(**kw) = load(path, **kw)``, with the loader's signature less its path; a file that
    is not well-formed XML a ``ModelError`` (a ``ValueError``) naming the fix."""
    sig = inspect.signature(load)

    def build(**kw):
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                model = load(path, **kw)
        except ET.ParseError as exc:
            raise ModelError([Problem(path, f"is not well-formed XML ({exc})", "fix the file")], _HEADER) from None
        _pass_on(caught, path, model)
        return model

    build.__signature__ = sig.replace(parameters=list(sig.parameters.values())[1:])
    build.__doc__ = load.__doc__
    build.__name__ = "build"
    build.who = f"{load.__name__}() (the robot file's build())"  # what -p's messages name
    return build


def _pass_on(caught, path, model):
    """The loader's warnings again, but its summary of the notes (a warning about ``path``) as
    one line on stderr that says where to read them: ``mbcomp info`` lists them."""
    n = sum(len(getattr(model, attr, None) or []) for attr in NOTES)
    for w in caught:
        if n and issubclass(w.category, UserWarning) and str(w.message).startswith(f"{path}:"):
            print(f"mbcomp: {path}: {n} elements not imported or renamed (mbcomp info lists them)", file=sys.stderr)
            n = 0
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


def import_notes(model, limit=12):
    """The lines ``mbcomp info`` prints of what the robot file's import left out or renamed
    (``model.urdf_notes`` / ``model.mjcf_notes``), at most ``limit`` notes; ``[]`` when there
    are none or the model was not imported from a robot file.

    Examples
    --------
    >>> import types
    >>> from mbcomp.cli.robots import import_notes
    >>> import_notes(types.SimpleNamespace(urdf_notes=["joint 'j': <mimic> not imported yet"]))
    ['not imported or renamed (1, model.urdf_notes):', "  joint 'j': <mimic> not imported yet"]
    """
    lines = []
    for attr in NOTES:
        notes = list(getattr(model, attr, None) or [])
        if not notes:
            continue
        lines.append(f"not imported or renamed ({len(notes)}, model.{attr}):")
        counts = Counter(notes)  # the same note n times (a file's five <gazebo> blocks): one line
        lines += [f"  {n}" + (f" (x{counts[n]})" if counts[n] > 1 else "") for n in list(counts)[:limit]]
        if len(counts) > limit:
            lines.append(f"  ... {len(counts) - limit} more (model.{attr} lists them all)")
    return lines
