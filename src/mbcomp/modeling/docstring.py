"""A component's docstring completed from its declarations: its parameters and ports.

Every :class:`~mbcomp.Component` subclass, the library's and a user's, gets a numpydoc
``Parameters`` section (name, kind and shape, unit, default, doc, the check a value must
pass) and a ``Ports`` section (frames and flanges, optional or not) in its ``__doc__``, made
from its :class:`~mbcomp.Param` and port declarations when the class is defined, so
``help(Revolute)``, pydoc and IDEs list them. A section the class writes itself is kept as
written. The sections go before ``See Also``, ``Notes``, ``References`` or ``Examples``
(numpydoc's order), else at the end.

Examples
--------
>>> from mbcomp import Component, Param, Flange
>>> class Stop(Component):
...     '''An end stop on a slider.'''
...     flange_b = Flange("the stopped flange")
...     gap = Param(0.02, unit="m", doc="free travel before contact", check="nonnegative")
>>> print(Stop.__doc__)
An end stop on a slider.
<BLANKLINE>
Parameters
----------
gap : float, m, default 0.02
    free travel before contact; >= 0
<BLANKLINE>
Ports
-----
flange_b : Flange
    the stopped flange
"""
from __future__ import annotations

import inspect
import re

import numpy as np

__all__ = ["document_component", "parameter_section", "port_section"]

_LATER = re.compile(r"^(See Also|Notes|References|Examples)\n-{3,}$", re.M)
_REQUIRES = {"positive": "> 0", "nonnegative": ">= 0", "nonzero": "not zero"}


def _has_section(doc, title):
    return re.search(rf"^{title}\n-{{3,}}$", doc, re.M) is not None


def _default(value):
    if callable(value):
        return getattr(value, "__name__", repr(value))
    arr = np.asarray(value) if isinstance(value, (list, tuple, np.ndarray)) else None
    if arr is not None and arr.ndim == 2 and arr.shape[0] == arr.shape[1] and np.array_equal(arr, np.eye(len(arr))):
        return "identity"
    if arr is not None and arr.dtype.kind in "fiu":
        return repr(tuple(arr.tolist())) if arr.ndim == 1 else repr(arr.tolist())
    return repr(value)


def _entry(name, par):
    kind = "float" if not par.shape else f"array {par.shape}"
    kind = {"start": f"{kind} or Guess", "law": f"{kind} or callable", "any": "any"}.get(par.kind, kind)
    unit = "dimensionless" if par.unit in ("1", "") else par.unit
    default = "optional" if par.default is None else f"default {_default(par.default)}"
    doc = par.doc or ""
    req = _REQUIRES.get(par.check) if isinstance(par.check, str) else None
    doc = f"{doc}; {req}" if doc and req else doc or (req or "")
    return f"{name} : {kind}, {unit}, {default}" + (f"\n    {doc}" if doc else "")


def parameter_section(cls):
    """The numpydoc ``Parameters`` section of a component class's declared parameters
    (``""`` for none).

    Examples
    --------
    >>> from mbcomp import Component, Frame, Param
    >>> class Lamp(Component):
    ...     frame_a = Frame("where it hangs", optional=True)
    ...     m = Param(0.5, unit="kg", doc="mass", check="nonnegative")
    >>> print(parameter_section(Lamp))
    Parameters
    ----------
    m : float, kg, default 0.5
        mass; >= 0
    """
    rows = [_entry(name, par) for name, par in cls.params().items()]
    return "Parameters\n----------\n" + "\n".join(rows) if rows else ""


def port_section(cls):
    """The ``Ports`` section of a component class's frames and flanges (``""`` for none).

    Examples
    --------
    >>> from mbcomp import Component, Frame
    >>> class Lamp(Component):
    ...     frame_a = Frame("where it hangs", optional=True)
    >>> print(port_section(Lamp))
    Ports
    -----
    frame_a : Frame, optional
        where it hangs
    """
    rows = []
    for name, port in cls.ports().items():
        kind = type(port).__name__ + (", optional" if port.optional else "")
        rows.append(f"{name} : {kind}" + (f"\n    {port.doc}" if port.doc else ""))
    return "Ports\n-----\n" + "\n".join(rows) if rows else ""


def document_component(cls):
    """Add the ``Parameters`` and ``Ports`` sections to ``cls.__doc__`` where the class does
    not write them itself; called by ``Component.__init_subclass__`` for every subclass."""
    doc = inspect.cleandoc(cls.__dict__.get("__doc__") or "")
    sections = [sec for title, sec in (("Parameters", parameter_section(cls)), ("Ports", port_section(cls)))
                if sec and not _has_section(doc, title)]
    if not sections:
        return
    text = "\n\n".join(sections)
    later = _LATER.search(doc)
    if later:
        doc = f"{doc[:later.start()].rstrip()}\n\n{text}\n\n{doc[later.start():]}"
    else:
        doc = f"{doc}\n\n{text}" if doc else text
    cls.__doc__ = doc
