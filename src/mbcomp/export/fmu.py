"""FMI export (first stage, issue 17): FMI 3.0 and 2.0 Model Exchange and Co-Simulation of
the Lagrange index-1 ODE.

What the FMU holds (see docs/design/fmu.md):

* ``sources/<id>.c``: the model's generated Lagrange program ``mbcomp_fun`` (accelerations
  by the recursive algorithms, loops closed by the multipliers with Baumgarte stabilization,
  the gains fixed at export), its parameter program in C (``mbcomp_params``: every nonzero
  numeric component parameter is an FMU parameter, checked against the decisions baked into
  the program), the FMU core ``fmu_core.c`` (an instance: parameters, state, evaluation, a
  Co-Simulation step) under the FMI 3.0 or 2.0 wrapper ``fmi3.c``/``fmi2.c`` (every function
  of the standard's header; those this FMU does not support log and return an error), the
  FMI 3.0 ``buildDescription.xml``, and, for Co-Simulation, the C
  runtime's DOP853 (``mbrt.h``, ``mbrt_rk.c``, ``mbrt_dop853.c``: error control at the
  experiment's tolerance, by default the model description's);
* ``binaries/x86_64-linux/<id>.so`` (3.0) or ``binaries/linux64/<id>.so`` (2.0) built with
  the system C compiler (libgcc linked statically, no dependency but libm and libc);
* ``modelDescription.xml``: the parameters (units, descriptions), the continuous states
  ``[q, u]`` with mbcomp's names and their derivatives (3.0: and the time); the
  instantiation token (2.0: guid) is a hash of the description.

* the output program: every result column that is not a state (reactions, multipliers, body
  positions, velocities and orientation quaternions, energies, residuals) as an output.

* the model's external inputs (:class:`mbcomp.Input`) as FMU inputs, held through a
  Co-Simulation step;
* for a model with constraints, the evaluation program and the runtime's ``mbrt_mech.c``:
  Co-Simulation projects ``[q, u]`` onto the constraint manifold after every accepted step.

* Model Exchange states of a model with constraints: D'Alembert's coordinates and independent
  speeds, the partition chosen again (and [q, u] projected) in Event Mode when it degrades or
  the positions drift (see docs/design/fmu.md).

* the start values of every coordinate and speed as parameters ``start.<name>``, projected
  onto the constraints at initialization when changed.

* FMU states: get, set, free, serialize and deserialize (``fmu_state.c``; both kinds, both
  versions): a Co-Simulation rollback and a state restored in another process continue bit for
  bit.
* what an importer sees (``fmu_rules.c``, :mod:`mbcomp.export.rules`): the FMI state machine
  enforced, mbcomp's parameter rules checked in C, messages naming variables, the model
  description's tolerance as the default, the joint coordinates and speeds as outputs, named
  units; a start value set on a state kept by the initialization (the model's guesses moved).
* exact directional and adjoint derivatives (states and inputs as knowns) and the
  ``<ModelStructure>`` dependencies (:mod:`mbcomp.export.derivatives`, ``fmu_derivatives.c``).
* a model with rigid end stops, frictionless one-sided contacts or stick/slip friction on an
  axis: event indicators, Event Mode's impacts and mode switches, Co-Simulation locating its
  events (:mod:`.fmu_events`); a contact's friction is refused, naming the contact.

Not yet: derivatives with respect to parameters, and of a model with modes (its FMU says so).

Examples
--------
>>> import pathlib, tempfile, mbcomp
>>> from mbcomp.export import export_fmu
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=2.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> info = export_fmu(m, pathlib.Path(tempfile.mkdtemp()) / "pendulum.fmu")
>>> info["states"], info["parameters"]          # the hinge axis's and rod's zeros are baked in
(['j.phi', 'j.w'], ['bob.m', 'j.n[3]', 'rod.r[2]', 'world.g[2]'])
"""
from __future__ import annotations

import hashlib
import os
import pathlib
import re
import shutil
import subprocess
import tempfile
import zipfile
from types import SimpleNamespace

import numpy as np

from ..assembly.initialization import fixed_starts, initialize
from ..assembly.system import assemble
from ..codegen.graph import CodegenError
from ..codegen.outputs import QUAT_C
from ..codegen.printers import Program
from ..codegen.toolchain import HEADER, c_compiler, chunk, compile_objects, runtime_directory
from ..codegen.tracer import param_vector, trace
from ..errors import ModelError, Problem
from ..modeling.model import Model
from . import fmu_events, fmu_user_events
from .description import (RUNTIME_C, build_description, model_description2, model_description3, output_name,
                          parameter_doc)
from .rules import c_names, c_rules, c_string

__all__ = ["export_fmu"]

HERE = pathlib.Path(__file__).resolve().parent
#: the C runtime's files the FMU carries: Co-Simulation steps with its DOP853
#: the C files of this package every FMU's sources carry (and the standard's fmi2.c or fmi3.c):
#: package data, so an installed mbcomp has them (tests/codegen/test_runtime_build.py checks the wheel)
FMU_SOURCES = ("fmu_core.c", "fmu_events.h", "fmu_events.c", "fmu_user_events.c", "fmu_state.c", "fmu_rules.c",
               "fmu_derivatives.c")
RUNTIME_DIR = pathlib.Path(__file__).resolve().parent.parent / "codegen" / "runtime"
RUNTIME = ("mbrt.h", "mbrt_rk_internal.h", "mbrt_check.h") + RUNTIME_C
#: Baumgarte gains (1/s) compiled into an FMU of a model with loops (as ``simulate``'s defaults)
ALPHA = BETA = 10.0


def _identifier(name):
    ident = re.sub(r"\W", "_", name)
    return ident if ident and not ident[0].isdigit() else f"m_{ident}"


def _c_array(name, values):
    vals = ", ".join(repr(float(v)) for v in values) if len(values) else "0.0"
    return f"static const double {name}[] = {{{vals}}};\n"


def _c_ints(name, values):
    vals = ", ".join(str(int(v)) for v in values) or "0"
    return f"static const int {name}[] = {{{vals}}};\n"


def _refuse_modes(system):
    """A ``ValueError`` naming the components with modes the FMU's events do not carry yet
    (contacts with friction: :mod:`.fmu_events`), which would otherwise run
    through as if they were not there; ``True`` when the model has modes the FMU carries
    (frictionless one-sided contacts, rolling or not, rigid end stops, stick/slip friction on an axis)."""
    return any(fmu_events.components(system))


def export_fmu(model, path, *, fmi="3.0", kind="both", params=None, outputs=None, name=None, stop_time=1.0,
               tolerance=1e-12, max_nodes=3_000_000, tunable="nonzero", derivatives=True, events=None):
    """Write ``model`` as an FMU at ``path``; returns what went in (a dict).

    Parameters
    ----------
    model : Model
    path : str or path-like
        The ``.fmu`` file to write.
    fmi : {"3.0", "2.0"}
        FMI version (default 3.0).
    kind : {"both", "me", "cs"}
        Model Exchange, Co-Simulation (the runtime's DOP853 at the experiment's tolerance),
        or both in one FMU (default).
    params : dict, optional
        Parameter values ``{"component.param": value}`` at export (tunable in the FMU too).
    outputs : list of str, optional
        Shell-style patterns (``"*.f.*"``, ``"energy.*"``) choosing the outputs among the
        result columns that are not states (default: all of them); a pattern that matches
        nothing is an error naming the columns.
    name : str, optional
        Model name (default: the file name); the model identifier is made from it.
    stop_time, tolerance : float
        The FMU's default experiment: end time (s) and the relative tolerance an importer's
        integrator is asked for (FMPy's CVODE on the slider-crank, 10 s: 3.7e-4 rad off at
        1e-8, 1.4e-7 at 1e-12; hence the default); also the Co-Simulation integrator's
        tolerance when the importer gives none.
    tunable : {"nonzero", "all"}
        Which numeric parameter entries are FMU parameters: the nonzero ones (default: the
        zeros are folded into the program, a smaller and faster one), or every entry (zeros and
        off-diagonal inertia terms too). The entries left out are listed in ``fixed``.
    derivatives : bool
        Carry the exact directional and adjoint derivatives and declare the dependencies
        (default); False builds a smaller FMU faster (Andrews: a third of the time and size,
        ``bench/fmu_derivatives.py``) whose derivative functions return an error.
    events : list of callables, optional
        User events as :func:`mbcomp.simulate` takes them (``f(t, y)``, ``y = [q, u]``, with
        ``terminal`` and ``direction``), traced into the FMU's C: the event indicators
        ``events.user.<name>`` and outputs ``events.user.<name>.time``; a terminal one ends the
        simulation (:mod:`.fmu_user_events`; a model with loops is refused).

    Returns
    -------
    dict
        ``states``, ``parameters``, ``outputs``, ``inputs`` (names), ``state_outputs`` (the
        states that are outputs too), ``fixed`` (``{parameter entry: why it is no FMU
        parameter}``), ``guid`` (the
        instantiation token), ``size`` (bytes), ``operations`` (of the programs), ``derivatives``,
        ``compiler``, ``model_identifier``.

    Raises
    ------
    ValueError
        A bad choice (version, kind, experiment, an output pattern matching nothing), no C
        compiler, or a law that cannot be traced into C (naming the component; the fix: a
        traceable expression or an :class:`mbcomp.Input`).
    ModelError
        A model the FMU cannot hold (a singular start, a drive law evaluated in Python).
    """
    cc, patterns = _check_request(model, fmi, kind, stop_time, tolerance, outputs)
    if tunable not in ("nonzero", "all"):
        raise ValueError(f"tunable={tunable!r}: use 'nonzero' (zeros folded into the program) or 'all'")
    path = pathlib.Path(path)
    name = name or path.stem
    ident = _identifier(name)
    system = assemble(model, params)
    specs = fmu_user_events.check(events, system)  # and the joints whose events only end the run
    hybrid = _refuse_modes(system) or bool(specs)
    init = fmu_events.initial_state(system) if hybrid else initialize(system)
    keep = _kept(system) if tunable == "all" else ()
    tr, prog, parts, n_work = _fun_program(system, max_nodes, keep)
    out_prog = _output_program(system, tr, max_nodes, keep)
    hy = fmu_events.plan(system, tolerance, max_nodes, layout=tr.layout,  # the events and modes (fmu_events.c)
                         user=fmu_user_events.plan(system, specs, max_nodes))
    mech = (SimpleNamespace(c="#define MECH 0\n", enabled=False) if hybrid
            else _projection(system, tr, max_nodes, keep))
    select = _selection(system, init, mech, kind)
    layout = tr.layout
    pv = param_vector(system, layout)
    y0 = np.concatenate((init.q, init.u))
    pnames = [f"{p}.{n}" if idx is None else f"{p}.{n}[{','.join(str(i + 1) for i in idx)}]" for p, n, idx in layout]
    states, x0, state_units = _states(system, init, select)
    names = _variable_names(pnames, states, out_prog, tr.inputs, system)
    out_prog.variables = [(n, k) for n, k in out_prog.variables if n not in set(states)]
    if hybrid:  # the output program evaluates the assembled system: only what no mode changes
        out_prog.variables = fmu_events.hybrid_outputs(system, out_prog.variables)
    if patterns is not None:
        out_prog.variables = _chosen(out_prog.variables, patterns)
    souts = _state_outputs(system, states, patterns)
    # a model with modes has other equations in each (fmu_events.c): no product programs of them yet
    deriv = (_derivatives(system, tr, out_prog, mech, select) if derivatives and not hybrid
             else SimpleNamespace(c="", structure=None))
    describe = model_description2 if fmi == "2.0" else model_description3
    xml = describe(ident, name, system, layout, pnames, pv, states, x0, guid="@GUID@", kind=kind,
                   outputs=out_prog.variables, inputs=(tr.inputs, out_prog.n_slots),
                   experiment=(float(stop_time), float(tolerance)), state_units=state_units, starts=y0,
                   state_outputs=souts, nominals=_state_nominals(system, tr.layout, pv, y0, select),
                   dependencies=deriv.structure, events=(hy.indicators, hy.times))
    guid = "{" + str(_uuid_of(xml)) + "}"
    xml = xml.replace("@GUID@", guid)
    model_c = _model_c(system, (tr, prog, parts, n_work), out_prog, mech, select, pv, y0, guid, fmi,
                       hy.c + deriv.c)
    model_c = _named(model_c, names, c_rules(system, layout), tolerance)
    _build(path, ident, fmi, cc, model_c, xml)
    outs = [output_name(n, set(pnames)) for n, _ in out_prog.variables]
    return dict(states=states, parameters=pnames, outputs=outs, state_outputs=[states[k] for k in souts],
                fixed=_fixed(system, layout),
                inputs=[i.name for i in tr.inputs], projects=mech.enabled and kind != "me",
                selects_states=select.enabled, derivatives=deriv.structure is not None, events=hy.indicators,
                guid=guid, size=os.path.getsize(path),
                operations=prog.n_ops("fun") + out_prog.n_ops, compiler=cc, model_identifier=ident)


def _model_c(system, fun, out_prog, mech, select, pv, y0, guid, fmi, extra_c=""):
    """The FMU's model.c: sizes and start values as defines and tables, the generated
    programs (``fun``: the right-hand side's trace, program, C parts and work size; outputs,
    projection, state selection, ``events``: :func:`.fmu_events.plan`'s), then the standard's
    functions (``fmi2.c``/``fmi3.c``)."""
    tr, prog, parts, n_work = fun
    loops = bool(system.topology.cut)
    return (HEADER + f"#define NQ {system.nq}\n#define NU {system.nu}\n"
            f"#define NP {len(pv)}\n#define NH {max(len(prog.hoisted), 1)}\n#define NW {max(n_work, 1)}\n"
            f"#define GUID \"{guid}\"\n#define ALPHA {ALPHA if loops else 0.0!r}\n#define BETA {BETA if loops else 0.0!r}\n"
            + f"#define NIN {len(tr.inputs)}\n" + _c_array("IN0", [i.start for i in tr.inputs])
            + _c_array("P0", pv) + _c_array("Y0", y0) + _c_array("NOMINAL", _nominals(system, tr.layout, pv, y0))
            + _start_freedom(system)
            + "\n".join(parts) + "\n" + prog.c_params("mbcomp_params") + "\n" + out_prog.c + mech.c + select.c
            + extra_c + f'\n#include "fmi{fmi[0]}.c"\n')


def _start_freedom(system):
    """The C tables of what the FMU's initialization may move (mbcomp's rule: fixed start values
    kept, guesses moved): ``PFREE0``/``VFREE0`` per speed direction (1: a guess), ``QDIR``/``QDIRN``
    the speed directions each coordinate's start value fixes (a joint whose coordinates are not
    its speeds, a quaternion's: all of the joint's), ``YNAME`` the names of ``[q, u]``."""
    qfix, ufix, _ = fixed_starts(system)
    qdir, qdirn = [0] * system.nq, [0] * system.nq
    for e in system.topology.edges:
        if e.kind != "joint" or e.q.stop <= e.q.start:
            continue
        same = e.q.stop - e.q.start == e.u.stop - e.u.start
        for i in range(e.q.start, e.q.stop):
            qdir[i], qdirn[i] = (e.u.start + i - e.q.start, 1) if same else (e.u.start, e.u.stop - e.u.start)
    names = list(system.q_names) + list(system.u_names)
    quoted = ", ".join(c_string(n) for n in names) or '""'
    flags = (f"static const unsigned char PFREE0[] = {{{', '.join(str(int(not f)) for f in qfix) or '0'}}};\n"
             f"static const unsigned char VFREE0[] = {{{', '.join(str(int(not f)) for f in ufix) or '0'}}};\n")
    return flags + _c_ints("QDIR", qdir) + _c_ints("QDIRN", qdirn) + f"static const char *const YNAME[] = {{{quoted}}};\n"


def _variable_names(pnames, states, out_prog, inputs, system):
    """The name of every value reference, in the order ``fmu_core.c`` numbers them (an output
    slot no variable declares: ``output <k>``)."""
    outs = [f"output {k}" for k in range(out_prog.n_slots)]
    taken = set(pnames)
    for n, k in out_prog.variables:
        outs[k] = output_name(n, taken)
    starts = [f"start.{n}" for n in list(system.q_names) + list(system.u_names)]
    return (list(pnames) + list(states) + [f"der({s})" for s in states] + ["time"] + outs
            + [i.name for i in inputs] + starts + ["solver.tolerance"])


def _named(model_c, names, rules, tolerance):
    """``model_c`` with the variables' names, the parameter rules and the default tolerance
    (the model description's) defined before the standard's functions are included."""
    at = model_c.rindex('#include "fmi')
    return model_c[:at] + f"#define DEFAULT_TOL {float(tolerance)!r}\n" + c_names(names) + rules + model_c[at:]


def _check_request(model, fmi, kind, stop_time, tolerance, outputs):
    """``(C compiler, output patterns or None)`` for a request; a clear error otherwise."""
    if fmi not in ("2.0", "3.0"):
        raise ValueError(f"fmi={fmi!r}: use '3.0' or '2.0'")
    if kind not in ("me", "cs", "both"):
        raise ValueError(f"kind={kind!r}: use 'me' (Model Exchange), 'cs' (Co-Simulation) or 'both'")
    if not (stop_time > 0 and 0 < tolerance < 1):
        raise ValueError(f"stop_time={stop_time!r}, tolerance={tolerance!r}: need stop_time > 0 and 0 < tolerance < 1")
    if not isinstance(model, Model):
        raise TypeError(f"export_fmu needs an mbcomp.Model, not {type(model).__name__}")
    cc = c_compiler()
    if cc is None:
        raise ValueError("export_fmu needs a C compiler (gcc or cc on PATH, or $CC) to build the FMU's binary")
    return cc, None if outputs is None else ([outputs] if isinstance(outputs, str) else list(outputs))


def _kept(system):
    """``(component, parameter)`` of every numeric parameter: all their entries FMU parameters."""
    from ..codegen.tracing import parameter_entries

    return tuple((path, name) for path, name, kind, val in parameter_entries(system)
                 if kind in ("number", "law") and isinstance(val, (float, np.floating, np.ndarray)))


def _fixed(system, layout):
    """``{entry name: why it is no FMU parameter}`` of the numeric parameter entries the
    program folds in (the export's log of what an importer cannot tune)."""
    from ..codegen.tracing import parameter_entries

    taken, fixed = {(p, n, None if i is None else tuple(int(k) for k in i)) for p, n, i in layout}, {}
    for path, name, kind, val in parameter_entries(system):
        if kind not in ("number", "law") or not isinstance(val, (float, np.floating, np.ndarray)):
            continue
        arr = np.asarray(val, dtype=float)
        for idx in ([None] if arr.ndim == 0 else list(np.ndindex(*arr.shape))):
            if (path, name, idx) not in taken:
                entry = f"{path}.{name}" + ("" if idx is None else f"[{','.join(str(k + 1) for k in idx)}]")
                fixed[entry] = "zero at export: folded into the program (export with tunable='all' to tune it)"
    return fixed


def _fun_program(system, max_nodes, keep=()):
    """The Lagrange right-hand side the FMU carries: ``(trace, Program, C parts, work size)``;
    a clear error for a law, a drive or a start position a program cannot hold."""
    try:
        tr = trace(system, max_nodes, program="fun", keep=keep)
    except CodegenError as exc:  # a law the program cannot hold: the FMU cannot either
        raise ValueError(f"the model cannot be exported: {exc} -> or give that value from outside the FMU as an "
                         "mbcomp.Input('name', ...)") from None
    if "fun" not in tr.groups:
        raise ModelError([Problem("(start)", "the start position is singular: no program can be generated there",
                                  "start the model away from the singular position")])
    if tr.drives:
        raise ModelError([Problem(", ".join(tr.drives), "the motion law cannot be traced into C, so an FMU cannot "
                                  "hold it", "write the law with numpy functions and plain arithmetic")])
    prog = Program(tr.graph, {"fun": tr.groups["fun"]}, guard_groups={"fun": tr.guard_groups["fun"]})
    _refuse_law_branches(tr.graph, prog.state_guards)
    parts, n_work = prog.c_parts("fun", "mbcomp_fun", chunk, n_parts=lambda n: 1)
    return tr, prog, parts, n_work


def _refuse_law_branches(graph, state_guards):
    """A ``ValueError`` naming every law that took a decision on the time or a state while it was
    traced (a Python ``if``, ``min``/``max``, ``abs`` of a comparison): the program holds the branch
    taken at the trace point only, so the FMU would fail (a guard) when the motion takes the other
    -- ``mbcomp.simulate`` goes on there by its numeric path, which an FMU does not carry. Decisions
    of mbcomp's own code (a pivot's sign in the recursive solve) are not a law's."""
    sites = sorted({graph.guard_sites[gd] for gd in state_guards if gd in graph.guard_sites})
    if sites:
        where = "; ".join(f"{law} ({file.rsplit('/', 1)[-1]}:{line})" for law, file, line in sites)
        raise ValueError(f"the model cannot be exported: the law {where} branches on the time or a state (an if, "
                         "min/max or a comparison on t, phi, w, s or v): the FMU's program would hold only the branch "
                         "taken at the start and fail when the motion takes the other -> write the law without "
                         "branching on them (smooth functions such as np.tanh(w / w0) for a sign, abs() and np.hypot "
                         "for sizes), or run it with mbcomp.simulate, whose numeric path follows every branch")


def _states(system, init, select):
    """``(names, start values, unit texts)`` of the Model Exchange states: ``[q, v]`` with
    D'Alembert's state selection (``v[k]``: the independent speeds, whose meaning changes with
    the partition: no unit), else ``[q, u]``."""
    topo = system.topology
    if select.enabled:
        k = len(select.ind)
        return (list(system.q_names) + [f"v[{j + 1}]" for j in range(k)],
                np.concatenate((init.q, init.u[select.ind])), list(topo.q_units) + [None] * k)
    return (list(system.q_names) + list(system.u_names), np.concatenate((init.q, init.u)),
            list(topo.q_units) + list(topo.u_units))


def _state_outputs(system, states, patterns):
    """The indices of the states that are outputs too: the joint coordinates and speeds (not
    D'Alembert's ``v[k]``, whose joint changes with the partition), those the output
    ``patterns`` choose when given."""
    from fnmatch import fnmatchcase

    columns = set(system.q_names) | set(system.u_names)
    return [k for k, s in enumerate(states)
            if s in columns and (patterns is None or any(fnmatchcase(s, pat) for pat in patterns))]


def _state_nominals(system, layout, pv, y0, select):
    """The nominal values of the states (``_nominals`` of ``[q, u]``, the independent speeds'
    of the first partition)."""
    nom = _nominals(system, layout, pv, y0)
    return np.concatenate((nom[:system.nq], nom[system.nq:][select.ind])) if select.enabled else nom


def _nominals(system, layout, pv, y0):
    """The states' nominal values from the model's scales: a length coordinate the model's
    length (the largest length parameter, m), its speed that length per second, an angle
    1 rad and its rate 1 rad/s (the importer's absolute tolerances scale with them); never
    below the start value's magnitude."""
    lengths = [abs(v) for (path, name, _), v in zip(layout, pv) if parameter_doc(system, path, name)[0] == "m"]
    L = max(lengths, default=1.0) or 1.0
    scale = {"m": L, "m/s": L, "rad": 1.0, "rad/s": 1.0, "1": 1.0}
    units = list(system.topology.q_units) + list(system.topology.u_units)
    return np.maximum(np.abs(y0), [scale.get(u, 1.0) for u in units])


#: the flags of an FMU's binary, its model file's and its runtime's objects alike (hidden
#: visibility: two FMUs in one process do not share the runtime's symbols)
FMU_FLAGS = ("-O2", "-fno-math-errno", "-fPIC", "-fvisibility=hidden")


def _runtime_objects(cc):
    """The object files of the runtime's C (``RUNTIME_C``) an FMU's binary links, compiled once
    per machine (the runtime's directory, keyed by the source, its headers' text, the flags and
    the compiler) instead of once per export: 0.7 s of gcc each time."""
    headers = "".join((RUNTIME_DIR / f).read_text() for f in RUNTIME if f.endswith(".h"))
    stamp = f"/* headers {hashlib.sha256(headers.encode()).hexdigest()} */\n"
    units = [(f"fmu_{f[:-2]}", stamp + (RUNTIME_DIR / f).read_text(), FMU_FLAGS + (f"-I{RUNTIME_DIR}",))
             for f in RUNTIME if f.endswith(".c")]
    return compile_objects(cc, units, runtime_directory())[0]


def _build(path, ident, fmi, cc, model_c, xml):
    """Lay out the FMU's files in a temporary folder, compile its binary, zip it to ``path``."""
    with tempfile.TemporaryDirectory(prefix="mbcomp-fmu-") as tmp:
        root = pathlib.Path(tmp)
        (root / "sources").mkdir()
        platform = "linux64" if fmi == "2.0" else "x86_64-linux"
        (root / "binaries" / platform).mkdir(parents=True)
        if fmi == "3.0":
            (root / "sources" / "buildDescription.xml").write_text(build_description(ident))
        (root / "sources" / f"{ident}.c").write_text(model_c)
        for f in FMU_SOURCES + (f"fmi{fmi[0]}.c",):
            shutil.copy(HERE / f, root / "sources" / f)
        for f in RUNTIME:
            shutil.copy(RUNTIME_DIR / f, root / "sources" / f)
        (root / "modelDescription.xml").write_text(xml)
        lib = root / "binaries" / platform / f"{ident}.so"
        cmd = [cc, *FMU_FLAGS, "-shared", "-static-libgcc", str(root / "sources" / f"{ident}.c"),
               *_runtime_objects(cc), "-o", str(lib), "-lm"]
        res = subprocess.run(cmd, capture_output=True, text=True, cwd=root / "sources")
        if res.returncode != 0:
            raise CodegenError(f"building the FMU's binary failed ({' '.join(cmd[:3])} ...):\n{res.stderr[-2000:]}")
        path.parent.mkdir(parents=True, exist_ok=True)
        with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
            for f in sorted(root.rglob("*")):
                if f.is_file():
                    z.write(f, f.relative_to(root).as_posix())


def _derivatives(system, tr, out_prog, mech, select):
    """The exact derivatives' product programs (C) and the ``<ModelStructure>`` dependencies
    (:mod:`mbcomp.export.derivatives`): ``structure`` is ``(der, out)``, known positions per
    state derivative and per output slot."""
    from .derivatives import derivative_programs, structure

    ev, res = (mech.tr, mech.res) if select.enabled else (None, [])
    nin = len(tr.inputs)
    c = derivative_programs(tr, out_prog.tr, ev, res, system.nq, system.nu, nin)
    st = structure(tr, out_prog.tr, ev, res, system.nq, system.nu, nin, select.enabled, out_prog.n_cols,
                   out_prog.n_rot)
    return SimpleNamespace(c=c, structure=(st.der, st.out))


def _chosen(variables, patterns):
    """The ``(name, index)`` of ``variables`` whose name matches one of the shell-style
    ``patterns``; ``ValueError`` for a pattern that matches none."""
    from fnmatch import fnmatchcase

    for pat in patterns:
        if not any(fnmatchcase(n, pat) for n, _ in variables):
            some = ", ".join(n for n, _ in variables[:8])
            raise ValueError(f"outputs pattern {pat!r} matches no result column -> choose among: {some}, ... "
                             f"({len(variables)} in all; e.g. '*.f.*' for joint forces, 'energy.*')")
    return [(n, k) for n, k in variables if any(fnmatchcase(n, pat) for pat in patterns)]


#: D'Alembert's state selection in Model Exchange: a new partition when |A_d^-1 A_i| exceeds
#: this (mbcomp.formulations.DAlembert's growth_max) ...
GROWTH_MAX = 4.0
#: ... or when the positions drift from the constraints by more than this (m or rad) and
#: DRIFT_RTOL times the experiment's tolerance (every event restarts the importer's integrator)
DRIFT, DRIFT_RTOL = 1e-9, 10.0


def _selection(system, init, mech, kind):
    """Model Exchange's states for a model with constraints: ``enabled``, the first partition
    ``dep``/``ind`` (pivoted QR at the start, as the D'Alembert formulation chooses it) and
    the core's defines (``SELECT``); disabled for open trees, Co-Simulation-only FMUs, or
    when the FMU cannot carry the evaluation program (``mech``)."""
    from ..assembly.manifold import SingularPartition, pivot_partition

    off = SimpleNamespace(enabled=False, ind=np.zeros(0, int), c="#define SELECT 0\n")
    if not mech.enabled or kind == "cs":
        return off
    ev = system.evaluate(0.0, init.q, init.u)
    if not ev.A.shape[0]:
        return off
    try:
        dep, ind = pivot_partition(ev.A)
    except SingularPartition:
        return off
    c = (f"#define SELECT 1\n#define MM {len(dep)}\n#define NI {len(ind)}\n#define GROWTH_MAX {GROWTH_MAX!r}\n"
         f"#define DRIFT {DRIFT!r}\n#define DRIFT_RTOL {DRIFT_RTOL!r}\n" + _c_ints("DEP0", dep) + _c_ints("IND0", ind))
    return SimpleNamespace(enabled=True, ind=np.asarray(ind, int), c=c)


def _projection(system, tr_fun, max_nodes, keep=()):
    """What a Co-Simulation step needs to project onto the constraint manifold after every
    accepted step (the runtime's ``mbrt_project``, as the compiled engine does): the
    evaluation program (constraints and their Jacobian) with its parameter program and
    qrate, the ``mbrt_mech`` layout. ``c`` defines ``MECH`` 0 (nothing to project: an open
    tree; or coordinates the C projection cannot move) or 1."""
    from ..codegen.engine import PROJECT_MAX_ITER, coordinate_map
    from ..codegen.tracer import FIELDS
    from ..assembly.manifold import ACCEPT_FACTOR, POSITION_TOL

    none = SimpleNamespace(c="#define MECH 0\n", enabled=False, tr=None, res=[])
    if not (system.topology.cut or any(e.kind == "joint" and not e.comp.tree_edge for e in system.topology.edges)):
        return none
    seg = coordinate_map(system)
    tr = trace(system, max_nodes, program="eval", keep=keep)
    if (seg is None or tr.drives or tr.layout != tr_fun.layout
            or [i.name for i in tr.inputs] != [i.name for i in tr_fun.inputs]):
        return none
    groups = {"eval": tr.groups["eval"], "qrate": tr.groups["qrate"]}
    prog = Program(tr.graph, groups, guard_groups={k: tr.guard_groups[k] for k in groups})
    parts, n_work = prog.c_parts("eval", "mbcomp_eval", chunk, n_parts=lambda n: 1)
    if not tr.qrate_identity:
        qparts, n_w = prog.c_parts("qrate", "mbcomp_qrate", chunk, n_parts=lambda n: 1)
        parts, n_work = parts + qparts, max(n_work, n_w)
    off, offs = 0, {}
    for name in FIELDS:
        offs[name] = off
        off += int(np.prod(tr.shapes[name], dtype=int))
    mh, mn = tr.shapes["Phi"][0] if tr.shapes["Phi"] else 0, tr.shapes["Psi"][0] if tr.shapes["Psi"] else 0
    rows = np.arange(mh) if system.row_mask is None else np.flatnonzero(system.row_mask)
    seg = np.asarray(seg, int).reshape(-1, 4) if len(seg) else np.zeros((0, 4), int)
    c = (f"#define MECH 1\n#define NH3 {max(len(prog.hoisted), 1)}\n#define NW3 {max(n_work, 1)}\n"
         f"#define NOUT3 {off}\n#define MH {mh}\n#define MN {mn}\n#define NROWS {len(rows)}\n#define NSEG {len(seg)}\n"
         f"#define QRATE {'NULL' if tr.qrate_identity else 'mbcomp_qrate'}\n"
         f"#define PROJ_TOL {POSITION_TOL!r}\n#define PROJ_ACCEPT {ACCEPT_FACTOR * POSITION_TOL!r}\n"
         f"#define PROJ_ITER {PROJECT_MAX_ITER}\n"
         + "".join(f"#define OFF_{k.upper()} {offs[k]}\n" for k in ("M", "f", "Phi", "Phid", "C", "cb", "B", "Bb", "Psi"))
         + _c_ints("MECH_ROWS", rows) + _c_ints("MECH_SEG", seg.ravel())
         + "\n".join(parts) + "\n" + prog.c_params("mbcomp_eval_params"))
    ev = tr.groups["eval"]
    res = [ev[offs["Phid"] + int(r)] for r in rows] + [ev[offs["Psi"] + r] for r in range(mn)]
    return SimpleNamespace(c=c, enabled=True, tr=tr, res=res)


def _output_program(system, tr_fun, max_nodes, keep=()):
    """The result columns the FMU computes as outputs (mbcomp's post-processing program: joint
    reactions, multipliers, body positions, velocities and orientations, energies, residuals):
    its C (with its parameter program and the quaternion of a rotation), the defines the core
    reads, and ``variables``: ``(name, index in the outputs)`` of every column, then every
    body's quaternion (the caller leaves out the states)."""
    tr = trace(system, max_nodes, program="outputs", baumgarte=True, hidden=False, keep=keep)
    ok = ("outputs" in tr.groups and not tr.drives and tr.layout == tr_fun.layout
          and [i.name for i in tr.inputs] == [i.name for i in tr_fun.inputs])
    if not ok:  # a drive the program does not hold, or a singular trace point: no outputs
        return SimpleNamespace(c=_NO_OUTPUTS, variables=[], n_ops=0, n_slots=0, tr=None, n_cols=0, n_rot=0)
    prog = Program(tr.graph, {"outputs": tr.groups["outputs"]}, guard_groups={"outputs": tr.guard_groups["outputs"]})
    parts, n_work = prog.c_parts("outputs", "mbcomp_outputs", chunk, n_parts=lambda n: 1)
    cols, rots = list(tr.output_names), list(tr.rotation_paths)
    variables = list(zip(cols, range(len(cols))))
    variables += [(f"{b}.Q.{c}", len(cols) + 4 * i + j) for i, b in enumerate(rots) for j, c in enumerate("wxyz")]
    defines = (f"#define NCOL {len(cols)}\n#define NROT {len(rots)}\n#define NH2 {max(len(prog.hoisted), 1)}\n"
               f"#define NW2 {max(n_work, 1)}\n")
    return SimpleNamespace(c=defines + "\n".join(parts) + "\n" + prog.c_params("mbcomp_outputs_params") + QUAT_C,
                           variables=variables, n_ops=prog.n_ops("outputs"), n_slots=len(cols) + 4 * len(rots),
                           tr=tr, n_cols=len(cols), n_rot=len(rots))


#: the output program of a model whose outputs cannot be traced: none
_NO_OUTPUTS = """#define NCOL 0
#define NROT 0
#define NH2 1
#define NW2 1
static int mbcomp_outputs(const double *q, const double *u, double t, const double *d, const double *h,
                          const double *p, double *w, double *out)
{ (void)q; (void)u; (void)t; (void)d; (void)h; (void)p; (void)w; (void)out; return 0; }
static int mbcomp_outputs_params(const double *pv, double *h) { (void)pv; (void)h; return 0; }
static void mbcomp_quat(const double *R, double *Q) { (void)R; (void)Q; }
"""


def _uuid_of(text):
    import uuid

    return uuid.UUID(hashlib.sha256(text.encode()).hexdigest()[:32])


