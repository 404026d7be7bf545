"""User events in an FMU (issue 33 item 1): ``export_fmu(model, path, events=[f])``.

A user event is what :func:`mbcomp.simulate` takes as ``events=[f]``: a scipy-style function
``f(t, y)`` of the time (s) and ``y = [q, u]`` (``system.q_names + system.u_names`` order)
with the attributes ``terminal`` (bool or a count of firings that ends the run) and
``direction`` (-1: fires falling through zero, +1: rising, 0: both). Each function is traced
into the FMU's C (:func:`check` then :func:`plan`, on the program tracer's ``t``, ``q``,
``u``) and becomes a continuous event indicator ``events.user.<name>`` (its value) and a
discrete output ``events.user.<name>.time`` (s, its last firing, -1 before any); the C
(``fmu_events.c``) fires it on a crossing in its direction, records the time and, for a
terminal one whose count is reached, ends the simulation (Model Exchange's
``terminateSimulation``, Co-Simulation's step stopping at the event).

A function that cannot be traced (``math.*``, ``float()``), or that branches on the time or
a state (a Python ``if`` on a traced value: the C would hold only the branch taken), is
refused naming it; so are bad ``terminal``/``direction`` attributes and duplicate names.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Prismatic, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> s = m.add("s", Prismatic(n=(0, 0, 1), s0=1.0)); b = m.add("b", PointMass(m=1.0))
>>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> def floor(t, y):
...     return y[0] - 0.5
>>> floor.terminal, floor.direction = True, -1
>>> specs = check([floor])
>>> [(e.name, e.direction, e.terminal) for e in specs]
[('floor', -1, 1)]
>>> p = plan(mbcomp.assemble(m), specs)
>>> p.indicators, p.times
(['events.user.floor'], ['events.user.floor.time'])
"""
from __future__ import annotations

import re
from types import SimpleNamespace

import numpy as np

from ..codegen.graph import CodegenError, Graph, Sym
from ..codegen.printers import Program
from ..codegen.toolchain import chunk
from ..codegen.tracer import trace_point
from .fmu_events import ending
from .rules import c_string

__all__ = ["check", "plan", "NONE_C"]

#: the C of no user events (fmu_events.c reads HY_NUE)
NONE_C = "#define HY_NUE 0\n"

_FIX = ("write it with numpy functions (np.sin, np.sqrt, ...) and plain arithmetic on t and y (no math.*, float(), "
        "no Python if on them), or run it with mbcomp.simulate(model, events=[f])")


def _code(f):
    """The code object a function runs (a bound method's, a callable object's ``__call__``)."""
    code = getattr(getattr(f, "__func__", f), "__code__", None)
    return code if code is not None else getattr(getattr(type(f), "__call__", None), "__code__", None)


def check(events, system=None):
    """The events' specifications ``[SimpleNamespace(fn, name, direction, terminal,
    indicator, time, code)]`` (``terminal``: the firings that end the run, 0: never): the user
    events ``events`` (None or a list of callables; a ``ValueError`` naming the function for a
    bad one), then, given ``system``, each event of the joints whose modes only end the run
    (:func:`mbcomp.export.fmu_events.ending`: a latch), terminal, traced from its
    ``Modes.events`` in its start mode."""
    specs = _user(events)
    for joint, e, modes in ending(system) if system is not None else []:
        nq = system.nq
        for k, (ev, _, direction) in enumerate(modes.events(np.zeros(e.q.stop - e.q.start),
                                                            np.zeros(e.u.stop - e.u.start), modes.start)):
            def fn(t, y, e=e, modes=modes, k=k, nq=nq):
                return modes.events(y[e.q], y[nq + e.u.start:nq + e.u.stop], modes.start)[k][1]
            specs.append(SimpleNamespace(fn=fn, name=f"{joint}.{ev}", direction=int(direction), terminal=1,
                                         indicator=f"events.{joint}.{ev}", time=f"events.{joint}.time",
                                         code=_code(type(modes).events)))
    return specs


def _user(events):
    if events is None:
        return []
    if callable(events) or isinstance(events, (str, bytes)):
        raise ValueError("events must be a list of functions f(t, y) -> fix: events=[f]")
    specs, seen = [], set()
    for k, f in enumerate(events):
        name = getattr(f, "__name__", None)
        if not callable(f):
            raise ValueError(f"events[{k}] = {f!r} is not a function f(t, y) -> fix: pass callables")
        if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
            raise ValueError(f"events[{k}]: its name {name!r} is no identifier (a lambda?) -> fix: define it with def "
                             "and a name, or set f.__name__ = 'my_event'")
        if name in seen:
            raise ValueError(f"events: two functions are named {name!r} (their variables events.user.{name} would "
                             "clash) -> fix: give each a distinct __name__")
        seen.add(name)
        direction = getattr(f, "direction", 0)
        if isinstance(direction, bool) or direction not in (-1, 0, 1):
            raise ValueError(f"event {name}: direction={direction!r} -> fix: -1 (falling through zero), "
                             "+1 (rising) or 0 (both)")
        term = getattr(f, "terminal", False)
        if isinstance(term, bool):
            count = int(term)
        elif isinstance(term, (int, np.integer)) and term > 0:
            count = int(term)
        else:
            raise ValueError(f"event {name}: terminal={term!r} -> fix: True/False, or a positive count of firings "
                             "that ends the run")
        specs.append(SimpleNamespace(fn=f, name=name, direction=int(direction), terminal=count,
                                     indicator=f"events.user.{name}", time=f"events.user.{name}.time", code=_code(f)))
    return specs


def _codes(code, out, name):
    out[code] = name
    for c in code.co_consts:
        if hasattr(c, "co_consts"):
            _codes(c, out, name)


def _traced(system, specs, max_nodes):
    """The graph and its outputs: each function on traced ``t``, ``y = [q, u]``."""
    t0, q0, u0 = trace_point(system)
    g = Graph(max_nodes)
    for e in specs:
        if e.code is not None:
            _codes(e.code, g.law_codes, f"event {e.name}")
    outs = []
    with g:
        q = [g.input("q", k, v) for k, v in enumerate(q0)]
        u = [g.input("u", k, v) for k, v in enumerate(u0)]
        t = g.input("t", 0, t0)
        y = np.array(q + u + [None], dtype=object)[:-1]
        for e in specs:
            try:
                v = e.fn(t, y)
                v = np.asarray(v, dtype=object)
                if v.size != 1:
                    raise TypeError(f"it returned {v.size} values, not one number")
                v = v.reshape(())[()]
                if not isinstance(v, Sym):
                    v = g.const(float(v))
            except CodegenError:
                raise
            except Exception as exc:  # noqa: BLE001 - re-raised naming the function
                raise ValueError(f"event {e.name}: cannot be traced into the FMU's C ({type(exc).__name__}: {exc}) "
                                 f"-> fix: {_FIX}") from None
            outs.append(v)
    return g, outs


def plan(system, specs, max_nodes=3_000_000):
    """What the FMU carries for the user events ``specs`` (:func:`check`): ``indicators`` and
    ``times`` (variable names; a joint's events share one) and ``c`` (``HY_NUE``, the tables
    ``HY_UE_DIR``, ``HY_UE_TERM``, ``HY_UE_NAME``, ``HY_UE_SLOT`` (each event's time among the
    ``HY_UE_NT`` times) and the program ``mbue_fun`` with ``mbue_params``)."""
    if not specs:
        return SimpleNamespace(indicators=[], times=[], c=NONE_C)
    g, outs = _traced(system, specs, max_nodes)
    prog = Program(g, {"ue": outs}, guard_groups={"ue": list(g.guards)})
    sites = sorted({g.guard_sites[gd] for gd in prog.state_guards if gd in g.guard_sites})
    if sites:
        where = "; ".join(f"{who} ({file.rsplit('/', 1)[-1]}:{line})" for who, file, line in sites)
        raise ValueError(f"cannot export {where}: it branches on the time or a state (an if, min/max or a comparison "
                         "on t or y): the FMU's C would hold only the branch taken at the trace point -> fix: write "
                         "it without branching (smooth functions, np.hypot, abs()), or run it with mbcomp.simulate")
    if prog.state_guards:
        raise ValueError(f"cannot export the events {', '.join(e.name for e in specs)}: a decision on the time or a "
                         f"state was taken while tracing them -> fix: {_FIX}")
    parts, n_work = prog.c_parts("ue", "mbue_fun", chunk, n_parts=lambda n: 1)

    def ints(name, vals):
        return f"static const int {name}[] = {{{', '.join(str(int(v)) for v in vals) or '0'}}};\n"

    times = list(dict.fromkeys(e.time for e in specs))
    c = (f"#define HY_NUE {len(specs)}\n#define HY_UE_NT {len(times)}\n#define HY_UE_NH {max(len(prog.hoisted), 1)}\n"
         f"#define HY_UE_NW {max(n_work, 1)}\n" + ints("HY_UE_DIR", [e.direction for e in specs])
         + ints("HY_UE_TERM", [e.terminal for e in specs]) + ints("HY_UE_SLOT", [times.index(e.time) for e in specs])
         + f"static const char *const HY_UE_NAME[] = {{{', '.join(c_string(e.name) for e in specs)}}};\n"
         + "\n".join(parts) + "\n" + prog.c_params("mbue_params") + "\n")
    return SimpleNamespace(indicators=[e.indicator for e in specs], times=times, c=c)
