"""The FMU's model description: variables, units, model structure, build description.

What :func:`mbcomp.export.fmu.export_fmu` writes into ``modelDescription.xml`` (FMI 3.0 and
2.0) and FMI 3.0's ``buildDescription.xml``: parameters with mbcomp's names, units with SI
base-unit exponents parsed from mbcomp's unit strings (:func:`unit_exponents`: mbcomp's one
unit parser, :mod:`mbcomp.modeling.units`), the states and their derivatives, the outputs
(units declared where the columns are made: :func:`mbcomp.assembly.column_units.column_units`,
as the results carry them), the inputs and the start values.

Examples
--------
>>> unit_exponents("N m"), unit_name(unit_exponents("N m"))
({'kg': 1, 'm': 2, 's': -2}, 'kg.m2/s2')
"""
from __future__ import annotations

from xml.sax.saxutils import escape

from ..assembly.column_units import column_units
from ..modeling.units import BASE as _BASE
from ..modeling.units import unit_exponents
from .fmu_events import VR_EVENTS

__all__ = ["unit_exponents", "unit_name", "named_unit", "output_name", "parameter_doc", "column_doc", "state_doc",
           "build_description", "model_description3", "model_description2"]

RUNTIME_C = ("mbrt_rk.c", "mbrt_check.c", "mbrt_events.c", "mbrt_dop853.c", "mbrt_mech.c", "mbrt_linalg.c")


def _version():
    """mbcomp's installed version (the ``generationTool`` of the model description)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("mbcomp")
    except PackageNotFoundError:
        return "(not installed)"


def unit_name(exps):
    """A unit name of the exponents in the FMI (Modelica) style: ``kg.m2/s2``; ``"1"`` for none."""
    num = ".".join(b + (str(e) if e != 1 else "") for b, e in exps.items() if e > 0)
    den = ".".join(b + (str(-e) if e != -1 else "") for b, e in exps.items() if e < 0)
    return (num or "1") + (f"/{den}" if den else "")


#: named units (SI derived units and the usual products) by their base-unit exponents: the
#: FMU declares these names, with their base units, instead of ``kg.m/s2``; torque and energy
#: share exponents: ``J`` where the unit text says J (energies, potentials), else ``N.m``
NAMED_UNITS = {
    (("kg", 1), ("m", 1), ("s", -2)): "N",
    (("kg", 1), ("m", 2), ("s", -2)): "N.m",
    (("kg", 1), ("m", 2), ("s", -3)): "W",
    (("kg", 1), ("s", -2)): "N/m",
    (("kg", 1), ("s", -1)): "N.s/m",
    (("kg", 1), ("m", 2), ("rad", -1), ("s", -2)): "N.m/rad",
    (("kg", 1), ("m", 2), ("rad", -1), ("s", -1)): "N.m.s/rad",
    (("kg", 1), ("m", -1), ("s", -2)): "Pa",
    (("kg", 1), ("m", 1), ("s", -1)): "N.s",
    (("kg", 1), ("m", 2), ("s", -1)): "N.m.s",
}


def named_unit(exps, text=None):
    """The FMU's name of the unit of exponents ``exps`` (``text``: the unit as written, which
    tells an energy from a torque).

    Examples
    --------
    >>> named_unit(unit_exponents("N")), named_unit(unit_exponents("N m")), named_unit(unit_exponents("J"), "J")
    ('N', 'N.m', 'J')
    >>> named_unit(unit_exponents("rad/s^2")), named_unit(unit_exponents("kg m^2"))
    ('rad/s2', 'kg.m2')
    """
    name = NAMED_UNITS.get(tuple(sorted(exps.items())))
    if name == "N.m" and text is not None and "J" in text.split():
        return "J"
    return name or unit_name(exps)


def _define(exps, defs, text=None):
    """The unit name of the exponents ``exps`` (None for None), added to the definitions ``defs``."""
    if exps is None:
        return None
    name = named_unit(exps, text)
    defs[name] = exps
    return name


def _text(text, defs):
    """The unit name of a unit text (None for none or an unreadable one), defined in ``defs``."""
    return _define(unit_exponents(text), defs, text) if text else None


def _per_second(exps):
    """The exponents of a unit per second (None for None): a rate's unit."""
    if exps is None:
        return None
    e = dict(exps)
    e["s"] = e.get("s", 0) - 1
    return {b: e[b] for b in _BASE if e.get(b)}


def _units(system, layout, state_units):
    """``(parameter units, state units, derivative units, definitions)``: unit names (None
    where unknown) and ``{name: exponents}`` of every unit used; ``state_units``: the states'
    unit texts (None: unknown)."""
    defs = {}
    par = [_text(parameter_doc(system, path, pname)[0], defs) for path, pname, _ in layout]
    sta = [_text(u, defs) for u in state_units]
    der = [_define(_per_second(unit_exponents(u)), defs) for u in state_units]
    return par, sta, der, defs


#: what an output column is, by the last parts of its name (``<joint>.f.x``: ``f``)
_COLUMN_DOCS = {"f": "reaction force of the joint, {0} component (frame_b axes)",
                "tau": "reaction torque of the joint, {0} component (frame_b axes)",
                "r": "position of the body's frame, {0} (world)", "v": "velocity of the body's frame, {0} (world)",
                "w": "angular velocity of the body, {0} (world)", "Q": "orientation quaternion of the body, {0}",
                "momentum": "linear momentum, {0} (world)", "angular_momentum": "angular momentum, {0} (world)",
                "energy": "energy of the system: {0}", "residual": "constraint residual: {0}"}


def column_doc(name):
    """A one-line description of the result column ``name`` (an FMU output).

    Examples
    --------
    >>> column_doc("crank_joint.f.x"), column_doc("j.w.der")
    ('reaction force of the joint, x component (frame_b axes)', 'rate of j.w')
    """
    parts = name.split(".")
    if parts[-1] == "der":
        return f"rate of {'.'.join(parts[:-1])}"
    if len(parts) >= 2 and parts[-2] in _COLUMN_DOCS:
        return _COLUMN_DOCS[parts[-2]].format(parts[-1])
    return f"result column {name} (mbcomp's output program)"


def state_doc(system, name):
    """A one-line description of the state ``name``: a joint's coordinate or speed, or an
    independent speed of D'Alembert's partition."""
    if name in system.q_names:
        return f"coordinate of joint {name.rsplit('.', 1)[0]} (a state)"
    if name in system.u_names:
        return f"speed of joint {name.rsplit('.', 1)[0]} (a state)"
    return "independent speed of the current partition (a state; the joint speeds are outputs)"


def _column_units(system):
    """``{column name: (SI exponents, unit text)}`` of the result columns whose unit is
    declared (:func:`mbcomp.assembly.column_units.column_units`)."""
    return {name: (unit_exponents(text), text) for name, text in column_units(system).items()}


def _minimum(system, path, name):
    """``' min="0"'`` for a parameter mbcomp requires to be >= 0 or > 0, else ``""``."""
    check = system.topology.flat.components[path].params()[name].check
    return ' min="0"' if check in ("positive", "nonnegative") else ""


def output_name(column, parameters):
    """The FMU variable of a result column: its own name, or ``<name>_out`` when a parameter
    has that name (an actuator's ``torque.tau``: FMI names are unique).

    Examples
    --------
    >>> output_name("torque.tau", {"torque.tau"}), output_name("j.phi", {"torque.tau"})
    ('torque.tau_out', 'j.phi')
    """
    return f"{column}_out" if column in parameters else column


def _outputs(system, outputs, pnames, defs):
    """``(FMU name, index, unit name, description)`` of the output columns ``outputs``
    (``(column, index)``), the units defined in ``defs``; one list for both standards."""
    units, taken = _column_units(system), set(pnames)
    return [(output_name(c, taken), k, _define(units[c][0], defs, units[c][1]) if c in units else None,
             column_doc(c)) for c, k in outputs]


def _start_names(system):
    """The start-value parameters' names and unit texts: ``start.<coordinate or speed>``."""
    names = list(system.q_names) + list(system.u_names)
    units = list(system.topology.q_units) + list(system.topology.u_units)
    return [f"start.{n}" for n in names], units


#: the FMU states' capabilities (fmu_state.c), on either interface: FMI 3.0's names ...
_STATES = ' canGetAndSetFMUState="true" canSerializeFMUState="true"'
#: ... and FMI 2.0's (its schema spells them "FMUstate")
_STATES2 = ' canGetAndSetFMUstate="true" canSerializeFMUstate="true"'

_TOL_DOC = "relative tolerance of the Co-Simulation integrator (DOP853; wins over the experiment's when set)"


def _start_rows3(system, starts, vr0, unit, defs, tolerance=1e-8):
    names, units = _start_names(system)
    tol = (f'    <Float64 name="solver.tolerance" valueReference="{vr0 + len(names)}" causality="parameter" '
           f'variability="fixed" start="{float(tolerance)!r}" description="{_TOL_DOC}"/>')
    return [tol] + [f'    <Float64 name="{escape(n)}" valueReference="{vr0 + k}" causality="parameter" variability="fixed" '
            f'start="{float(v)!r}" description="start value (projected onto the constraints at initialization)"'
            f'{unit(_text(u, defs))}/>' for k, (n, u, v) in enumerate(zip(names, units, starts))]


def _start_rows2(system, starts, vr0, unit, defs, tolerance=1e-8):
    names, units = _start_names(system)
    tol = (f'    <ScalarVariable name="solver.tolerance" valueReference="{vr0 + len(names)}" causality="parameter" '
           f'variability="fixed" initial="exact" description="{_TOL_DOC}"><Real start="{float(tolerance)!r}"/>'
           f'</ScalarVariable>')
    return [tol] + [f'    <ScalarVariable name="{escape(n)}" valueReference="{vr0 + k}" causality="parameter" '
            f'variability="fixed" initial="exact" description="start value (projected onto the constraints at '
            f'initialization)"><Real start="{float(v)!r}"{unit(_text(u, defs))}/></ScalarVariable>'
            for k, (n, u, v) in enumerate(zip(names, units, starts))]


def _experiment(experiment):
    stop, tol = experiment
    return f'  <DefaultExperiment startTime="0.0" stopTime="{stop!r}" tolerance="{tol!r}"/>\n'


def _unit_definitions(defs):
    rows = []
    for name, exps in sorted(defs.items()):
        attrs = " ".join(f'{b}="{e}"' for b, e in exps.items())
        rows.append(f'    <Unit name="{escape(name)}"><BaseUnit {attrs}/></Unit>' if attrs else
                    f'    <Unit name="{escape(name)}"/>')
    return "  <UnitDefinitions>\n" + "\n".join(rows) + "\n  </UnitDefinitions>\n" if rows else ""


def parameter_doc(system, path, name):
    """``(unit text, description)`` of the parameter ``name`` of the component at ``path``
    (as the component declares them; either may be None)."""
    comp = system.topology.flat.components[path]
    par = comp.params()[name]
    return par.unit, par.doc


def build_description(ident):
    """FMI 3.0's ``sources/buildDescription.xml`` of the model ``ident``: its C file and the
    runtime's, in C99.

    Examples
    --------
    >>> print(build_description("pendulum").splitlines()[3].strip())
    <SourceFileSet language="C99">
    """
    files = "".join(f'      <SourceFile name="{f}"/>\n' for f in (f"{ident}.c",) + RUNTIME_C)
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n<fmiBuildDescription fmiVersion="3.0">\n'
            f'  <BuildConfiguration modelIdentifier="{ident}">\n    <SourceFileSet language="C99">\n{files}'
            f'    </SourceFileSet>\n  </BuildConfiguration>\n</fmiBuildDescription>\n')


def model_description3(ident, name, system, layout, pnames, pv, states, y0, guid, kind, outputs=(), inputs=((), 0),
                       experiment=(1.0, 1e-12), state_units=(), starts=(), state_outputs=(), nominals=None,
                       dependencies=None, events=((), ())):
    """FMI 3.0's ``modelDescription.xml``: the parameters (value references ``0..NP-1``), the
    states and their derivatives, the time, the outputs, the inputs and the start values, in
    the order the generated C (``fmi3.c``) numbers them; ``kind`` is ``"me"``, ``"cs"`` or
    ``"both"``; ``state_outputs``: the indices of the states that are outputs too (the joint
    coordinates and speeds), ``nominals``: the states' nominal values. ``dependencies``: ``(der,
    out)`` of :func:`mbcomp.export.derivatives.structure` (known positions per state derivative
    and per output slot); given, the FMU declares its directional and adjoint derivatives and the
    dependencies of its outputs and derivatives (a state that is an output depends on itself).
    ``events``: the event indicators' and last event times' names
    (:func:`mbcomp.export.fmu_events.plan`). :func:`mbcomp.export.fmu.export_fmu` calls it
    with what it built."""
    nx, npar = len(states), len(pv)
    souts = sorted(state_outputs)
    nominal = [f' nominal="{float(v)!r}"' for v in nominals] if nominals is not None else [""] * nx
    upar, usta, uder, defs = _units(system, layout, state_units)
    defs["s"] = {"s": 1}

    def unit(u):
        return f' unit="{escape(u)}"' if u else ""

    rows = [f'    <Float64 name="time" valueReference="{npar + 2 * nx}" causality="independent" '
            f'variability="continuous" description="time" unit="s"/>']
    for k, ((path, pname, _), full) in enumerate(zip(layout, pnames)):
        text, doc = parameter_doc(system, path, pname)
        rows.append(f'    <Float64 name="{escape(full)}" valueReference="{k}" causality="parameter" variability="fixed" '
                    f'start="{pv[k]!r}" description="{escape(doc or "")} [{escape(text or "")}]"{unit(upar[k])}'
                    f'{_minimum(system, path, pname)}/>')
    for k, s in enumerate(states):
        rows.append(f'    <Float64 name="{escape(s)}" valueReference="{npar + k}" '
                    f'causality="{"output" if k in souts else "local"}" variability="continuous" initial="exact" '
                    f'start="{float(y0[k])!r}" description="{escape(state_doc(system, s))}"{unit(usta[k])}'
                    f'{nominal[k]}/>')
    for k, s in enumerate(states):
        rows.append(f'    <Float64 name="der({escape(s)})" valueReference="{npar + nx + k}" causality="local" '
                    f'variability="continuous" initial="calculated" derivative="{npar + k}" '
                    f'description="time derivative of {escape(s)}"{unit(uder[k])}/>')
    vr_out = npar + 2 * nx + 1
    for oname, k, uname, doc in _outputs(system, outputs, pnames, defs):
        rows.append(f'    <Float64 name="{escape(oname)}" valueReference="{vr_out + k}" causality="output" '
                    f'variability="continuous" initial="calculated" description="{escape(doc)}"{unit(uname)}/>')
    for k, inp in enumerate(inputs[0]):
        uname = _text(inp.unit, defs)
        rows.append(f'    <Float64 name="{escape(inp.name)}" valueReference="{vr_out + inputs[1] + k}" causality="input" '
                    f'variability="continuous" start="{inp.start!r}" description="{escape(inp.description)}"'
                    f'{unit(uname)}/>')
    rows += _start_rows3(system, starts, vr_out + inputs[1] + len(inputs[0]), unit, defs, experiment[1])
    der = [npar + nx + k for k in range(nx)]
    outs = [vr_out + k for _, k in outputs]
    vr_in = vr_out + inputs[1]
    dep_der, dep_out, provides = _dependencies3(dependencies, nx, npar, vr_in, len(der), [k for _, k in outputs])
    ev_rows, indicators, times = _event_rows(events)
    rows += [r3 for r3, _ in ev_rows]
    outs += times
    dep_out += [""] * len(times)  # the last event times: discrete, no dependencies declared
    interfaces = ""
    if kind in ("me", "both"):
        interfaces += (f'  <ModelExchange modelIdentifier="{ident}" needsCompletedIntegratorStep="true"'
                       f'{_STATES}{provides}/>\n')
    if kind in ("cs", "both"):
        interfaces += (f'  <CoSimulation modelIdentifier="{ident}" canHandleVariableCommunicationStepSize="true" '
                       f'hasEventMode="false"{_STATES}{provides}/>\n')
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n'
            f'<fmiModelDescription fmiVersion="3.0" modelName="{escape(name)}" instantiationToken="{guid}" '
            f'generationTool="mbcomp {_version()}" variableNamingConvention="structured">\n'
            + interfaces + _unit_definitions(defs) + _experiment(experiment)
            + '  <ModelVariables>\n' + "\n".join(rows) + '\n  </ModelVariables>\n  <ModelStructure>\n'
            + "".join(f'    <Output valueReference="{npar + k}"{_dependencies_attr([npar + k]) if provides else ""}/>\n'
                      for k in souts)
            + "".join(f'    <Output valueReference="{v}"{d}/>\n' for v, d in zip(outs, dep_out))
            + "".join(f'    <ContinuousStateDerivative valueReference="{v}"{d}/>\n' for v, d in zip(der, dep_der))
            + "".join(f'    <InitialUnknown valueReference="{v}"/>\n' for v in outs + der)
            + "".join(f'    <EventIndicator valueReference="{v}"/>\n' for v in indicators)
            + '  </ModelStructure>\n</fmiModelDescription>\n')


def _dependencies_attr(known):
    """``dependencies="..."`` of the knowns ``known`` (value references or indices); none for
    None (the unknown depends on every known)."""
    return "" if known is None else f' dependencies="{" ".join(str(k) for k in known)}"'


def _dependencies3(dependencies, nx, npar, vr_in, n_der, slots):
    """FMI 3.0's dependency attributes of the state derivatives and of the outputs (slots),
    and the capability attributes; empty without ``dependencies``."""
    if dependencies is None:
        return [""] * n_der, [""] * len(slots), ""
    der, out = dependencies

    def vr(pos):
        return npar + pos if pos < nx else vr_in + pos - nx

    def attr(d):
        return _dependencies_attr(None if d is None else [vr(p) for p in d])

    return ([attr(d) for d in der], [attr(out[k]) for k in slots],
            ' providesDirectionalDerivatives="true" providesAdjointDerivatives="true"')


def _interface(tag, ident, derivatives=False):
    files = "".join(f'      <File name="{f}"/>\n' for f in (f"{ident}.c",) + RUNTIME_C)
    extra = ' canHandleVariableCommunicationStepSize="true"' if tag == "CoSimulation" else ""
    extra += ' providesDirectionalDerivative="true"' if derivatives else ""
    return (f'  <{tag} modelIdentifier="{ident}" canNotUseMemoryManagementFunctions="true"{_STATES2}{extra}>\n'
            f'    <SourceFiles>\n{files}    </SourceFiles>\n  </{tag}>\n')


def model_description2(ident, name, system, layout, pnames, pv, states, y0, guid, kind, outputs=(), inputs=((), 0),
                       experiment=(1.0, 1e-12), state_units=(), starts=(), state_outputs=(), nominals=None,
                       dependencies=None, events=((), ())):
    """FMI 2.0's ``modelDescription.xml``: the variables of :func:`model_description3` (the
    same value references; the time is no variable in 2.0) with 2.0's model structure
    (``dependencies`` as there, as 1-based indices of the variables)."""
    nx, npar = len(states), len(pv)
    souts = sorted(state_outputs)
    nominal = [f' nominal="{float(v)!r}"' for v in nominals] if nominals is not None else [""] * nx
    upar, usta, uder, defs = _units(system, layout, state_units)

    def unit(u):
        return f' unit="{escape(u)}"' if u else ""

    rows = []
    for k, ((path, pname, _), full) in enumerate(zip(layout, pnames)):
        text, doc = parameter_doc(system, path, pname)
        rows.append(f'    <ScalarVariable name="{escape(full)}" valueReference="{k}" causality="parameter" '
                    f'variability="fixed" initial="exact" description="{escape(doc or "")} [{escape(text or "")}]">'
                    f'<Real start="{pv[k]!r}"{unit(upar[k])}{_minimum(system, path, pname)}/></ScalarVariable>')
    for k, s in enumerate(states):
        rows.append(f'    <ScalarVariable name="{escape(s)}" valueReference="{npar + k}" '
                    f'causality="{"output" if k in souts else "local"}" variability="continuous" initial="exact" '
                    f'description="{escape(state_doc(system, s))}"><Real start="{float(y0[k])!r}"{unit(usta[k])}'
                    f'{nominal[k]}/></ScalarVariable>')
    first_state = npar + 1  # 1-based index of the first state among the variables
    for k, s in enumerate(states):
        rows.append(f'    <ScalarVariable name="der({escape(s)})" valueReference="{npar + nx + k}" causality="local" '
                    f'variability="continuous" initial="calculated" description="time derivative of {escape(s)}">'
                    f'<Real derivative="{first_state + k}"{unit(uder[k])}/></ScalarVariable>')
    vr_out = npar + 2 * nx + 1  # the time's reference (NP + 2 NX) is not a variable in 2.0
    for oname, k, uname, doc in _outputs(system, outputs, pnames, defs):
        rows.append(f'    <ScalarVariable name="{escape(oname)}" valueReference="{vr_out + k}" causality="output" '
                    f'variability="continuous" initial="calculated" description="{escape(doc)}"><Real{unit(uname)}/>'
                    f'</ScalarVariable>')
    for k, inp in enumerate(inputs[0]):
        uname = _text(inp.unit, defs)
        rows.append(f'    <ScalarVariable name="{escape(inp.name)}" valueReference="{vr_out + inputs[1] + k}" '
                    f'causality="input" variability="continuous" description="{escape(inp.description)}">'
                    f'<Real start="{inp.start!r}"{unit(uname)}/></ScalarVariable>')
    rows += _start_rows2(system, starts, vr_out + inputs[1] + len(inputs[0]), unit, defs, experiment[1])
    der = [npar + nx + k + 1 for k in range(nx)]
    outs = [npar + 2 * nx + j + 1 for j in range(len(outputs))]  # 1-based indices among the variables
    ev_rows, indicators, times = _event_rows(events)
    if times:
        defs["s"] = {"s": 1}
    outs += [len(rows) + 1 + j for j, (_, r2) in enumerate(ev_rows) if 'causality="output"' in r2]
    rows += [r2 for _, r2 in ev_rows]
    unknowns = "\n".join(f'      <Unknown index="{i}"/>' for i in sorted(outs + der))
    dep_der, dep_out = [""] * nx, [""] * len(outs)
    if dependencies is not None:
        def index(pos):  # a state's or an input's 1-based index among the variables
            return npar + pos + 1 if pos < nx else npar + 2 * nx + len(outputs) + pos - nx + 1

        def attr(d):
            return _dependencies_attr(None if d is None else [index(p) for p in d])

        dep_der = [attr(d) for d in dependencies[0]]
        dep_out = [attr(dependencies[1][k]) for _, k in outputs]
    itself = (lambda i: _dependencies_attr([i])) if dependencies is not None else (lambda i: "")
    out_list = ("".join(f'      <Unknown index="{first_state + k}"{itself(first_state + k)}/>\n' for k in souts)
                + "".join(f'      <Unknown index="{i}"{d}/>\n' for i, d in zip(outs, dep_out)))
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n'
            f'<fmiModelDescription fmiVersion="2.0" modelName="{escape(name)}" guid="{guid}" '
            f'generationTool="mbcomp {_version()}" numberOfEventIndicators="{len(indicators)}" '
            'variableNamingConvention="structured">\n'
            + "".join(_interface(tag, ident, dependencies is not None)
                      for tag, k in (("ModelExchange", "me"), ("CoSimulation", "cs"))
                      if kind in (k, "both")) + _unit_definitions(defs) + _experiment(experiment)
            + '  <ModelVariables>\n' + "\n".join(rows) + '\n  </ModelVariables>\n'
            + '  <ModelStructure>\n' + (f'    <Outputs>\n{out_list}    </Outputs>\n' if out_list else '')
            + '    <Derivatives>\n' + "\n".join(f'      <Unknown index="{i}"{d}/>' for i, d in zip(der, dep_der))
            + '\n    </Derivatives>\n'
            f'    <InitialUnknowns>\n{unknowns}\n    </InitialUnknowns>\n  </ModelStructure>\n'
            f'</fmiModelDescription>\n')


_INDICATOR_DOC = ("event indicator (an event when it falls through zero): an open contact's gap (m) or a closed "
                  "one's normal force (N); a free stop's distance to its limit (rad or m) or an engaged one's push")
_TIME_DOC = "time of the component's last event (an impact or a release; -1 before any)"


def _event_rows(events):
    """``([(FMI 3.0 row, FMI 2.0 row)], indicator references, time references)`` of the event
    variables ``events`` (indicator names, last-event-time names), numbered from
    :data:`mbcomp.export.fmu_events.VR_EVENTS` as ``fmu_events.c`` reads them."""
    names, times = events
    rows, ind, tvr = [], [], []
    for k, n in enumerate(names):
        vr = VR_EVENTS + k
        ind.append(vr)
        rows.append((f'    <Float64 name="{escape(n)}" valueReference="{vr}" causality="local" variability="continuous" '
                     f'initial="calculated" description="{_INDICATOR_DOC}"/>',
                     f'    <ScalarVariable name="{escape(n)}" valueReference="{vr}" causality="local" '
                     f'variability="continuous" initial="calculated" description="{_INDICATOR_DOC}"><Real/>'
                     f'</ScalarVariable>'))
    for k, n in enumerate(times):
        vr = VR_EVENTS + len(names) + k
        tvr.append(vr)
        rows.append((f'    <Float64 name="{escape(n)}" valueReference="{vr}" causality="output" variability="discrete" '
                     f'initial="calculated" unit="s" description="{_TIME_DOC}"/>',
                     f'    <ScalarVariable name="{escape(n)}" valueReference="{vr}" causality="output" '
                     f'variability="discrete" initial="calculated" description="{_TIME_DOC}"><Real unit="s"/>'
                     f'</ScalarVariable>'))
    return rows, ind, tvr
