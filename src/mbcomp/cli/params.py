"""``-p name=value``: the text of a value parsed into what ``build()`` (or a component) takes.

Every value is first read as a Python literal or a word (:func:`parse_value`):

* numbers: ``3``, ``0.5``, ``1e-3``, ``-2.5E+2``;
* booleans: ``true`` / ``false`` in any case (and Python's ``True`` / ``False``);
* lists: ``0.1,0,0`` (commas, no spaces needed), ``(0.1, 0, 0)`` or ``[0.1, 0, 0]``: a tuple
  of the parsed elements (a list for ``[...]``);
* quoted strings ``'abc'`` / ``"abc"``; anything else stays the text itself.

A build() parameter then gets the kind its default value (or its annotation, ``float``,
``int``, ``bool``, ``str``) declares (:func:`build_value`):

* a number: a number, or ``<number> <unit>`` (``"30 deg"``, ``"250 g"``, ``"3000 rpm"``)
  converted to its SI value (``0.5236``, ``0.25``, ``314.16``: angles in rad) -- build() is
  Python code that may compute with the value (``m * L**2``), and a number default is in SI,
  as every mbcomp parameter is; so ``-p m_crank="250 g"`` is ``-p m_crank=0.25``;
* ``True``/``False``: ``true``/``false`` (or 1/0);
* a tuple or list (or array) of numbers: a list of numbers, given as above (a tuple, or a list
  when the default is one), or an array with one unit, ``"(10, 0, 0) cm"``, converted to SI;
* a string: the text itself, with one pair of surrounding quotes removed;
* no default, ``None`` or ``**kwargs``: whatever :func:`parse_value` makes of it.

Anything else is a ``ValueError`` naming the parameter, its default and the fix. Component
parameters (``-p spring.c=200``, ``-p crank.m="250 g"``) get :func:`parse_value`; the
component checks them and converts a unit into the one its parameter declares.

Examples
--------
>>> from mbcomp.cli.params import build_value
>>> def build(length=0.5, damped=False, r=(0.1, 0.0, 0.0), mode="fast"): ...
>>> build_value(build, "length", "1e-3"), build_value(build, "damped", "TRUE")
(0.001, True)
>>> build_value(build, "r", "0.2,0,1"), build_value(build, "mode", "'slow'"), build_value(build, "length", "30 cm")
((0.2, 0, 1), 'slow', 0.3)
>>> build_value(build, "r", "(10, 0, 5) mm"), round(build_value(build, "length", "90 deg"), 6)
((0.01, 0.0, 0.005), 1.570796)
>>> build_value(build, "length", "3 furlong")
Traceback (most recent call last):
...
ValueError: -p length=3 furlong: unknown unit 'furlong'; known: m, g, s, rad, A, K, mol, cd, N, J, W, Pa, Hz with SI prefixes (T, G, M, k, h, da, d, c, m, u, µ, n, p); kg, %, deg, rev, rpm, min, h, in, ft, bar, Nm -> give a number in SI units, e.g. -p length=0.5, or a number with a known unit, e.g. "250 g", "30 deg"
>>> build_value(build, "length", "abc")
Traceback (most recent call last):
...
ValueError: -p length=abc: 'abc' is not a number; build() takes length (default 0.5) -> give a number, e.g. -p length=0.5
"""
from __future__ import annotations

import ast
import inspect
import numbers
import re

import numpy as np

from ..modeling.units import UnitError, parse_unit, to_unit, unit_text

__all__ = ["parse_value", "build_value", "expected_kind", "describe_parameters"]

#: a number followed by a unit (``"30 deg"``, ``"250 g"``, ``"9.81 m/s^2"``, ``"50 %"``)
_WITH_UNIT = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*([A-Za-z\u00b0\u00b5%][A-Za-z0-9_/*^.\s\u00b0\u00b5\u00b7-]*)$")
#: an array in brackets followed by one unit (``"(10, 0, 0) cm"``)
_ARRAY_WITH_UNIT = re.compile(r"^[(\[][^()\[\]]*[)\]]\s*([A-Za-z\u00b0\u00b5%][A-Za-z0-9_/*^.\s\u00b0\u00b5\u00b7-]*)$")


def parse_value(text):
    """The value the text ``text`` spells: a number, a boolean, a tuple or list, a quoted
    string, else the text itself.

    Examples
    --------
    >>> from mbcomp.cli import parse_value
    >>> parse_value("1e-3"), parse_value("(0, 0, 1)"), parse_value("RK45")
    (0.001, (0, 0, 1), 'RK45')
    >>> parse_value("false"), parse_value("0.1,0,0"), parse_value("[1, 2]"), parse_value("'x'")
    (False, (0.1, 0, 0), [1, 2], 'x')
    """
    text = text.strip()
    word = {"true": True, "false": False}.get(text.lower())
    if word is not None:
        return word
    if "," in text and text[:1] not in "([{'\"":  # 0.1,0,0 or true,false: a tuple of the parsed parts
        return tuple(parse_value(part) for part in text.split(","))
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
        return text


def _real(v):
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def expected_kind(param):
    """What the build() parameter ``param`` (an :class:`inspect.Parameter`) takes: ``"number"``,
    ``"bool"``, ``"sequence"``, ``"str"`` or ``None`` (anything: no default, ``None``, or an
    annotation not among float, int, bool, str)."""
    ann = param.annotation
    ann = getattr(ann, "__name__", ann)
    kind = {"float": "number", "int": "number", "bool": "bool", "str": "str"}.get(ann if isinstance(ann, str) else "")
    if kind:
        return kind
    d = param.default
    if isinstance(d, bool):
        return "bool"
    if _real(d):
        return "number"
    if isinstance(d, str):
        return "str"
    if isinstance(d, (tuple, list, np.ndarray)) and all(_real(x) for x in np.ravel(np.asarray(d, dtype=object))):
        return "sequence"
    return None


def _default(param):
    d = param.default
    if d is param.empty:
        return "no default"
    return f"default {tuple(np.ravel(d).tolist()) if isinstance(d, np.ndarray) else d!r}"


def describe_parameters(build):
    """``"a (default 1.0), b (no default)"``: build()'s parameters, for error messages."""
    params = [p for p in inspect.signature(build).parameters.values()
              if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
    return ", ".join(f"{p.name} ({_default(p)})" for p in params) or "none"


def _example(param, kind):
    d = param.default
    if kind == "sequence":
        return ",".join(f"{x:g}" for x in np.ravel(d)) if d is not param.empty and len(np.ravel(d)) else "0.1,0,0"
    if kind == "bool":
        return "true"
    return f"{d!r}" if _real(d) else "0.3"


def build_value(build, name, text):
    """The value ``-p name=text`` gives build()'s parameter ``name`` (see the module doc).

    Raises
    ------
    ValueError
        The text is not what the parameter's default declares: the message names the
        parameter, its default and an example.
    """
    param = inspect.signature(build).parameters.get(name)
    value = parse_value(text)
    kind = expected_kind(param) if param is not None else None
    if kind is None:
        return value
    if kind == "str":
        text = text.strip()
        quoted = len(text) >= 2 and text[0] == text[-1] and text[0] in "'\""
        return text[1:-1] if quoted else text
    if kind == "number":
        if _real(value):
            return value
        unit = _WITH_UNIT.match(text.strip())
        if unit:
            return _in_si(name, text, unit.group(3), param)
        what, fix = "a number", "give a number"
    elif kind == "bool":
        if isinstance(value, bool) or (_real(value) and value in (0, 1)):
            return bool(value)
        what, fix = "true or false", "give true or false"
    else:
        if isinstance(value, (tuple, list)) and all(_real(x) for x in value):
            return list(value) if isinstance(param.default, list) else tuple(value)
        unit = _ARRAY_WITH_UNIT.match(text.strip())
        if unit:
            values = [float(x) for x in _in_si(name, text, unit.group(1), param)]
            return values if isinstance(param.default, list) else tuple(values)
        what, fix = "a list of numbers", "give numbers separated by commas"
    raise ValueError(f"-p {name}={text}: {text.strip()!r} is not {what}; build() takes {name} ({_default(param)}) "
                     f"-> {fix}, e.g. -p {name}={_example(param, kind)}")


def _in_si(name, text, unit, param):
    """``text`` (``"<number> <unit>"`` or ``"(<numbers>) <unit>"``) in the SI unit of its
    dimension (angles in rad): build()'s number defaults are SI, as every mbcomp parameter."""
    try:
        si = unit_text(parse_unit(unit)[1])
        value = to_unit(text.strip(), si)
    except UnitError as exc:
        d = param.default
        example = f"{d!r}" if _real(d) else "0.5"
        raise ValueError(f"-p {name}={text}: {exc} -> give a number in SI units, e.g. -p {name}={example}, or a "
                         "number with a known unit, e.g. \"250 g\", \"30 deg\"") from None
    return float(value) if np.ndim(value) == 0 else np.asarray(value, float).tolist()
