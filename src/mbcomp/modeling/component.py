"""Components, parameters and connectors.

A component declares its parameters (:class:`Param`) and its ports (:class:`Frame`,
:class:`Flange`) as class attributes. Parameter values are checked by
:meth:`Component.problems`, which :meth:`mbcomp.Model.validate` collects for every
component before raising once.

Examples
--------
>>> from mbcomp import Component, Param, Frame
>>> class Marker(Component):
...     '''A massless marker frame.'''
...     frame_a = Frame("the marked frame")
...     size = Param(0.1, unit="m", doc="drawing size", check="positive")
>>> Marker(size=0.2).p.size
0.2
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from ..errors import Problem
from .docstring import document_component
from .shapes import rgb, shapes_given
from .units import UnitError, example, has_unit, is_quantity, to_unit

__all__ = ["Param", "Frame", "Flange", "Port", "Component", "Guess"]


class Guess:
    """A start value that initialization may change (not fixed); like any parameter value it
    may carry a unit (``Guess("30 deg")``), converted when the component is made.

    Examples
    --------
    >>> from mbcomp import Guess
    >>> Guess(0.3).value
    0.3
    >>> from mbcomp.library import Revolute
    >>> round(Revolute(phi0=Guess("90 deg")).p.phi0.value, 6)
    1.570796
    """

    def __init__(self, value):
        self.value = value

    def __repr__(self):
        return f"Guess({self.value!r})"


_CHECKS = {
    "positive": (lambda v: (v > 0).all(), "must be > 0"),
    "nonnegative": (lambda v: (v >= 0).all(), "must be >= 0"),
    "nonzero": (lambda v: np.linalg.norm(np.atleast_1d(v)) > 0, "must not be zero"),
}
#: the same checks of a plain float (:meth:`Param.coerce`'s fast path)
_SCALAR_CHECKS = {"positive": lambda x: x > 0, "nonnegative": lambda x: x >= 0, "nonzero": lambda x: abs(x) > 0}


class Param:
    """A documented, validated parameter in SI units.

    A value may be given with a unit (:mod:`mbcomp.modeling.units`): a string such as
    ``"250 g"``, ``"30 deg"``, ``"2 kN/m"``, ``"(10, 0, 0) cm"``, a list or tuple of numbers and
    such strings (``("10 cm", 0, 0)``), or a ``pint`` quantity. It is converted to the
    parameter's ``unit`` once, when the component is made (:meth:`coerce`); a unit of another
    dimension or an unknown one is a problem :meth:`mbcomp.Model.validate` reports, naming the
    parameter and both units.

    Parameters
    ----------
    default : float, array_like, callable or None
        Default value. ``None`` means the parameter is optional.
    unit : str
        SI unit, e.g. ``"kg"``, ``"N/m"``, ``"rad"``; ``"1"`` for none; alternatives as
        ``"m or rad"`` (a value in either is accepted).
    doc : str
        One-line meaning, including the frame a vector is resolved in.
    shape : tuple, optional
        Required array shape; scalars when omitted.
    check : str or callable, optional
        ``"positive"``, ``"nonnegative"``, ``"nonzero"``, or ``f(value) -> str | None``
        returning a message when the value is bad.
    kind : {"number", "start", "law", "any"}
        ``"start"`` values may be a :class:`Guess`; ``"law"`` values may be callables;
        ``"any"`` values are kept as given (only a pint quantity is converted).

    Examples
    --------
    >>> from mbcomp import Param
    >>> Param(1.0, unit="N/m").coerce("2 kN/m")
    (2000.0, None)
    >>> Param(1.0, unit="kg").coerce("30 deg")[1]
    '"30 deg" has unit deg (angle), expected kg (mass)'
    """

    def __init__(self, default, unit="1", doc="", shape=(), check=None, kind="number"):
        self.default, self.unit, self.doc = default, unit, doc
        self.shape, self.check, self.kind = tuple(shape), check, kind
        self.name = None
        self._checked_default = None  # (value, problem) of a tuple default, once coerced

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        return obj.p.__dict__[self.name]

    def __repr__(self):
        return f"Param({self.default!r}, unit={self.unit!r}, doc={self.doc!r})"

    def _unit_suffix(self):
        return "" if self.unit in ("1", "") else f" {self.unit}"

    def hint(self, given=None):
        """The fix to suggest for a bad value: what the parameter means, its unit and shape;
        for a value ``given`` with a unit, also a value with a unit of the right dimension."""
        what = f" ({self.doc})" if self.doc else ""
        shape = f" as an array of shape {self.shape}" if self.shape else ""
        unit = " (dimensionless)" if self.unit in ("1", "") else f" in {self.unit}"
        req = {"positive": ", > 0", "nonnegative": ", >= 0", "nonzero": ", not zero"}.get(
            self.check if isinstance(self.check, str) else None, "")
        alt = example(self.unit) if given is not None and has_unit(given) else ""
        return f"give {self.name}{what}{shape}{unit}{req}" + (f", or {alt}" if alt else "")

    def coerce(self, value):
        """Return ``(value, problem_text)``: the value as stored (converted to :attr:`unit` when
        given with a unit), or why it is bad."""
        if value is None:
            return None, None
        if self.kind == "any":  # a law, a number or text: only a pint quantity is converted
            return self._convert(value) if is_quantity(value) else (value, None)
        if self.kind == "law" and callable(value):
            return value, None
        if self.kind == "start" and isinstance(value, Guess):
            inner, msg = self.coerce(value.value)
            return (Guess(inner) if msg is None else value), msg
        if (type(value) is float or type(value) is int) and not self.shape:  # a plain number: as below, in floats
            return self._number(value)
        if value is self.default and type(value) is tuple:  # a class's default: checked once
            if self._checked_default is None:
                self._checked_default = self._coerce_number(value)
            got, msg = self._checked_default
            return (got.copy() if isinstance(got, np.ndarray) else got), msg
        return self._coerce_number(value)

    def _number(self, value):
        """:meth:`coerce` of a plain ``float`` or ``int`` for a scalar parameter: the same
        value and messages, without the array operations."""
        x = float(value)
        if not math.isfinite(x):
            return value, f"{value!r} is not finite"
        if self.check is not None:
            if isinstance(self.check, str):
                ok, msg = _SCALAR_CHECKS[self.check], _CHECKS[self.check][1]
                if not ok(x):
                    return value, f"{x:g}{self._unit_suffix()} {msg}"
            else:
                msg = self.check(np.array(x))
                if msg:
                    return value, msg
        return x, None

    def _coerce_number(self, value):
        """:meth:`coerce` of a value to be converted and checked as a number or array."""
        if type(value) in (tuple, list) and all(type(x) is float or type(x) is int for x in value):
            number = value  # plain numbers: nothing to convert (to_unit would return their list)
        else:
            number, msg = self._convert(value)
            if msg:
                return value, msg
        try:
            arr = np.array(number, dtype=float)
        except (TypeError, ValueError):
            return value, f"{value!r} is not a number{'' if not self.shape else ' array'}"
        if arr.shape != self.shape:
            return value, f"has shape {arr.shape}, expected {self.shape or 'a scalar'}"
        if not np.isfinite(arr).all():
            return value, f"{value!r} is not finite"
        if self.check is not None:
            if isinstance(self.check, str):
                ok, msg = _CHECKS[self.check]
                if not ok(arr):
                    return value, f"{_fmt(arr)}{self._unit_suffix()} {msg}"
            else:
                msg = self.check(arr)
                if msg:
                    return value, msg
        return (float(arr) if arr.shape == () else arr), None

    def _convert(self, value):
        """``(value in this parameter's unit, None)``, or ``(value, why not)``."""
        try:
            return to_unit(value, self.unit), None
        except UnitError as exc:
            return value, str(exc)


def _fmt(arr):
    return f"{float(arr):g}" if np.ndim(arr) == 0 else np.array2string(np.asarray(arr), precision=4)


class Port:
    """Declaration of a connector on a component class (see :class:`Frame`, :class:`Flange`)."""

    kind = "port"

    def __init__(self, doc="", optional=False):
        self.doc, self.optional, self.name = doc, optional, None

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        return PortRef(obj, self.name, self.kind)

    def __repr__(self):
        return f"{type(self).__name__}({self.doc!r}{', optional=True' if self.optional else ''})"


class Frame(Port):
    """Frame connector: position and orientation (3x3) and their rates as potentials,
    force and torque (resolved in the world frame) as flows. Connecting frames makes them
    one rigid frame; any number of components may attach to it."""

    kind = "frame"


class Flange(Port):
    """1-D connector: coordinate and rate (m or rad, m/s or rad/s) as potentials,
    force or torque as flow. Drives, springs and dampers act on a joint's axis through it."""

    kind = "flange"


class PortRef:
    """A port of a component instance: what :meth:`Model.connect` takes."""

    __slots__ = ("component", "name", "kind", "_hash")

    def __init__(self, component, name, kind):
        self.component, self.name, self.kind = component, name, kind
        self._hash = hash((id(component), name))  # the assembly's union-finds hash each port hundreds of times

    def __eq__(self, other):
        return isinstance(other, PortRef) and other.component is self.component and other.name == self.name

    def __hash__(self):
        return self._hash

    def __reduce__(self):  # made again where unpickled or copied: the hash follows the component's new id
        return PortRef, (self.component, self.name, self.kind)

    @property
    def path(self):
        return f"{self.component.path}.{self.name}"

    def __repr__(self):
        return f"<{self.kind} {self.path}>"



#: (class, kind) -> (the sizes of the classes' namespaces along the MRO, {name: declaration})
_DECLARED = {}


def _declared(cls, kind):
    """``{name: declaration}`` of the ``kind`` (:class:`Param` or :class:`Port`) attributes of
    ``cls`` and its bases, base classes first. Read once per class (a model builds and
    assembles its components' declarations hundreds of times); read again when a class on
    the MRO gained or lost an attribute since."""
    mro = cls.__mro__
    sizes = tuple(map(len, map(vars, mro)))  # (a generator here was a tenth of assembling 1000 links)
    got = _DECLARED.get((cls, kind))
    if got is not None and got[0] == sizes:
        return got[1]
    out = {}
    for klass in reversed(mro):
        for k, v in vars(klass).items():
            if isinstance(v, kind):
                out[k] = v
    _DECLARED[(cls, kind)] = (sizes, out)
    return out

class Component:
    """Base class of every component: parameters, ports, a name given by the model.

    Subclasses declare ``Param`` and ``Frame``/``Flange`` class attributes and implement
    one role (see :mod:`mbcomp.roles`). Parameter values are available as ``self.p.<name>``
    (construction-time values); the assembled system passes runtime values to the role
    methods, so changing a parameter never re-derives anything.

    Besides its parameters every component takes how it looks in animations and snapshots:
    ``shape=`` a shape or a list of shapes of :mod:`mbcomp.modeling.shapes` instead of its
    default ones (:meth:`visuals`), ``color=`` (a name, ``"#rrggbb"`` or ``(r, g, b)``) and
    ``visible=False`` to hide it.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.library import PointMass
    >>> PointMass(m=2.0).p.m
    2.0
    >>> PointMass(m=2.0, shape=mbcomp.Sphere(0.05), color="gold").look.color
    '#d4a017'
    """

    role = None
    #: whether the component's forces do no work but through its :meth:`potential` (or none at
    #: all): declared by each class, read by :meth:`conserves_energy`
    conservative = True
    #: whether the shapes of :meth:`visuals` draw the body the component is fixed to (a
    #: wheel's contact draws the wheel), so that body draws none of its own
    draws_body = False

    def __init_subclass__(cls, **kwargs):
        """Document the subclass's parameters (unit, default, doc) and ports in its docstring,
        so ``help()``, pydoc and IDEs list them (:func:`mbcomp.modeling.docstring.document_component`)."""
        super().__init_subclass__(**kwargs)
        document_component(cls)

    def conserves_energy(self, p):
        """Whether the component, with parameter values ``p``, keeps the total energy of a
        mechanism built from such components constant (its forces derive from its potential
        or do no work). The class's :attr:`conservative`; a class whose answer depends on a
        parameter (a damper's rate) overrides this."""
        return self.conservative

    def __init__(self, *, shape=None, color=None, visible=True, **values):
        self.name = None
        self.parent = None
        where = type(self).__name__
        self.look = SimpleNamespace(shape=shapes_given(shape, where), color=rgb(color, f"{where}.color"),
                                    visible=bool(visible))
        params = self.params()
        unknown = [k for k in values if k not in params]
        if unknown:
            raise TypeError(
                f"{type(self).__name__} has no parameter {', '.join(map(repr, unknown))}; "
                f"its parameters are: {', '.join(params) or 'none'}"
            )
        self._raw = {}
        self._bad = {}
        store = {}
        for name, par in params.items():
            raw = values.get(name, par.default)
            self._raw[name] = raw
            val, msg = par.coerce(raw)
            if msg:
                self._bad[name] = msg
            store[name] = val
        self.p = SimpleNamespace(**store)

    def visuals(self, p, view):
        """The component's default shapes (:mod:`mbcomp.modeling.shapes`), each placed in one
        of its frames; none by default. Components override this to be seen without extra work.

        ``view`` (:mod:`mbcomp.visual.scene`) tells: ``scale``, the mechanism's size (m);
        ``attached(port)``, the origins of the frames rigidly fixed to a port's frame (m, its
        axes); ``covered(port)``, whether another component draws the body there (a wheel's
        contact); ``range(column)``, ``(min, max)`` of one of the component's result columns
        over the run (a slider's travel); ``track(port, of)``, where frame ``of`` went over the
        run, in the axes of frame ``port`` (a surface patch covers the ball's path); and for a
        component on a joint's axis flange (no frames: a rotor) ``axis(port)``, the joint's
        axis in the frame the flange moves, on which its shapes are placed."""
        return []

    def shapes(self, p, view):
        """The shapes drawn: those given at construction (``shape=``) or :meth:`visuals`,
        recoloured by ``color=``; none when ``visible=False``."""
        look = getattr(self, "look", None)
        if look is not None and not look.visible:
            return []
        items = list(look.shape) if look is not None and look.shape is not None else list(self.visuals(p, view))
        if look is not None and look.color is not None:
            items = [s.placed(color=look.color) for s in items]
        return items

    @classmethod
    def params(cls):
        """Dictionary ``name -> Param`` of the class's parameters, in declaration order."""
        return dict(_declared(cls, Param))

    @classmethod
    def ports(cls):
        """Dictionary ``name -> Port`` of the class's connectors."""
        return dict(_declared(cls, Port))

    @property
    def path(self):
        """Dotted name inside the top-level model (``"arm.link1"``)."""
        if self.name is None:
            return f"<unnamed {type(self).__name__}>"
        if self.parent is not None and self.parent.parent is not None:
            return f"{self.parent.path}.{self.name}"
        return self.name

    def problems(self):
        """Every problem with this component's parameters, as :class:`Problem` objects."""
        out = []
        for name, msg in self._bad.items():
            par = self.params()[name]
            out.append(
                Problem(f"{self.path}.{name}", f"parameter {msg}",
                        par.hint(self._raw[name]))
            )
        out.extend(self.check_params(self.p))
        return out

    def check_params(self, p):
        """Cross-parameter checks; subclasses return a list of :class:`Problem`."""
        return []

    def runtime_params(self, overrides=None):
        """Parameter namespace with ``overrides`` (name -> value) applied and checked."""
        if not overrides:
            return self.p
        vals = dict(vars(self.p))
        params = self.params()
        probs = []
        for k, v in overrides.items():
            if k not in params:
                probs.append(Problem(f"{self.path}.{k}", "no such parameter",
                                     f"use one of: {', '.join(params)}"))
                continue
            val, msg = params[k].coerce(v)
            if msg:
                probs.append(Problem(f"{self.path}.{k}", f"parameter {msg}", params[k].hint(v)))
            vals[k] = val
        ns = SimpleNamespace(**vals)
        probs.extend(self.check_params(ns))
        if probs:
            from ..errors import ModelError
            raise ModelError(probs, header="bad parameter values")
        return ns

    def __repr__(self):
        return f"<{type(self).__name__} {self.path}>"
