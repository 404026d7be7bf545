"""What the FMU's C knows of its variables by name: the names of every value reference, and
mbcomp's own parameter rules as a table the C checks.

:func:`c_names` writes ``VAR_NAME[]`` (value reference -> the variable's name) so the FMU's
messages say ``rod.m``, not "parameter 11". :func:`c_rules` writes the rules mbcomp applies to
the exported parameters (:class:`mbcomp.modeling.component.Param`'s ``check``): ``positive``,
``nonnegative``, ``nonzero`` (a vector: not all zero) and an inertia tensor's
(:func:`mbcomp.modeling.inertia.inertia_problem`: symmetric, non-negative principal moments,
each at most the sum of the other two; recognised as a checked 3x3 parameter in kg m^2) and a
rotation matrix's (a checked 3x3 parameter of unit 1: orthonormal, determinant +1); every
parameter must also be finite. The entries of a parameter the program baked in (its zeros)
enter a group rule as constants. ``fmu_rules.c`` checks a value against its own rules when
it is set and the group rules at ``ExitInitializationMode``, naming the variable, its value
and the rule (``rod.m = -2 kg: must be >= 0 (the mbcomp rule of RigidBody.m)``).

Examples
--------
>>> print(c_names(["bob.m", 'a"b']).strip())
#define NNAMES 2
static const char *const VAR_NAME[] = {"bob.m", "a\\"b"};
"""
from __future__ import annotations

import numpy as np

from ..modeling.free_joint import rotation_matrix_problem
from ..modeling.inertia import inertia_problem

__all__ = ["c_names", "c_rules", "c_string", "RULES"]

#: the rule kinds of the C table (fmu_rules.c's RULE_* constants), by Param.check text
RULES = {"positive": 1, "nonnegative": 2, "nonzero": 3}
INERTIA, ROTATION = 4, 5


def c_string(text):
    """``text`` as a C string literal (backslashes and quotes escaped)."""
    return '"' + str(text).replace("\\", "\\\\").replace('"', '\\"') + '"'


def c_names(names):
    """``VAR_NAME[]``: the name of every value reference ``0 .. len(names) - 1`` as C."""
    body = ", ".join(c_string(n) for n in names) or '""'
    return f"#define NNAMES {len(names)}\nstatic const char *const VAR_NAME[] = {{{body}}};\n"


def _owner(comp, name):
    """``Class.param`` of the class that declares the parameter ``name`` of ``comp``."""
    for cls in type(comp).__mro__:
        if name in vars(cls):
            return f"{cls.__name__}.{name}"
    return f"{type(comp).__name__}.{name}"


def _kind(par):
    """The rule kind of a Param (0: finiteness only): its ``check`` text, or the framework's
    check functions known by identity (an inertia tensor's, a rotation matrix's), never guessed
    from a unit or a name."""
    check = par.check
    if isinstance(check, str):
        return RULES.get(check, 0)
    return {inertia_problem: INERTIA, rotation_matrix_problem: ROTATION}.get(check, 0)


def c_rules(system, layout):
    """The rule table of the FMU's parameters ``layout`` (``(component, parameter, index)`` in
    value-reference order) as C: ``NRULE`` rules, each a kind, its entries (a value reference
    or -1 with the constant the program baked in), the parameter's name, its declaring class's
    rule name and unit."""
    comps = system.topology.flat.components
    groups = {}
    for vr, (path, name, idx) in enumerate(layout):
        groups.setdefault((path, name), {})[tuple(int(i) for i in idx) if idx is not None else ()] = vr
    kinds, starts, lens, names, owners, units, vrs, consts = [], [], [], [], [], [], [], []
    for (path, name), refs in groups.items():
        comp = comps[path]
        par = comp.params()[name]
        kind = _kind(par)
        if not kind:
            continue
        value = np.atleast_1d(np.asarray(getattr(system.P[path], name), dtype=float))
        shape = value.shape if par.shape else ()
        entries = [()] if shape == () else [tuple(int(i) for i in ix) for ix in np.ndindex(*shape)]
        kinds.append(kind)
        starts.append(len(vrs))
        lens.append(len(entries))
        names.append(f"{path}.{name}")
        owners.append(_owner(comp, name))
        units.append("" if par.unit in ("1", "", None) else par.unit)
        for ix in entries:
            vrs.append(refs.get(ix, -1))
            consts.append(float(value.reshape(shape)[ix]) if shape else float(value[0]))
    n = len(kinds)
    ints = lambda v: ", ".join(str(int(x)) for x in v) or "0"  # noqa: E731
    strs = lambda v: ", ".join(c_string(x) for x in v) or '""'  # noqa: E731
    return (f"#define NRULE {n}\n"
            f"static const int RULE_KIND[] = {{{ints(kinds)}}};\n"
            f"static const int RULE_START[] = {{{ints(starts)}}};\n"
            f"static const int RULE_LEN[] = {{{ints(lens)}}};\n"
            f"static const char *const RULE_NAME[] = {{{strs(names)}}};\n"
            f"static const char *const RULE_OWNER[] = {{{strs(owners)}}};\n"
            f"static const char *const RULE_UNIT[] = {{{strs(units)}}};\n"
            f"#define NRULE_ENTRIES {len(vrs)}\n"
            f"static const int RULE_VR[] = {{{ints(vrs)}}};\n"
            f"static const double RULE_CONST[] = {{{', '.join(repr(c) for c in consts) or '0.0'}}};\n")
