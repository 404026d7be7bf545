"""Units: the one parser of unit texts, and values given with units converted once.

A unit text is a product of symbols, each with an optional integer power, over an optional
denominator: ``"N m s/rad"``, ``"kg m^2"``, ``"m/s^2"``, ``"kN/m"``, ``"kg*m**2"``,
``"kg.m2/s2"`` (FMI's style). Everything after a ``/`` divides (``"m/s/s"`` is ``m/s^2``);
parentheses are ignored (``"kg/(m s)"``). Symbols:

* SI base and derived units, each with an SI prefix allowed (``T G M k h da d c m u µ n p``):
  ``m g s rad N J W Pa Hz A K mol cd`` (``km``, ``mm``, ``µm``, ``mg``, ``ms``, ``kN``,
  ``mrad``, ``MPa``, ``kW``, ...); ``kg`` is the base unit of mass;
* without prefixes: ``deg`` (also ``°``), ``rev`` (2 pi rad), ``rpm`` (rev/min), ``min``,
  ``h``, ``in`` (also ``inch``), ``ft``, ``bar``, ``%``, ``Nm`` (N m), ``1``.

Angles have a dimension of their own (``rad``, as in the FMU's unit definitions): ``"30 deg"``
is no length and ``"50 Hz"`` is no angular velocity (a cycle per second is ``2 pi rad/s``:
write ``"50 rev/s"`` or ``"3000 rpm"``).

A value with a unit (:func:`to_unit`) is a string ``"<number> <unit>"`` (``"250 g"``,
``"30 deg"``, ``"1.5e-3 m"``), an array in brackets followed by one unit
(``"(10, 0, 0) cm"``), a list or tuple whose items are numbers or such strings
(``("10 cm", 0, 0)``: plain numbers are in the parameter's own unit), or a ``pint`` quantity
(recognised by its ``magnitude`` and ``units``, converted through its base units: pint is
never imported here). Components convert their parameters once, when they are made
(:meth:`mbcomp.Param.coerce`); nothing converts units while a model runs.

Examples
--------
>>> to_unit("250 g", "kg"), to_unit("2 kN/m", "N/m"), to_unit("(10, 0, 0) cm", "m").tolist()
(0.25, 2000.0, [0.1, 0.0, 0.0])
>>> round(to_unit("30 deg", "rad"), 9), round(to_unit("60 rpm", "rad/s"), 9)
(0.523598776, 6.283185307)
>>> to_unit("30 deg", "kg")
Traceback (most recent call last):
...
mbcomp.modeling.units.UnitError: "30 deg" has unit deg (angle), expected kg (mass)
"""
from __future__ import annotations

import ast
import math
import re

import numpy as np

__all__ = ["UnitError", "parse_unit", "unit_exponents", "unit_text", "per_second", "dimension", "to_unit",
           "has_unit", "is_quantity", "example", "BASE"]

#: the base dimensions, in the order exponents are written (the FMU's ``BaseUnit`` attributes)
BASE = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")


def _u(factor=1.0, **exps):
    return factor, {b: exps[b] for b in BASE if exps.get(b)}


#: symbols an SI prefix may go with: (factor to SI, base exponents)
_PREFIXABLE = {
    "m": _u(m=1), "g": _u(1e-3, kg=1), "s": _u(s=1), "rad": _u(rad=1), "A": _u(A=1), "K": _u(K=1),
    "mol": _u(mol=1), "cd": _u(cd=1), "N": _u(kg=1, m=1, s=-2), "J": _u(kg=1, m=2, s=-2),
    "W": _u(kg=1, m=2, s=-3), "Pa": _u(kg=1, m=-1, s=-2), "Hz": _u(s=-1),
}
#: symbols without prefixes
_PLAIN = {
    "kg": _u(kg=1), "1": _u(), "%": _u(0.01), "deg": _u(math.pi / 180, rad=1), "°": _u(math.pi / 180, rad=1),
    "rev": _u(2 * math.pi, rad=1), "rpm": _u(2 * math.pi / 60, rad=1, s=-1), "min": _u(60.0, s=1),
    "h": _u(3600.0, s=1), "in": _u(0.0254, m=1), "inch": _u(0.0254, m=1), "ft": _u(0.3048, m=1),
    "bar": _u(1e5, kg=1, m=-1, s=-2), "Nm": _u(kg=1, m=2, s=-2),
}
_PREFIXES = {"T": 1e12, "G": 1e9, "M": 1e6, "k": 1e3, "h": 1e2, "da": 1e1, "d": 1e-1, "c": 1e-2, "m": 1e-3,
             "u": 1e-6, "µ": 1e-6, "\u03bc": 1e-6, "n": 1e-9, "p": 1e-12}

_NAMES = {  # dimension names, by their exponents
    (): "dimensionless", (("kg", 1),): "mass", (("m", 1),): "length", (("s", 1),): "time", (("rad", 1),): "angle",
    (("m", 1), ("s", -1)): "velocity", (("m", 1), ("s", -2)): "acceleration",
    (("s", -1), ("rad", 1)): "angular velocity", (("s", -2), ("rad", 1)): "angular acceleration",
    (("kg", 1), ("m", 1), ("s", -2)): "force", (("kg", 1), ("m", 2), ("s", -2)): "torque or energy",
    (("kg", 1), ("m", 2), ("s", -3)): "power", (("kg", 1), ("m", -1), ("s", -2)): "pressure",
    (("kg", 1), ("s", -2)): "stiffness", (("kg", 1), ("m", 2), ("s", -2), ("rad", -1)): "rotational stiffness",
    (("kg", 1), ("s", -1)): "damping", (("kg", 1), ("m", 2), ("s", -1), ("rad", -1)): "rotational damping",
    (("kg", 1), ("m", 2)): "moment of inertia", (("s", -1),): "frequency", (("m", 2),): "area",
    (("m", 3),): "volume",
}
#: a value with a unit of each dimension, for the fixes error messages suggest
_EXAMPLES = {"mass": "250 g", "length": "10 cm", "time": "20 ms", "angle": "30 deg", "velocity": "36 km/h",
             "angular velocity": "60 rpm", "angular acceleration": "90 deg/s^2", "force": "2 kN",
             "torque or energy": "1.5 kN m", "power": "1.5 kW", "pressure": "2 bar", "stiffness": "2 kN/m",
             "rotational stiffness": "5 N m/deg", "damping": "20 N s/mm", "rotational damping": "0.1 N m s/deg",
             "moment of inertia": "500 kg cm^2", "frequency": "50 Hz"}

_NUMBER = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$", re.S)
_ARRAY = re.compile(r"\s*([\(\[].*[\)\]])\s*(.*?)\s*$", re.S)
_TOKEN = re.compile(r"^([^\d\^\-]+|1)\^?(-?\d+)?$")


class UnitError(ValueError):
    """A unit that is unknown, or a value whose unit has the wrong dimension (the message says
    which and what was expected)."""


def known_symbols():
    """The unit symbols the parser knows, as one line for error messages.

    Examples
    --------
    >>> known_symbols().split(";")[0]
    'm, g, s, rad, A, K, mol, cd, N, J, W, Pa, Hz with SI prefixes (T, G, M, k, h, da, d, c, m, u, µ, n, p)'
    """
    pre = ", ".join(k for k in _PREFIXES if k != "\u03bc")
    return (f"{', '.join(_PREFIXABLE)} with SI prefixes ({pre}); "
            f"{', '.join(k for k in _PLAIN if k not in ('1', '°', 'inch'))}")


def _symbol(sym):
    if sym in _PLAIN:
        return _PLAIN[sym]
    if sym in _PREFIXABLE:
        return _PREFIXABLE[sym]
    for pre, f in _PREFIXES.items():
        if sym.startswith(pre) and sym[len(pre):] in _PREFIXABLE:
            factor, exps = _PREFIXABLE[sym[len(pre):]]
            return f * factor, exps
    raise UnitError(f"unknown unit {sym!r}; known: {known_symbols()}")


def parse_unit(text):
    """``(factor, exponents)`` of a unit text: the value of one of it in SI base units, and
    the base units' powers (``{"kg": 1, "m": 2, "s": -2}``; none for a pure number).

    Raises :class:`UnitError` naming an unknown symbol and listing the known ones.

    Examples
    --------
    >>> parse_unit("kN/m")
    (1000.0, {'kg': 1, 's': -2})
    >>> parse_unit("kg*m**2"), parse_unit("kg.m2/s2")[1]
    ((1.0, {'kg': 1, 'm': 2}), {'kg': 1, 'm': 2, 's': -2})
    """
    text = re.sub(r"\s*\*\*\s*", "^", str(text).strip())
    text = re.sub(r"\s*\^\s*", "^", text)
    for sep in "*·()":
        text = text.replace(sep, " ")
    parts = text.split("/")
    factor, exps = 1.0, {}
    for k, part in enumerate(parts):
        sign = 1 if k == 0 else -1
        tokens = part.replace(".", " ").split()
        if not tokens and (k > 0 or len(parts) > 1):
            raise UnitError(f"unit {text!r} has an empty {'denominator' if k else 'numerator'}")
        for tok in tokens:
            m = _TOKEN.match(tok)
            if not m:
                raise UnitError(f"unit {tok!r} is not a symbol with an integer power (write e.g. m^2)")
            f, e = _symbol(m.group(1))
            power = sign * int(m.group(2) or 1)
            factor *= f ** power
            for b, x in e.items():
                exps[b] = exps.get(b, 0) + x * power
    return factor, {b: exps[b] for b in BASE if exps.get(b)}


def unit_exponents(text):
    """The SI base-unit exponents of a unit that is SI (one of it is one in SI base units:
    ``"N m s/rad"``, ``"kg m^2"``, ``"m/s^2"``), or None when it is not one unit
    (``"m or rad"``), a symbol is unknown, or it is scaled (``"mm"``, ``"deg"``): what the
    FMU's unit definitions declare.

    Examples
    --------
    >>> unit_exponents("N m s/rad")
    {'kg': 1, 'm': 2, 's': -1, 'rad': -1}
    >>> unit_exponents("m or rad") is None, unit_exponents("deg") is None, unit_exponents("1")
    (True, True, {})
    """
    if not text or " or " in text:
        return None
    try:
        factor, exps = parse_unit(text)
    except UnitError:
        return None
    return exps if math.isclose(factor, 1.0, rel_tol=1e-12) else None


def unit_text(exps):
    """A unit text of base-unit exponents, as mbcomp writes units: ``"kg m^2/s^2"``; ``"1"``
    for none.

    Examples
    --------
    >>> unit_text({"rad": 1, "s": -2}), unit_text({"s": -1}), unit_text({})
    ('rad/s^2', '1/s', '1')
    """
    def word(b, e):
        return b if e == 1 else f"{b}^{e}"

    num = " ".join(word(b, e) for b, e in exps.items() if e > 0)
    den = " ".join(word(b, -e) for b, e in exps.items() if e < 0)
    return (num or "1") + (f"/{den}" if den else "")


def per_second(text):
    """The unit text of a rate of ``text`` (per second), in base units; None for None or a
    unit that is not SI.

    Examples
    --------
    >>> per_second("rad/s"), per_second("m"), per_second("m or rad")
    ('rad/s^2', 'm/s', None)
    """
    exps = unit_exponents(text) if text else None
    if exps is None:
        return None
    e = dict(exps)
    e["s"] = e.get("s", 0) - 1
    return unit_text({b: e[b] for b in BASE if e.get(b)})


def dimension(exps):
    """The name of a dimension (``"mass"``, ``"angular velocity"``), else its base units.

    Examples
    --------
    >>> dimension({"kg": 1, "s": -2}), dimension({"kg": 1, "m": 1, "s": -3})
    ('stiffness', 'kg m/s^3')
    """
    return _NAMES.get(tuple(exps.items()), unit_text(exps))


def example(unit):
    """A value with a unit of the dimension of ``unit`` (``'"250 g"'`` for ``"kg"``), for a
    fix to suggest; ``""`` when there is none or the unit is unknown.

    Examples
    --------
    >>> example("kg"), example("N m/rad"), example("m or rad")
    ('a mass such as "250 g"', 'a rotational stiffness such as "5 N m/deg"', 'a length such as "10 cm"')
    """
    for alt in str(unit).split(" or "):
        try:
            name = dimension(parse_unit(alt)[1])
        except UnitError:
            continue
        if name in _EXAMPLES:
            return f'a{"n" if name[0] in "aeiou" else ""} {name} such as "{_EXAMPLES[name]}"'
    return ""


def is_quantity(value):
    """Whether ``value`` looks like a pint quantity (duck typing: pint is never imported)."""
    return hasattr(value, "magnitude") and hasattr(value, "units") and hasattr(value, "to_base_units")


def has_unit(value):
    """Whether ``value`` carries a unit to convert: a string, a pint quantity, or a list, tuple
    or object array holding one.

    Examples
    --------
    >>> has_unit(("10 cm", 0, 0)), has_unit((0.1, 0, 0)), has_unit("30 deg")
    (True, False, True)
    """
    if isinstance(value, str) or is_quantity(value):
        return True
    if isinstance(value, (list, tuple)):
        return any(has_unit(v) for v in value)
    if isinstance(value, np.ndarray) and value.dtype.kind in "OUS":
        return any(has_unit(v) for v in value.ravel().tolist())
    return False


def _expected(unit):
    """``[(text, factor, exponents)]`` of each alternative of a declared unit (``"m or rad"``),
    None when one of them is unknown to the parser."""
    out = []
    for alt in str(unit).split(" or "):
        try:
            out.append((alt.strip(),) + parse_unit(alt))
        except UnitError:
            return None
    return out


def _scaled(number, factor):
    """``number * factor``; a decimal fraction as a division (``10 / 1e6``, not ``10 * 1e-6``:
    correctly rounded)."""
    inv = 1.0 / factor
    return number / round(inv) if factor < 1 and abs(inv - round(inv)) < 1e-9 * inv else number * factor


def _convert(number, given, shown, unit):
    """``number`` (float or array) in the unit text ``given`` as a value in ``unit``;
    ``shown``: the value as the messages quote it."""
    expected = _expected(unit)
    if expected is None:  # a unit mbcomp cannot read: only the same text passes, unchanged
        if given.strip() in ("", str(unit).strip()):
            return number
        raise UnitError(f"{shown} has unit {given}, but the parameter's unit {unit!r} is not one mbcomp can "
                        f"convert to")
    if not given.strip():
        return number
    try:
        factor, exps = parse_unit(given)
    except UnitError as exc:
        raise UnitError(f"{shown}: {exc}") from None
    for _text, f_exp, e_exp in expected:
        if exps == e_exp:
            return _scaled(number, factor / f_exp)
    want = " or ".join(f"{t} ({dimension(e)})" for t, _f, e in expected)
    raise UnitError(f"{shown} has unit {given} ({dimension(exps)}), expected {want}")


def _from_text(text, unit):
    m = _NUMBER.fullmatch(text)
    if m:
        return _convert(float(m.group(1)), m.group(2), f'"{text}"', unit)
    m = _ARRAY.fullmatch(text)
    if m:
        try:
            arr = np.array(ast.literal_eval(m.group(1)), dtype=float)
        except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
            raise UnitError(f"{text!r} is not a number or an array of numbers with a unit") from None
        return _convert(arr, m.group(2), f'"{text}"', unit)
    raise UnitError(f"{text!r} is not a number (nor a number with a unit, such as \"250 g\")")


def to_unit(value, unit):
    """``value`` in the unit ``unit`` (a declared parameter unit such as ``"kg"``, ``"N/m"``
    or ``"m or rad"``): strings and pint quantities converted, lists and tuples item by item,
    anything else returned as it is.

    Raises :class:`UnitError` for an unknown unit, a value whose unit has another dimension
    (naming both units), or a string that is no number.

    Examples
    --------
    >>> to_unit(("10 cm", 0, "2 mm"), "m"), to_unit(0.5, "kg"), to_unit("50 %", "1")
    ([0.1, 0, 0.002], 0.5, 0.5)
    """
    if isinstance(value, str):
        return _from_text(value, unit)
    if is_quantity(value):
        base = value.to_base_units()
        given = format(base.units, "~")
        try:  # its base units as mbcomp writes them
            given = unit_text(parse_unit(given)[1])
        except UnitError:
            pass
        return _convert(np.asarray(base.magnitude, dtype=float), given, f'"{value}" (pint)', unit)[()]
    if isinstance(value, (list, tuple)):
        return [to_unit(v, unit) for v in value]
    if isinstance(value, np.ndarray) and value.dtype.kind in "OUS":
        return [to_unit(v, unit) for v in value.tolist()]
    return value
