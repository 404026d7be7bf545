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

__all__ = ["unit_exponents", "unit_name", "output_name", "parameter_doc", "build_description", "model_description3",
           "model_description2"]

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


def _define(exps, defs):
    """The unit name of the exponents ``exps`` (None for None), added to the definitions ``defs``."""
    if exps is None:
        return None
    name = unit_name(exps)
    defs[name] = exps
    return name


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
    par = [_define(unit_exponents(parameter_doc(system, path, pname)[0]), defs) for path, pname, _ in layout]
    sta = [_define(unit_exponents(u), defs) for u in state_units]
    der = [_define(_per_second(unit_exponents(u)), defs) for u in state_units]
    return par, sta, der, defs


def _column_units(system):
    """``{column name: SI exponents}`` of the result columns whose unit is declared
    (:func:`mbcomp.assembly.column_units.column_units`)."""
    return {name: unit_exponents(text) for name, text in column_units(system).items()}


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
    """``(FMU name, index, unit name)`` of the output columns ``outputs`` (``(column,
    index)``), the units defined in ``defs``; one list for both standards."""
    units, taken = _column_units(system), set(pnames)
    return [(output_name(c, taken), k, _define(units.get(c), defs)) for c, k in outputs]


def _start_names(system):
    """The start-value parameters' names and unit texts: ``start.<coordinate or speed>``."""
    names = list(system.q_names) + list(system.u_names)
    units = list(system.topology.q_units) + list(system.topology.u_units)
    return [f"start.{n}" for n in names], units


_TOL_DOC = "relative tolerance of the Co-Simulation integrator (DOP853; wins over the experiment's when set)"


def _start_rows3(system, starts, vr0, unit, defs):
    names, units = _start_names(system)
    tol = (f'    <Float64 name="solver.tolerance" valueReference="{vr0 + len(names)}" causality="parameter" '
           f'variability="fixed" start="1e-08" description="{_TOL_DOC}"/>')
    return [tol] + [f'    <Float64 name="{escape(n)}" valueReference="{vr0 + k}" causality="parameter" variability="fixed" '
            f'start="{float(v)!r}" description="start value (projected onto the constraints at initialization)"'
            f'{unit(_define(unit_exponents(u), defs))}/>' for k, (n, u, v) in enumerate(zip(names, units, starts))]


def _start_rows2(system, starts, vr0, unit, defs):
    names, units = _start_names(system)
    tol = (f'    <ScalarVariable name="solver.tolerance" valueReference="{vr0 + len(names)}" causality="parameter" '
           f'variability="fixed" initial="exact" description="{_TOL_DOC}"><Real start="1e-08"/></ScalarVariable>')
    return [tol] + [f'    <ScalarVariable name="{escape(n)}" valueReference="{vr0 + k}" causality="parameter" '
            f'variability="fixed" initial="exact" description="start value (projected onto the constraints at '
            f'initialization)"><Real start="{float(v)!r}"{unit(_define(unit_exponents(u), defs))}/></ScalarVariable>'
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
                       experiment=(1.0, 1e-12), state_units=(), starts=(), events=((), ())):
    """FMI 3.0's ``modelDescription.xml``: the parameters (value references ``0..NP-1``), the
    states and their derivatives, the time, the outputs, the inputs and the start values, in
    the order the generated C (``fmi3.c``) numbers them; ``kind`` is ``"me"``, ``"cs"`` or
    ``"both"``; ``events``: the event indicators' and last event times' names
    (:func:`mbcomp.export.fmu_events.plan`). :func:`mbcomp.export.fmu.export_fmu` calls it
    with what it built."""
    nx, npar = len(states), len(pv)
    upar, usta, uder, defs = _units(system, layout, state_units)
    defs["s"] = {"s": 1}

    def unit(u):
        return f' unit="{escape(u)}"' if u else ""

    rows = [f'    <Float64 name="time" valueReference="{npar + 2 * nx}" causality="independent" '
            f'variability="continuous" description="time" unit="s"/>']
    for k, ((path, pname, _), full) in enumerate(zip(layout, pnames)):
        text, doc = parameter_doc(system, path, pname)
        rows.append(f'    <Float64 name="{escape(full)}" valueReference="{k}" causality="parameter" variability="fixed" '
                    f'start="{pv[k]!r}" description="{escape(doc or "")} [{escape(text or "")}]"{unit(upar[k])}/>')
    for k, s in enumerate(states):
        rows.append(f'    <Float64 name="{escape(s)}" valueReference="{npar + k}" causality="local" '
                    f'variability="continuous" initial="exact" start="{float(y0[k])!r}"{unit(usta[k])}/>')
    for k, s in enumerate(states):
        rows.append(f'    <Float64 name="der({escape(s)})" valueReference="{npar + nx + k}" causality="local" '
                    f'variability="continuous" initial="calculated" derivative="{npar + k}"{unit(uder[k])}/>')
    vr_out = npar + 2 * nx + 1
    for oname, k, uname in _outputs(system, outputs, pnames, defs):
        rows.append(f'    <Float64 name="{escape(oname)}" valueReference="{vr_out + k}" causality="output" '
                    f'variability="continuous" initial="calculated"{unit(uname)}/>')
    for k, inp in enumerate(inputs[0]):
        uname = _define(unit_exponents(inp.unit), defs)
        rows.append(f'    <Float64 name="{escape(inp.name)}" valueReference="{vr_out + inputs[1] + k}" causality="input" '
                    f'variability="continuous" start="{inp.start!r}" description="{escape(inp.description)}"'
                    f'{unit(uname)}/>')
    rows += _start_rows3(system, starts, vr_out + inputs[1] + len(inputs[0]), unit, defs)
    der = [npar + nx + k for k in range(nx)]
    outs = [vr_out + k for _, k in outputs]
    ev_rows, indicators, times = _event_rows(events)
    rows += [r3 for r3, _ in ev_rows]
    outs += times
    interfaces = ""
    if kind in ("me", "both"):
        interfaces += f'  <ModelExchange modelIdentifier="{ident}" needsCompletedIntegratorStep="true"/>\n'
    if kind in ("cs", "both"):
        interfaces += (f'  <CoSimulation modelIdentifier="{ident}" canHandleVariableCommunicationStepSize="true" '
                       f'hasEventMode="false"/>\n')
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n'
            f'<fmiModelDescription fmiVersion="3.0" modelName="{escape(name)}" instantiationToken="{guid}" '
            f'generationTool="mbcomp {_version()}" variableNamingConvention="structured">\n'
            + interfaces + _unit_definitions(defs) + _experiment(experiment)
            + '  <ModelVariables>\n' + "\n".join(rows) + '\n  </ModelVariables>\n  <ModelStructure>\n'
            + "".join(f'    <Output valueReference="{v}"/>\n' for v in outs)
            + "".join(f'    <ContinuousStateDerivative valueReference="{v}"/>\n' for v in der)
            + "".join(f'    <InitialUnknown valueReference="{v}"/>\n' for v in outs + der)
            + "".join(f'    <EventIndicator valueReference="{v}"/>\n' for v in indicators)
            + '  </ModelStructure>\n</fmiModelDescription>\n')


def _interface(tag, ident):
    files = "".join(f'      <File name="{f}"/>\n' for f in (f"{ident}.c",) + RUNTIME_C)
    extra = ' canHandleVariableCommunicationStepSize="true"' if tag == "CoSimulation" else ""
    return (f'  <{tag} modelIdentifier="{ident}" canNotUseMemoryManagementFunctions="true"{extra}>\n'
            f'    <SourceFiles>\n{files}    </SourceFiles>\n  </{tag}>\n')


def model_description2(ident, name, system, layout, pnames, pv, states, y0, guid, kind, outputs=(), inputs=((), 0),
                       experiment=(1.0, 1e-12), state_units=(), starts=(), events=((), ())):
    """FMI 2.0's ``modelDescription.xml``: the variables of :func:`model_description3` (the
    same value references; the time is no variable in 2.0) with 2.0's model structure."""
    nx, npar = len(states), len(pv)
    upar, usta, uder, defs = _units(system, layout, state_units)

    def unit(u):
        return f' unit="{escape(u)}"' if u else ""

    rows = []
    for k, ((path, pname, _), full) in enumerate(zip(layout, pnames)):
        text, doc = parameter_doc(system, path, pname)
        rows.append(f'    <ScalarVariable name="{escape(full)}" valueReference="{k}" causality="parameter" '
                    f'variability="fixed" initial="exact" description="{escape(doc or "")} [{escape(text or "")}]">'
                    f'<Real start="{pv[k]!r}"{unit(upar[k])}/></ScalarVariable>')
    for k, s in enumerate(states):
        rows.append(f'    <ScalarVariable name="{escape(s)}" valueReference="{npar + k}" causality="local" '
                    f'variability="continuous" initial="exact"><Real start="{float(y0[k])!r}"{unit(usta[k])}/>'
                    f'</ScalarVariable>')
    first_state = npar + 1  # 1-based index of the first state among the variables
    for k, s in enumerate(states):
        rows.append(f'    <ScalarVariable name="der({escape(s)})" valueReference="{npar + nx + k}" causality="local" '
                    f'variability="continuous" initial="calculated"><Real derivative="{first_state + k}"{unit(uder[k])}/>'
                    f'</ScalarVariable>')
    vr_out = npar + 2 * nx + 1  # the time's reference (NP + 2 NX) is not a variable in 2.0
    for oname, k, uname in _outputs(system, outputs, pnames, defs):
        rows.append(f'    <ScalarVariable name="{escape(oname)}" valueReference="{vr_out + k}" causality="output" '
                    f'variability="continuous" initial="calculated"><Real{unit(uname)}/></ScalarVariable>')
    for k, inp in enumerate(inputs[0]):
        uname = _define(unit_exponents(inp.unit), defs)
        rows.append(f'    <ScalarVariable name="{escape(inp.name)}" valueReference="{vr_out + inputs[1] + k}" '
                    f'causality="input" variability="continuous" description="{escape(inp.description)}">'
                    f'<Real start="{inp.start!r}"{unit(uname)}/></ScalarVariable>')
    rows += _start_rows2(system, starts, vr_out + inputs[1] + len(inputs[0]), unit, defs)
    der = [npar + nx + k + 1 for k in range(nx)]
    outs = [npar + 2 * nx + j + 1 for j in range(len(outputs))]  # 1-based indices among the variables
    ev_rows, indicators, times = _event_rows(events)
    if times:
        defs["s"] = {"s": 1}
    outs += [len(rows) + 1 + j for j, (_, r2) in enumerate(ev_rows) if 'causality="output"' in r2]
    rows += [r2 for _, r2 in ev_rows]
    unknowns = "\n".join(f'      <Unknown index="{i}"/>' for i in sorted(outs + der))
    out_list = "".join(f'      <Unknown index="{i}"/>\n' for i in outs)
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n'
            f'<fmiModelDescription fmiVersion="2.0" modelName="{escape(name)}" guid="{guid}" '
            f'generationTool="mbcomp {_version()}" numberOfEventIndicators="{len(indicators)}" '
            'variableNamingConvention="structured">\n'
            + "".join(_interface(tag, ident) for tag, k in (("ModelExchange", "me"), ("CoSimulation", "cs"))
                      if kind in (k, "both")) + _unit_definitions(defs) + _experiment(experiment)
            + '  <ModelVariables>\n' + "\n".join(rows) + '\n  </ModelVariables>\n'
            + '  <ModelStructure>\n' + (f'    <Outputs>\n{out_list}    </Outputs>\n' if outs else '')
            + '    <Derivatives>\n' + "\n".join(f'      <Unknown index="{i}"/>' for i in der) + '\n    </Derivatives>\n'
            f'    <InitialUnknowns>\n{unknowns}\n    </InitialUnknowns>\n  </ModelStructure>\n'
            f'</fmiModelDescription>\n')


_INDICATOR_DOC = ("event indicator (an event when it falls through zero): an open contact's gap (m) or a closed "
                  "one's normal force (N); a free stop's distance to its limit (rad or m) or an engaged one's push")
_TIME_DOC = "time of the component's last event (an impact or a release; -1 before any)"


def _event_rows(events):
    """``([(FMI 3.0 row, FMI 2.0 row)], indicator references, time references)`` of the event
    variables ``events`` (indicator names, last-event-time names), numbered from
    :data:`mbcomp.export.fmu_events.VR_EVENTS` as ``fmu_events.c`` reads them."""
    from .fmu_events import VR_EVENTS

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
