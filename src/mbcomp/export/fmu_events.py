"""FMU events (issue 33 item 1): what a model with modes carries into its FMU.

A model whose joints declare modes (:meth:`mbcomp.modeling.roles.Joint.modes`: unilateral
contacts, rigid end stops, an axis's stick/slip friction) exports to an FMU whose C (``fmu_events.c``) keeps the active set
(one mode per component), steps the system of the rows in force -- the assembled evaluation
program's mass matrix, forces and rows, the rows of closed contacts (the normal row and the
contact's rolling rows, velocity rows with velocity-level stabilization only) and engaged stops
held by the Lagrange index-1 solve with Baumgarte's gains, ``dq/dt`` the coordinate rates
(quaternions) -- and acts at events as the hybrid layer does (:mod:`mbcomp.hybrid.events`):
Newton's restitution with the impulse through the mass matrix along the contact's normal row or
the stop's row, the contact's rolling rows (perfectly rough) and the other rows in force held; a
rebound too small to rise ``REST_HEIGHT`` atol or a Zeno accumulation (``CHATTER`` shrinking
intervals) settles in the resting mode, the state then made consistent with its rows (positions
through the coordinate map, ``mbrt_increment``); a held row whose push falls through zero is
released. After every event closed contacts that would pull open, the most pulling first, and a
closing row that would pull at once stays open; a contact let go whose gap would accelerate into
its surface (the frictionless bicycle's wheel: perfectly rough rolling rows, Painleve-like) is
an error naming it.

A model with kinematic loops (a slider-crank whose slider hits an end stop, a four-bar with a
stop on a hinge) carries its loops' closures as rows always in force, before the modes' rows:
the independent ones of its cut joints' (and flange constraints') holonomic rows, as the
consistent initialization chose them (``system.row_mask``: a planar loop of 3-D joints has
dependent rows), and the velocity rows of nonholonomic joints that are no contacts with modes
(:func:`_permanent_rows`); accelerations, impacts and the projection after an event hold them,
and an importer's start values are moved onto them (the starts it set and the model's fixed
ones kept, the guesses moved; start values the rows cannot meet are an error naming them).

Event indicators, one per contact and two per stop or friction, are continuous: an open
contact's gap (m) or a closed one's normal force (N), a free stop's distance to each limit
(rad or m) or an engaged limit's push (N m or N), a stuck friction's margins to its break-away
force or a slipping one's speed. Every event is the indicator falling through zero. Model
Exchange acts in ``fmi3UpdateDiscreteStates``/``fmi2NewDiscreteStates`` and reports
``valuesOfContinuousStatesChanged``; Co-Simulation locates the events on its own DOP853's
dense output (the runtime's ``mbrt_dop853_events``) inside ``DoStep`` and acts the same way.

What is supported is read from the modes' declarations (:func:`components`); anything else
(contacts with friction, modes on a loop's cut joint, a contact, stop or friction whose row
depends on a loop's rows, drives, coordinates that move neither additively nor as quaternions)
is refused naming the component.

Examples
--------
>>> import mbcomp
>>> ball = mbcomp.load_model_file("models/bouncing_ball.py").build()
>>> p = plan(mbcomp.assemble(ball))
>>> p.enabled, p.indicators, p.components
(True, ['events.ground.normal'], ['ground'])
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..codegen.graph import CodegenError
from ..codegen.printers import Program
from ..codegen.toolchain import chunk
from ..codegen.tracer import FIELDS, trace
from ..modeling.events import AxisRow, ContactRow, End, EventRow, Impact, StickRow, Switch
from .rules import c_string

__all__ = ["plan", "components", "ending", "hybrid_outputs", "initial_state", "VR_EVENTS", "REST_HEIGHT", "CHATTER"]

#: the value reference of the first event indicator variable (FMI 3.0), far from the others
VR_EVENTS = 1 << 30
#: as the hybrid layer (mbcomp.hybrid.events): a rebound rising less than this times atol rests ...
REST_HEIGHT = 10.0
#: ... and this many successive shrinking intervals between a component's impacts are a Zeno accumulation
CHATTER = 30
#: Baumgarte gains (1/s) of the rows in force (simulate's defaults)
GAINS = (10.0, 10.0)

_NOT_YET = ("export without it (e.g. limits=None, unilateral=False, friction=None), or use a compliant stop or "
            "a regularized friction (flange forces, which the FMU carries)")


def _refuse(name, why):
    raise ValueError(f"cannot export {name}: {why}: not supported by the FMU's events yet -> {_NOT_YET}")


def _contact(system, e, modes):
    """``(holonomic row index, restitution, closed at start)`` of a frictionless one-sided
    contact's modes (its rolling rows, if any, held with the normal row while closed)."""
    if modes.slips:
        _refuse(e.name, f"the modes of {type(e.comp).__name__} ({type(modes).__name__}: a contact with friction, "
                        "friction=ContactFriction(...), rolling and sliding)")
    ok = (not modes.has_force and modes.start in ("open", "closed")
          and not modes.holds_rows("open") and modes.holds_rows("closed"))
    evs = modes.events(np.zeros(0), np.zeros(0), "open") if ok else []
    ok = ok and len(evs) == 1 and isinstance(evs[0][1], ContactRow) and evs[0][2] == -1
    ok = ok and not modes.events(np.zeros(0), np.zeros(0), "closed")
    ok = ok and modes.rows("closed") == [ContactRow(evs[0][1].name)] and modes.rows("open") == []
    act = modes.action(evs[0][0], "open") if ok else None
    ok = ok and isinstance(act, Impact) and act.engage == "closed" and modes.action("release", "closed") == Switch("open")
    if not ok:
        _refuse(e.name, f"the modes of {type(e.comp).__name__} ({type(modes).__name__}: modes other than a "
                        "one-sided contact's open/closed)")
    names = list(system.constraint_names(all_rows=True))
    row = f"{e.name}.{evs[0][1].name}"
    if row not in names:
        _refuse(e.name, f"a contact whose row {row!r} is not among the model's rows")
    return names.index(row), float(act.restitution), modes.start == "closed"


def _rolling_rows(system, contacts):
    """``[(first, count)]``: each contact's rolling rows (velocity constraints) among the
    evaluation's nonholonomic rows ``B`` (count 0: none), read from an evaluation at the start
    values; a ``ValueError`` naming the joints whose rolling rows are not a one-sided contact's."""
    if not system.nonholonomic:
        return [(0, 0)] * len(contacts)
    ev = system.evaluate(0.0, system.default_q(), np.zeros(system.nu))
    first, at = {}, 0
    for e, rows, _ in ev.local_nh:
        first[e.name] = (at, len(rows))
        at += len(rows)
    return [first.get(c[0], (0, 0)) for c in contacts]


def _permanent_rows(system, contacts, axes, init=None):
    """``(holonomic, nonholonomic)``: the rows always in force, as indices into the evaluation's
    ``Phi`` and ``B`` -- the loop closures (every holonomic row that is no one-sided contact's:
    cut joints, flange constraints, contacts without modes), only those the consistent
    initialization keeps as independent (``system.row_mask`` after :func:`initial_state`: a planar
    loop of 3-D joints has dependent rows, which would make the saddle matrix singular), and the
    velocity rows of the nonholonomic joints that are no contacts with modes. A ``ValueError``
    names a contact closed at the start whose row the initialization found dependent on them, and
    a contact, stop or friction (``axes``: ``(name, iq, iu, ...)``) whose row depends on them at
    the start (the loop already holds what it would hold); ``init``: the consistent start (made
    when not given)."""
    names = list(system.constraint_names(all_rows=True))
    mine = {c[0] for c in contacts}
    hol = [i for i, n in enumerate(names) if n.rsplit(".", 1)[0] not in mine]
    nh, at = [], 0
    if system.nonholonomic:
        for e, rows, _ in system.evaluate(0.0, system.default_q(), np.zeros(system.nu)).local_nh:
            nh += [] if e.name in mine else list(range(at, at + len(rows)))
            at += len(rows)
    if not hol and not nh:
        return [], []
    from ..assembly.manifold import rank
    from ..hybrid.contacts import initialize_in_modes

    init = initialize_in_modes(system, 0.0) if init is None else init
    mask = np.ones(len(names), bool) if init.row_mask is None else np.asarray(init.row_mask, bool)
    for name, row, _, closed in contacts:
        if closed and not mask[row]:
            _refuse(name, f"a contact closed at the start whose row {names[row]!r} depends on the model's other rows "
                          "(a loop's closure already holds it)")
    hol = [i for i in hol if mask[i]]
    ev = system.evaluate(0.0, init.q, init.u, masked=False)
    held = np.vstack((ev.C[hol], ev.B[nh]))
    r0 = rank(held)
    for name, row, _, _ in contacts:
        if rank(np.vstack((held, ev.C[row]))) <= r0:
            _refuse(name, f"a contact whose row {names[row]!r} depends on the loop's rows at the start")
    for name, _, iu, *_ in axes:
        if rank(np.vstack((held, np.eye(system.nu)[iu]))) <= r0:
            _refuse(name, "a stop or friction on a joint whose motion the loop's rows lock at the start")
    return hol, nh


def _c_permanent(hol, nh):
    """The C tables of the rows always in force (``fmu_events.c``'s ``hy_add_permanent``)."""
    def ints(name, vals):
        return f"static const int {name}[] = {{{', '.join(str(int(v)) for v in vals) or '0'}}};\n"

    return f"#define HY_NPR {len(hol)}\n#define HY_NPN {len(nh)}\n" + ints("HY_P_ROWS", hol) + ints("HY_P_NH", nh)


def _stop(system, e, modes):
    """``(q index, u index, lo, hi, restitution)`` of a joint's rigid end stops."""
    ok = (getattr(modes, "linear_events", False) and not modes.slips and not modes.has_force
          and modes.start == "free")
    rows = modes.event_rows("free") if ok else []
    ok = ok and [(r.name, r.of, r.index, r.sign, r.direction) for r in rows if isinstance(r, EventRow)] == [
        ("lo", "q", 0, 1.0, -1), ("hi", "q", 0, -1.0, -1)]
    if ok:
        lo, hi = rows[0].at, rows[1].at
        ok = (modes.rows("lo") == [AxisRow("lo", 1.0, lo)] and modes.rows("hi") == [AxisRow("hi", -1.0, hi)]
              and all(modes.action(k, "free") == Impact(modes.action(k, "free").restitution, engage=k)
                      for k in ("lo", "hi"))
              and modes.action("release", "lo") == Switch("free") == modes.action("release", "hi"))
    if not ok or e.drive or e.q.stop - e.q.start != 1:
        _refuse(e.name, f"the modes of {type(e.comp).__name__} ({type(modes).__name__}: stick/slip friction or modes "
                        "other than end stops' free/lo/hi)")
    return e.q.start, e.u.start, float(lo), float(hi), float(modes.action("lo", "free").restitution)


def _friction(system, e, modes):
    """``(q index, u index, static, kinetic, start mode: 0 stick, 1 slip+, 2 slip-)`` of a
    Coulomb friction's stick/slip modes on a 1-DOF joint's axis."""
    rows = modes.rows("stick") if modes.has_force and not modes.slips else []
    ok = (len(rows) == 1 and isinstance(rows[0], StickRow) and rows[0].sign == 1.0 and modes.start in
          ("stick", "slip+", "slip-") and modes.rows("slip+") == [] == modes.rows("slip-")
          and not modes.events(np.zeros(1), np.zeros(1), "stick")
          and modes.events(np.zeros(1), np.ones(1), "slip+") == [("stick", 1.0, -1)]
          and modes.events(np.zeros(1), -np.ones(1), "slip-") == [("stick", -1.0, 1)]
          and modes.action("break+", "stick") == Switch("slip+") and modes.action("break-", "stick") == Switch("slip-")
          and modes.action("stick", "slip+") == Switch("stick") == modes.action("stick", "slip-")
          and modes.force("stick") == 0.0 and modes.force("slip+") == -modes.force("slip-") <= 0.0)
    if not ok or e.drive or e.q.stop - e.q.start != 1:
        _refuse(e.name, f"the modes of {type(e.comp).__name__} ({type(modes).__name__}: a force or rows other than a "
                        "Coulomb friction's stick/slip+/slip-)")
    return (e.q.start, e.u.start, float(rows[0].limit), float(-modes.force("slip+")),
            ("stick", "slip+", "slip-").index(modes.start))


def _ends(e, modes):
    """Whether every event of the joint's start mode ends the run (:class:`End`; a latch): no
    rows, force or slip of its own, its events numbers of its own coordinates and speeds."""
    if modes.has_force or modes.slips or modes.rows(modes.start) or not modes.holds_rows(modes.start):
        return False
    if e.comp.tree_edge and e.q.stop == e.q.start:  # a joint cut to close a loop: no coordinates to watch
        return False
    evs = modes.events(np.zeros(e.q.stop - e.q.start), np.zeros(e.u.stop - e.u.start), modes.start)
    return bool(evs) and all(isinstance(v, (int, float, np.number)) and not isinstance(v, bool)
                             and isinstance(modes.action(n, modes.start), End) for n, v, _ in evs)


def ending(system):
    """``[(name, edge, modes)]``: the joints whose modes' every event ends the run (the FMU
    carries them as terminal events: :mod:`mbcomp.export.fmu_user_events`)."""
    out = []
    for e in system.topology.edges:
        modes = e.comp.modes(system.P[e.name]) if e.kind == "joint" else None
        if modes is not None and _ends(e, modes):
            out.append((e.name, e, modes))
    return out


def components(system):
    """``(contacts, stops, frictions)``: ``[(name, row, restitution, closed at start)]``,
    ``[(name, iq, iu, lo, hi, restitution)]`` and ``[(name, iq, iu, static, kinetic, start
    mode)]`` of the joints with modes; a ``ValueError`` naming any the FMU cannot carry."""
    contacts, stops, frictions = [], [], []
    for e in system.topology.edges:
        modes = e.comp.modes(system.P[e.name]) if e.kind == "joint" else None
        if modes is None or _ends(e, modes):  # a joint that only ends the run: a terminal event
            continue
        if e.comp.tree_edge and e.name in system.topology.cut:
            raise ValueError(f"cannot export {e.name}: the modes of {type(e.comp).__name__} ({type(modes).__name__}) "
                             f"act on the joint's own coordinate, but {e.name} is the cut joint closing a loop (no "
                             "coordinate of its own; mbcomp.simulate refuses it too) -> put them on another joint "
                             "of the loop")
        if e.comp.tree_edge and modes.has_force:
            frictions.append((e.name, *_friction(system, e, modes)))
        elif e.comp.tree_edge:
            stops.append((e.name, *_stop(system, e, modes)))
        else:
            contacts.append((e.name, *_contact(system, e, modes)))
    return contacts, stops, frictions


def plan(system, tolerance=1e-12, max_nodes=3_000_000, layout=None, user=None):
    """What the FMU of ``system`` carries for its events: ``enabled`` (the model has modes),
    ``components`` (names, contacts first), ``indicators`` (the event indicator variables'
    names), ``times`` (the variables of each component's last event time) and ``c`` (the
    defines, tables and evaluation program ``fmu_events.c`` reads); ``tolerance`` sets the
    resting height (``REST_HEIGHT`` x 1e-2 ``tolerance``: the FMU's atol); ``layout``, the
    right-hand side's parameter layout, makes restitutions and limits tunable parameters;
    ``user``: the user events' (:func:`mbcomp.export.fmu_user_events.plan`), carried by the
    same C after the components' (a model without modes then takes this path too)."""
    contacts, stops, frictions = components(system)
    user = user if user is not None else SimpleNamespace(indicators=[], times=[], c="")
    if not contacts and not stops and not frictions and not user.indicators:
        return SimpleNamespace(enabled=False, components=[], indicators=[], times=[], c="#define HYBRID 0\n")
    from ..codegen.engine import coordinate_map

    mine = {c[0] for c in contacts}
    permanent = _permanent_rows(system, contacts, stops + frictions)
    rolling = _rolling_rows(system, contacts)
    tr = trace(system, max_nodes, program="eval")
    seg = coordinate_map(system)
    if tr.drives or seg is None:
        _refuse(", ".join(sorted(mine | {s[0] for s in stops + frictions}) or user.indicators), "a model with drives, "
                "or coordinates the "
                "FMU cannot move along its speeds (a joint whose increment is neither additive nor a quaternion's)")
    if layout is not None and tr.layout != layout:
        raise CodegenError("the evaluation program's parameters differ from the right-hand side's")
    names = [c[0] for c in contacts] + [s[0] for s in stops] + [f[0] for f in frictions]
    seg = np.asarray(seg, int).reshape(-1, 4) if len(seg) else np.zeros((0, 4), int)
    return SimpleNamespace(enabled=True, components=names,
                           indicators=[f"events.{c[0]}.{_row_name(c[1], system)}" for c in contacts]
                           + [f"events.{s[0]}.{k}" for s in stops for k in ("lo", "hi")]
                           + [f"events.{f[0]}.{k}" for f in frictions for k in ("forward", "backward")]
                           + list(user.indicators),
                           times=[f"events.{n}.time" for n in names] + list(user.times),
                           c=user.c + _c(system, tr, (contacts, rolling, seg), stops, frictions, tolerance)
                           + _c_permanent(*permanent))


def _row_name(row, system):
    return list(system.constraint_names(all_rows=True))[row].rsplit(".", 1)[1]


def _tunable(layout, name, param, idx, value):
    """The parameter index (in the FMU's parameter vector) of ``name.param[idx]`` if it is a
    parameter with this value, else -1 (then the value is compiled in)."""
    for k, (path, pname, pidx) in enumerate(layout):
        if path == name and pname == param and (pidx is None if idx is None else
                                                 pidx is not None and tuple(int(i) for i in pidx) == idx):
            return k
    return -1


def _c(system, tr, contacts, stops, frictions, tolerance):
    contacts, rolling, seg = contacts
    groups = {"eval": tr.groups["eval"], "qrate": tr.groups["qrate"]}
    prog = Program(tr.graph, groups, guard_groups={k: tr.guard_groups[k] for k in groups})
    parts, n_work = prog.c_parts("eval", "mbhy_eval", chunk, n_parts=lambda n: 1)
    if not tr.qrate_identity:  # dq/dt = qrate(q, u): quaternions
        qparts, n_w = prog.c_parts("qrate", "mbhy_qrate", chunk, n_parts=lambda n: 1)
        parts, n_work = parts + qparts, max(n_work, n_w)
    off, offs = 0, {}
    for name in FIELDS:
        offs[name] = off
        off += int(np.prod(tr.shapes[name], dtype=int))
    lay = tr.layout

    def ints(name, vals):
        return f"static const int {name}[] = {{{', '.join(str(int(v)) for v in vals) or '0'}}};\n"

    def dbls(name, vals):
        return f"static const double {name}[] = {{{', '.join(repr(float(v)) for v in vals) or '0.0'}}};\n"

    c_par = [_tunable(lay, n, "restitution", None, e) for n, _, e, _ in contacts]
    s_par = [(_tunable(lay, n, "limits", (0,), lo), _tunable(lay, n, "limits", (1,), hi),
              _tunable(lay, n, "restitution", None, e)) for n, _, _, lo, hi, e in stops]
    return (f"#define HYBRID 1\n#define HY_NC {len(contacts)}\n#define HY_NS {len(stops)}\n"
            f"#define HY_NH {max(len(prog.hoisted), 1)}\n#define HY_NW {max(n_work, 1)}\n#define HY_NOUT {off}\n"
            f"#define HY_MH {tr.shapes['Phi'][0] if tr.shapes['Phi'] else 0}\n"
            f"#define HY_MN {tr.shapes['Psi'][0] if tr.shapes['Psi'] else 0}\n"
            f"#define HY_NCR {sum(1 + n for _, n in rolling)}\n#define HY_QRATE {int(not tr.qrate_identity)}\n"
            f"#define HY_NSEG {len(seg)}\n" + ints("HY_SEG", seg.ravel())
            + ints("HY_C_NH0", [r[0] for r in rolling]) + ints("HY_C_NHN", [r[1] for r in rolling])
            + f"static const char *const HY_C_NAME[] = {{{', '.join(c_string(c[0]) for c in contacts) or '0'}}};\n"
            f"#define HY_REST {REST_HEIGHT * 1e-2 * tolerance!r}\n#define HY_CHATTER {CHATTER}\n"
            f"#define HY_ALPHA {GAINS[0]!r}\n#define HY_BETA {GAINS[1]!r}\n#define HY_VR {VR_EVENTS}\n"
            + "".join(f"#define HY_OFF_{k.upper()} {offs[k]}\n"
                      for k in ("M", "f", "Phi", "Phid", "C", "cb", "B", "Bb", "Psi"))
            + ints("HY_C_ROW", [c[1] for c in contacts]) + dbls("HY_C_E", [c[2] for c in contacts])
            + ints("HY_C_EP", c_par) + ints("HY_C_CLOSED0", [c[3] for c in contacts])
            + ints("HY_S_IQ", [s[1] for s in stops]) + ints("HY_S_IU", [s[2] for s in stops])
            + dbls("HY_S_LO", [s[3] for s in stops]) + dbls("HY_S_HI", [s[4] for s in stops])
            + dbls("HY_S_E", [s[5] for s in stops]) + ints("HY_S_LOP", [p[0] for p in s_par])
            + ints("HY_S_HIP", [p[1] for p in s_par]) + ints("HY_S_EP", [p[2] for p in s_par])
            + f"#define HY_NF {len(frictions)}\n" + ints("HY_F_IQ", [f[1] for f in frictions])
            + ints("HY_F_IU", [f[2] for f in frictions]) + dbls("HY_F_STATIC", [f[3] for f in frictions])
            + dbls("HY_F_KINETIC", [f[4] for f in frictions]) + ints("HY_F_MODE0", [f[5] for f in frictions])
            + "\n".join(parts) + "\n" + prog.c_params("mbhy_eval_params") + "\n")


def initial_state(system):
    """The consistent start of a model with modes: contacts that start open initialized
    without their rows (:func:`mbcomp.hybrid.contacts.initialize_in_modes`); a ``ValueError``
    naming a contact, stop or friction whose row depends on a loop's rows (before a program
    holding them all is traced: it would be singular)."""
    from ..hybrid.contacts import initialize_in_modes

    init = initialize_in_modes(system, 0.0)
    contacts, stops, frictions = components(system)
    _permanent_rows(system, contacts, stops + frictions, init)
    return init


#: result columns whose values depend on the active set (accelerations, forces, multipliers,
#: the rows' residuals, the impacts' losses): not outputs of an FMU with events
_MODAL_UNITS = {"N", "N m", "m/s^2", "rad/s^2"}


def hybrid_outputs(system, variables):
    """The output columns ``variables`` (``(name, index)``) an FMU with events carries: those
    that do not depend on the active set (positions, velocities, orientations, energies,
    momenta); the output program evaluates the assembled system, whose contacts are closed."""
    from ..assembly.column_units import column_units

    units = column_units(system)
    return [(n, k) for n, k in variables
            if units.get(n) not in _MODAL_UNITS and not n.endswith(".der")
            and not n.startswith(("lambda.", "residual.")) and n != "energy.impacts"]
