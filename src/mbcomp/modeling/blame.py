"""Who raised: the component and the law behind an exception, read from its traceback.

Used wherever mbcomp runs component code and must turn a failure into a message naming the
component (the driver, the program tracer, the symbolic tracer): the innermost frame whose
``self`` is a :class:`~mbcomp.modeling.component.Component` names the component, the last
frame outside mbcomp's own framework, the standard library and installed packages (numpy,
scipy) names the law (a user's function or method, or a library component's) and its line.

Examples
--------
>>> from mbcomp.modeling.blame import blame
>>> def law(t):
...     return 1.0 / t
>>> try:
...     law(0.0)
... except ZeroDivisionError as exc:
...     b = blame(exc)
>>> b.component is None, b.law
(True, 'law')
"""
from __future__ import annotations

import pathlib
import sysconfig
from dataclasses import dataclass
from typing import Any

__all__ = ["Blame", "blame", "FRAMEWORK"]

#: mbcomp's framework sources (``src/mbcomp``): frames here are not a user's law
FRAMEWORK = pathlib.Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Blame:
    """What raised.

    Attributes
    ----------
    component : Component or None
        The innermost component whose method was running.
    law : str
        Name of the function or method that raised, outside the framework (e.g. a user's
        force law, or ``wrenches`` of a library component); ``"?"`` if unknown.
    where : str
        ``"file.py:line in name"`` of that frame.
    """

    component: Any
    law: str
    where: str

    @property
    def path(self):
        """The component's path in the model, or ``"model"``."""
        return self.component.path if self.component is not None else "model"

    @property
    def who(self):
        """``"<Class> '<path>'"`` or ``"a component"``."""
        c = self.component
        return f"{type(c).__name__} {c.path!r}" if c is not None else "a component"


#: where ``mbcomp.library`` sits when mbcomp is installed as a package (not editable)
_LIBRARY_INSTALLED = FRAMEWORK / "library"

#: the interpreter's own library and installed packages: numpy or scipy raising inside a law
#: is the law's failure, not theirs
_NOT_LAWS = tuple({pathlib.Path(p).resolve() for p in (sysconfig.get_paths()["stdlib"], sysconfig.get_paths()["purelib"],
                                                     sysconfig.get_paths()["platlib"])})


def _in_framework(filename):
    """Framework code, the standard library or an installed package -- not a law. The
    component library counts as laws wherever it is installed (beside ``src/`` in a checkout,
    or inside the installed ``mbcomp`` package among site-packages)."""
    try:
        path = pathlib.Path(filename).resolve()
    except (OSError, ValueError):
        return True  # <frozen ...>: not a user's source file
    if path.is_relative_to(_LIBRARY_INSTALLED):
        return False
    return any(path.is_relative_to(r) for r in (FRAMEWORK,) + _NOT_LAWS)


def blame(exc, component_types=None) -> Blame:
    """The component and law behind ``exc`` (see :class:`Blame`).

    Parameters
    ----------
    exc : BaseException
        With its traceback.
    component_types : tuple of type, optional
        What counts as a component (default :class:`~mbcomp.modeling.component.Component`);
        a tracer may add its own stand-ins for components.
    """
    from .component import Component

    kinds = component_types or (Component,)
    tb, found, last = exc.__traceback__, None, None
    while tb is not None:
        obj = tb.tb_frame.f_locals.get("self")
        if isinstance(obj, kinds):
            found = obj
        if not _in_framework(tb.tb_frame.f_code.co_filename):
            last = tb
        tb = tb.tb_next
    if last is None:
        return Blame(found, "?", "?")
    co = last.tb_frame.f_code
    return Blame(found, co.co_name, f"{pathlib.Path(co.co_filename).name}:{last.tb_lineno} in {co.co_name}")
