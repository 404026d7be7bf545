"""The assembled multibody system: coordinates, M(q), forces, constraints, reactions.

``assemble(model)`` validates the model, builds its :class:`~mbcomp.topology.Topology`
and returns a :class:`MultibodySystem`. The system evaluates, for given ``(t, q, u)``:

* ``M(q)`` (nu x nu) and the generalized forces ``f(q, u, t)`` (applied minus
  velocity-product terms), so that the tree obeys ``M du/dt = f - C^T lam``;
* the loop-closure constraints ``Phi(q, t)``, their velocity Jacobian ``C`` (``dPhi/dt =
  C u + c_t``) and bias ``c_b`` (``d2Phi/dt2 = C du/dt + c_b``);
* nonholonomic constraints ``B(q) u = b(q, t)`` (a rolling contact's no-slip rows; the
  rows are carried through every formulation);
* reactions of every joint, energies, and named outputs.

Parameters are runtime values: :meth:`MultibodySystem.with_params` returns a system with new
values that shares the topology; nothing is re-derived.

Evaluators
----------
``evaluate`` and ``q_rate`` are delegated to the system's *evaluator*: by default a
:class:`NumericEvaluator`, which runs the jet recursion (:meth:`MultibodySystem.evaluate_numeric`);
:func:`mbcomp.codegen.compile_system` returns the same system with an evaluator running a
generated program (``system.backend`` is then ``"python"`` or ``"c"``). Everything else --
kinematics, reactions, energies, ``increment`` -- is the system's own numeric code, and the
numeric evaluation stays reachable as ``evaluate_numeric`` and ``q_rate_numeric``.

Examples
--------
>>> import numpy as np
>>> from mbcomp import Model, assemble
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = Model(); w = m.add("world", World()); j = m.add("j", Revolute(n=(0, 0, 1)))
>>> L = m.add("L", FixedTranslation(r=(1, 0, 0))); b = m.add("b", PointMass(m=2.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, L.frame_a); m.connect(L.frame_b, b.frame_a)
>>> sys = assemble(m)
>>> ev = sys.evaluate(0.0, np.zeros(1), np.zeros(1))
>>> float(ev.M[0, 0]), float(ev.f[0])   # m l^2 and the gravity torque -m g l
(2.0, -19.62)
"""
from __future__ import annotations

import numpy as np

from ..modeling.component import PortRef
from ..errors import ModelError, Problem
from ..assembly.jets import FrameJet, as_array, is_traced, rigid_constraints
from ..geometry.kinematics import added, cross, cross_entries, entries, skew
from ..modeling.roles import FrameState, Joint
from ..assembly.topology import ROOT, Topology
from .body_stack import kane_terms
from .plan import topology_of
from .evaluation import Evaluation, Rows, completed, cut_rows
from .flange_rows import flange_rows, flange_starts, reflected_rotors, rotor_wrench, rotors

__all__ = ["assemble", "MultibodySystem", "Evaluation", "NumericEvaluator"]


def _dtype(t, q, u):
    """Array dtype of one evaluation: ``object`` when it is traced (object ``q``/``u`` or a
    traced ``t``, see :mod:`mbcomp.jets`), else ``float``; chosen once per call."""
    return object if q.dtype == object or u.dtype == object or is_traced(t) else float


def assemble(model, params=None):
    """Validate ``model`` and assemble it; ``params`` maps ``"component.param"`` to values."""
    flat = model.validate()
    return MultibodySystem(topology_of(flat), params)


class NumericEvaluator:
    """The default evaluator: the system's own numeric jet recursion.

    An evaluator is bound to one system and gives its ``evaluate(t, q, u, masked)`` and
    ``q_rate(q, u)``; ``backend`` names it, ``stats`` counts what it did, ``rebind(system)``
    is the same evaluator for a system with other parameter values (see
    :meth:`MultibodySystem.with_params`). A generated program
    (:class:`mbcomp.codegen.ProgramEvaluator`) follows the same contract.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> type(system.evaluator).__name__, system.backend
    ('NumericEvaluator', 'numeric')
    >>> float(system.evaluator.evaluate(0.0, np.zeros(1), np.zeros(1)).f[0])   # -m g
    -19.62
    """

    backend = "numeric"
    __slots__ = ("system",)

    def __init__(self, system):
        self.system = system

    #: what this evaluator offers beyond ``evaluate``/``q_rate`` (see
    #: :attr:`mbcomp.codegen.evaluator.ProgramEvaluator.capabilities`)
    capabilities = frozenset()

    def evaluate(self, t, q, u, masked=True):
        return self.system.evaluate_numeric(t, q, u, masked)

    def q_rate(self, q, u):
        return self.system.q_rate_numeric(q, u)

    def evaluate_rows(self, t, q, u):
        return self.system.evaluate_rows_numeric(t, q, u)

    def complete(self, rows, masked=True):
        return self.system.complete_numeric(rows, masked)

    def rebind(self, system, laws=False):
        return NumericEvaluator(system)

    @property
    def stats(self):
        return {"backend": self.backend}

    @property
    def source(self):
        raise AttributeError("a numeric system has no generated source: mbcomp.codegen.compile_system(system) "
                             "generates one")


class MultibodySystem:
    """Numeric evaluation of an assembled model (see module docstring).

    ``evaluate`` and ``q_rate`` go through :attr:`evaluator` (:class:`NumericEvaluator` unless
    the system was compiled, see :func:`mbcomp.codegen.compile_system`); ``backend`` says
    which: ``"numeric"``, ``"python"`` or ``"c"``.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World()); j = m.add("j", Revolute())
    >>> rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0))); bob = m.add("bob", PointMass(m=2.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> system.backend, float(system.evaluate(0.0, np.zeros(1), np.zeros(1)).M[0, 0])   # m l^2
    ('numeric', 2.0)
    >>> float(system.with_params({"bob.m": 3.0}).evaluate_numeric(0.0, np.zeros(1), np.zeros(1)).M[0, 0])
    3.0
    """

    def __init__(self, topology: Topology, params=None):
        self.topology = topo = topology
        self.P = {}
        over = {}
        owners = self.owners()
        for k, v in (params or {}).items():
            comp, _, pname = k.rpartition(".")
            if comp not in owners:
                raise ModelError([Problem(k, f"no component {comp!r} in the model",
                                          f"use one of: {', '.join(sorted(owners))}")],
                                 header="bad parameter override")
            over.setdefault(comp, {})[pname] = v
        for path, comp in owners.items():
            self.P[path] = comp.runtime_params(over.get(path))
        self.params = {k: dict(v) for k, v in over.items()}
        g = None
        if topo.gravity_source:
            g = topo.flat.components[topo.gravity_source].gravity(self.P[topo.gravity_source])
        self.g = np.zeros(3) if g is None else as_array(g)
        self.nq, self.nu = topo.nq, topo.nu
        self._edge = {e.name: e for e in topo.edges}
        self._nonholonomic = [e for e in topo.edges if e.kind == "joint" and e.comp.has_velocity_constraints]
        self.row_mask = None  # independent constraint rows, set by consistent initialization
        self.flange_s0 = flange_starts(self)  # geared axes' start coordinates: the gears' phase
        self._row_names = None
        self.evaluator = NumericEvaluator(self)
        self._check_static()

    def with_params(self, params):
        """A system with parameter values changed (topology shared, nothing re-derived; a
        compiled system keeps its program)."""
        merged = {f"{c}.{k}": v for c, d in self.params.items() for k, v in d.items()}
        merged.update(params)
        new = MultibodySystem(self.topology, merged)
        new.row_mask = self.row_mask
        new.evaluator = self.evaluator.rebind(new, laws=any(callable(v) for v in params.values()))
        return new

    def with_evaluator(self, make=None):
        """This system (same topology, parameter values and row mask) evaluated by
        ``make(system)``, or by the jet recursion (``make=None``: a numeric copy)."""
        new = self.variant()
        if make is not None:
            new.evaluator = make(new)
        return new

    def variant(self, *, topology=None, P=None, g=None, nonholonomic=None):
        """A numeric copy with its topology, parameter values ``P``, gravity ``g`` or held
        velocity rows (``nonholonomic``: edges) replaced -- for tracers (traced parameter values,
        stand-ins) and a hybrid run's rows in force (:mod:`mbcomp.hybrid`). Nothing is validated
        or re-derived; the evaluator is :class:`NumericEvaluator`; all else is shared (row mask,
        caches; the rows' names are found again when the cut joints changed)."""
        new = object.__new__(MultibodySystem)
        new.__dict__.update(vars(self), _row_names=self._row_names if topology is None
                            or list(topology.cut) == list(self.topology.cut) else None)
        for name, value in (("topology", topology), ("P", P), ("g", g), ("_nonholonomic", nonholonomic)):
            if value is not None:
                setattr(new, name, list(value) if name == "_nonholonomic" else value)
        new.evaluator = NumericEvaluator(new)
        return new

    @property
    def backend(self):
        """What evaluates the system: ``"numeric"`` (the jets), ``"python"`` or ``"c"`` (a
        generated program, :func:`mbcomp.codegen.compile_system`)."""
        return self.evaluator.backend

    @property
    def stats(self):
        """The evaluator's statistics (a generated program's build statistics and fallbacks)."""
        return self.evaluator.stats

    @property
    def source(self):
        """The generated program's source (compiled systems only)."""
        return self.evaluator.source

    def _check_static(self):
        topo = self.topology
        probs = [Problem(", ".join(topo.node_ports[n]), "frame is joined neither to the world nor to any body with mass",
                         "connect it to the mechanism or remove the components that use it") for n in topo.unreached]
        if probs:
            raise ModelError(probs)

    # --- names ----------------------------------------------------------------------------
    @property
    def q_names(self):
        return self.topology.q_names

    @property
    def u_names(self):
        return self.topology.u_names

    def edge(self, name):
        """Joint ``name``'s topology edge: its component ``comp``, frame nodes, slices ``q``, ``u``."""
        return self._edge[name]

    @property
    def nonholonomic(self):
        """The edges of the joints whose velocity rows (``B u = b``) the system holds."""
        return list(self._nonholonomic)

    def owners(self):
        """``{path: component}`` of every parameter owner: the model's components and the
        implicit joints the topology added (``"<body>.free"`` start values)."""
        topo = self.topology
        out = dict(topo.flat.components)
        out.update({e.name: e.comp for e in topo.edges if e.implicit})
        return out

    def row_names(self):
        """Names of every loop-closure row, mask not applied, keeping nothing on this system
        (structural: kept per structure by a compiled evaluator)."""
        memo = getattr(self.evaluator, "structure_memo", dict)()
        if self._row_names is None and "constraint_names" not in memo:
            ev = self.evaluate_rows_numeric(0.0, self.default_q(), np.zeros(self.nu))
            memo["constraint_names"] = tuple(f"{e.name}.{r}" for e, rows, _ in ev.local for r in rows)
        return list(self._row_names if self._row_names is not None else memo["constraint_names"])

    def constraint_names(self, all_rows=False):
        """Names ``"<cut joint>.<row>"`` of the loop-closure constraint rows."""
        self._row_names = self.row_names() if self._row_names is None else self._row_names
        names, mask = self._row_names, (None if all_rows else self.row_mask)
        return list(names) if mask is None else [n for n, k in zip(names, mask) if k]

    def default_q(self):
        q = np.zeros(self.nq)
        for e in self.topology.tree:
            if e.q.stop > e.q.start:
                q[e.q] = e.comp.start(self.P[e.name])[0]
        return q

    # --- evaluation -----------------------------------------------------------------------
    def _joint_motion(self, e, t, q, u):
        p = self.P[e.name]
        if e.kind == "ground":
            R, r = e.comp.pose(p)
            z = np.zeros((3, 0))
            return R, r, z, z, np.zeros(3), np.zeros(3), None, None, np.zeros(0), np.zeros(0)
        if e.drive:
            s, v, a = self.topology.flat.components[e.drive].motion(t, self.P[e.drive])
            qj = np.array([s])
            Hw, Hv = e.comp.motion(qj, p)
            R, r = e.comp.relative(qj, p)
            z = np.zeros((3, 0))
            return R, r, z, z, Hw[:, 0] * v, Hv[:, 0] * v, Hw[:, 0] * a, Hv[:, 0] * a, qj, np.array([v])
        qj, uj = q[e.q], u[e.u]
        R, r = e.comp.relative(qj, p)
        Hw, Hv = e.comp.motion(qj, p)
        # a joint whose Hw u, Hv u change at constant u (a rod's end on its sphere) declares their
        # rates, the relative bias accelerations (frame_a coordinates): Joint.motion_bias
        bw, bv = e.comp.motion_bias(qj, uj, p) if e.comp.has_motion_bias else (None, None)
        return R, r, Hw, Hv, Hw.dot(uj), Hv.dot(uj), bw, bv, qj, uj

    def kinematics(self, t, q, u):
        """Jets of every frame node (dict node -> :class:`~mbcomp.jets.FrameJet`)."""
        jets = {ROOT: FrameJet.ground(self.nu)}
        for e in self.topology.tree:
            jets[e.child] = self.child_jet(e, jets[e.parent], t, q, u, e.u)
        return jets

    def child_jet(self, e, pj, t, q, u, cols):
        """The jet of tree edge ``e``'s child frame from its parent's jet ``pj``; the edge's
        speeds are the Jacobian columns ``cols`` of ``pj`` (``e.u`` in the global jets; the
        recursive algorithms, :mod:`mbcomp.assembly.recursive`, pass jets of the edge's own
        width)."""
        if e.dof == 0:  # rigid offsets and ground frames: constant transforms
            R, r = e.comp.pose(self.P[e.name]) if e.kind == "ground" else e.comp.relative(None, self.P[e.name])
            return pj.offset(R, r) if e.forward else pj.offset(R.T, -(R.T.dot(r)))
        R, r, Hw, Hv, wr, vr, bw, bv, _, _ = self._joint_motion(e, t, q, u)
        if e.forward:
            return pj.through(R, r, Hw, Hv, cols, wr, vr, bw, bv)
        return pj.back_through(R, r, Hw, Hv, cols, wr, vr, bw, bv)

    def frame_state(self, J):
        """The :class:`~mbcomp.modeling.roles.FrameState` a component sees of frame jet ``J``."""
        return FrameState(J.r, J.R, J.v, J.w)

    def flange_state(self, root, jets, t, q, u):
        owner = self.topology.flange_owner[root]
        if owner[1] == "support":
            return 0.0, 0.0
        e = self._edge[owner[0]]
        if e.drive:
            s, v, _ = self.topology.flat.components[e.drive].motion(t, self.P[e.drive])
            return s, v
        if e.name in self.topology.cut:
            return e.comp.measure(jets[e.node_a], jets[e.node_b], self.P[e.name])
        s, v = q[e.q.start], u[e.u.start]
        return (s, v) if q.dtype == object or u.dtype == object else (float(s), float(v))

    def applied(self, t, q, u, jets):
        """Applied wrenches per frame node: dict node -> [f (3), tau (3)] (world, about origin)."""
        out = {}
        dt = _dtype(t, q, u)

        def add(node, f, tau):
            w = out.setdefault(node, [np.zeros(3), np.zeros(3)])
            w[0] = w[0] + f
            w[1] = w[1] + tau

        for path, comp, ports in self.topology.forces:
            states = {pn: self.frame_state(jets[n]) for pn, n in ports.items()}
            for pn, (f, tau) in comp.wrenches(t, states, self.P[path]).items():
                add(ports[pn], np.asarray(f, dt), np.asarray(tau, dt))
        for path, comp in self.topology.flange_elements:
            roots = {pn: self.topology.flange_of[PortRef(comp, pn, "flange")]
                     for pn, pt in comp.ports().items() if pt.kind == "flange"}
            states = {pn: self.flange_state(r, jets, t, q, u) for pn, r in roots.items()}
            for pn, flow in comp.flange_forces(t, states, self.P[path]).items():
                jname, which = self.topology.flange_owner[roots[pn]]
                if which != "axis":
                    continue  # the support is fixed to frame_a: the reaction is already applied there
                e = self._edge[jname]
                n = e.comp.axis_world(jets[e.node_a].R, self.P[e.name]) * flow
                z = np.zeros(3)
                if e.comp.axis_kind == "rotational":
                    add(e.node_b, z, n)
                    add(e.node_a, z, -n)
                else:
                    add(e.node_b, n, z)
                    add(e.node_a, -n, z)
        return out

    def body_inertia(self, comp, path, J):
        """``(m, rho, Iw)`` of body ``comp`` on jet ``J``: kg, centre of mass (m), inertia (kg m^2); world."""
        m, rc, I = comp.mass_properties(self.P[path])
        R = J.R
        return m, R.dot(rc), R.dot(I).dot(R.T)  # .dot: @'s products, a quarter of its overhead

    def evaluate(self, t, q, u, masked=True) -> Evaluation:
        """Mass matrix, forces and constraints at ``(t, q, u)``, from the system's evaluator
        (``masked``: only the independent constraint rows, see ``row_mask``)."""
        return self.evaluator.evaluate(t, q, u, masked)

    def evaluate_rows(self, t, q, u) -> Rows:
        """The loop-closure rows alone at ``(t, q, u)``, every row (:class:`~mbcomp.assembly.evaluation.Rows`):
        ``Phi, Phid, C, cb`` of ``evaluate(t, q, u, masked=False)`` bit for bit, without the mass
        matrix and forces where the evaluator can (its ``evaluate_rows``), else from that
        evaluation. For Newton closures (:mod:`mbcomp.assembly.initialization`)."""
        rows = getattr(self.evaluator, "evaluate_rows", None)
        return rows(t, q, u) if rows is not None else Rows.of(self.evaluate(t, q, u, masked=False))

    def evaluate_from(self, rows, masked=True) -> Evaluation:
        """``evaluate(rows.t, rows.q, rows.u, masked)`` bit for bit, reusing what ``rows`` (this
        system's :meth:`evaluate_rows`) holds: its unmasked evaluation, or the jets and rows
        the evaluator completes (its ``complete``)."""
        if rows.evaluation is None:
            return self.evaluator.complete(rows, masked)
        return self.evaluate(rows.t, rows.q, rows.u, masked) if masked else rows.evaluation

    def q_rate(self, q, u):
        """``dq/dt`` from the speeds ``u`` (quaternion kinematics where needed), from the evaluator."""
        return self.evaluator.q_rate(q, u)

    def _inertia_terms(self, jets, nu, dt):
        """``M`` and the inertial and gravity part of ``f`` summed over the bodies (Kane's form)."""
        if dt is float:  # every body's products at once (body_stack: the same bits as the loop below)
            M, f = kane_terms(self, jets, nu)
        else:  # traced: body by body (the generated program's structure)
            M, f = np.zeros((nu, nu), dt), np.zeros(nu, dt)
        for path, comp, node in self.topology.bodies if dt is not float else ():
            J = jets[node]
            m, rho, Iw = self.body_inertia(comp, path, J)
            Jw, w, rh = J.Jw, entries(J.w), entries(rho)  # 3-vectors' entries, products by .dot: jets.py
            Jv = J.Jv - skew(rh).dot(Jw)
            a = np.array(added(J.a, cross_entries(J.alpha, rh), cross_entries(w, cross_entries(w, rh))))
            M += m * (Jv.T.dot(Jv)) + Jw.T.dot(Iw).dot(Jw)
            f += Jv.T.dot(m * (self.g - a)) - Jw.T.dot(Iw.dot(J.alpha) + cross(w, Iw.dot(J.w)))
        for node, Iw, gyro in rotors(self, jets):  # rotors on joint axes: bodies of inertia J n n^T
            J = jets[node]
            M = M + J.Jw.T @ Iw @ J.Jw
            f = f - J.Jw.T @ rotor_wrench(J, Iw, gyro)
        for k, Jr in reflected_rotors(self):  # on a joint's own rate: J u_k^2 / 2, no force
            M[k, k] = M[k, k] + Jr
        return M, f

    def evaluate_numeric(self, t, q, u, masked=True) -> Evaluation:
        """Mass matrix, forces and constraints at ``(t, q, u)`` by the jet recursion."""
        dt = _dtype(t, q, u)
        jets = self.kinematics(t, q, u)
        M, f = self._dynamics(t, q, u, jets, dt)  # before the rows: a traced program's order
        return completed(self, cut_rows(self, t, q, u, jets, dt), M, f, masked, dt)

    def evaluate_rows_numeric(self, t, q, u) -> Rows:
        """The loop-closure rows alone at ``(t, q, u)`` (every row) by the jet recursion: those
        of ``evaluate_numeric`` bit for bit (the same code), without ``M`` and ``f``."""
        return cut_rows(self, t, q, u, self.kinematics(t, q, u), _dtype(t, q, u))

    def complete_numeric(self, rows, masked=True) -> Evaluation:
        """``evaluate_numeric`` at the point of ``rows`` (:meth:`evaluate_rows_numeric`'s),
        bit for bit, its jets and rows taken from ``rows``."""
        dt = _dtype(rows.t, rows.q, rows.u)
        return completed(self, rows, *self._dynamics(rows.t, rows.q, rows.u, rows.jets, dt), masked, dt)

    def _dynamics(self, t, q, u, jets, dt):
        """``M`` and ``f``: the bodies' inertia terms and the applied wrenches."""
        M, f = self._inertia_terms(jets, self.nu, dt)
        for node, (F, T) in self.applied(t, q, u, jets).items():
            J = jets[node]
            f += J.Jv.T.dot(F) + J.Jw.T.dot(T)
        return M, f

    def cut_constraints(self, jets, t=0.0, q=None):
        """``(edge, [(row name, ScalarJet)])`` of every cut joint at the frames' ``jets`` (a
        cut ground frame: its six rigid rows), unmasked, in the order of ``topology.cut``, then
        of every flange constraint (a :class:`~mbcomp.assembly.flange_rows.FlangeRows` over its
        ``nodes``; these need the time ``t`` and coordinates ``q``)."""
        for name in self.topology.cut:
            e = self._edge[name]
            p = self.P[name]
            a, b = jets[e.node_a], jets[e.node_b]
            if e.kind == "ground":
                R0, r0 = e.comp.pose(p)
                yield e, rigid_constraints(a, b, R0, r0)
            else:
                yield e, e.comp.constraints(a, b, p)
        for fr in self.topology.flange_rows:
            yield fr, flange_rows(self, fr, jets, t, q)

    def velocity_constraints(self, jets):
        """``(edge, [(row name, ScalarJet)])`` of every joint with nonholonomic rows."""
        for e in self._nonholonomic:
            yield e, e.comp.velocity_constraints(jets[e.node_a], jets[e.node_b], self.P[e.name])

    def q_rate_numeric(self, q, u):
        """``dq/dt`` from the speeds ``u`` by the joints' own kinematics."""
        qd = np.empty(self.nq)
        for e in self.topology.tree:
            if e.q.stop > e.q.start:
                qd[e.q] = e.comp.q_rate(q[e.q], u[e.u], self.P[e.name])
        return qd

    def increment(self, q, du):
        """Coordinates moved by ``du`` along the speeds (for Newton corrections); the joints that
        keep :meth:`Joint.increment <mbcomp.modeling.roles.Joint.increment>` (``q + du``: hinges,
        sliders) in one addition on numbers."""
        qn = q.copy()
        memo = self.__dict__.get("_increments")
        if memo is None or memo[0] is not self.topology:  # per topology: which joints add
            tree = [e for e in self.topology.tree if e.q.stop > e.q.start]
            add = [e for e in tree if type(e.comp).increment is Joint.increment]
            own = [e for e in tree if type(e.comp).increment is not Joint.increment]
            memo = self._increments = (self.topology, np.array([i for e in add for i in range(e.q.start, e.q.stop)], int),
                                       np.array([i for e in add for i in range(e.u.start, e.u.stop)], int), own)
        plain = q.dtype == float and getattr(du, "dtype", None) == float
        if plain:
            qn[memo[1]] = q[memo[1]] + du[memo[2]]
        for e in memo[3] if plain else self.topology.tree:
            if e.q.stop > e.q.start:
                qn[e.q] = e.comp.increment(q[e.q], du[e.u], self.P[e.name])
        return qn

    def normalize(self, q):
        """Coordinates with every quaternion scaled to unit length."""
        return self.increment(q, np.zeros(self.nu))

    # --- post-processing ------------------------------------------------------------------
    def energies(self, ev: Evaluation):
        """``(kinetic, potential)`` in J; potential of gravity (zero at the world origin) and
        of every conservative element."""
        T = V = 0.0
        jets = ev.jets
        for path, comp, node in self.topology.bodies:
            J = jets[node]
            m, rho, Iw = self.body_inertia(comp, path, J)
            v = J.v + cross(J.w, rho)
            T += 0.5 * m * (v @ v) + 0.5 * J.w @ Iw @ J.w
            V -= m * (self.g @ (J.r + rho))
        for node, Iw, _ in rotors(self, jets):
            T += 0.5 * jets[node].w @ Iw @ jets[node].w
        T += sum(0.5 * Jr * ev.u[k] ** 2 for k, Jr in reflected_rotors(self))  # rotors on a joint's own rate
        for path, comp, ports in self.topology.forces:
            V += comp.potential({pn: self.frame_state(jets[n]) for pn, n in ports.items()}, self.P[path])
        for path, comp in self.topology.flange_elements:
            states = {pn: self.flange_state(self.topology.flange_of[PortRef(comp, pn, "flange")], jets, ev.t, ev.q, ev.u)
                      for pn, pt in comp.ports().items() if pt.kind == "flange"}
            V += comp.potential(states, self.P[path])
        return T, V

    def momenta(self, ev: Evaluation):
        """``(p, h)``: the bodies' linear momentum (kg m/s) and angular momentum about the
        world origin (kg m^2/s), world frame, summed in the bodies' order (rotors on joint
        axes not included)."""
        P = L = np.zeros(3)
        for path, comp, node in self.topology.bodies:
            J = ev.jets[node]
            m, rho, Iw = self.body_inertia(comp, path, J)
            p = m * (J.v + cross(J.w, rho))
            P, L = P + p, L + (cross(J.r + rho, p) + Iw @ J.w)
        return P, L

    def reactions(self, ev: Evaluation, ud, lam):
        """Reaction wrench of every edge: dict name -> (f, tau), the force and torque exerted on
        frame_b through the joint (flange-element forces excluded; a drive's force is included),
        resolved in frame_b, torque about frame_b's origin.

        ``ud`` are the speeds' rates (the jets carry Jacobians), or a function ``(node, r) ->
        (a_lin, a_ang)`` giving the part of the accelerations of the point at ``r`` (world, m)
        moving with frame ``node`` that the speeds' rates cause (jets without Jacobian
        columns, :mod:`mbcomp.assembly.outputs`)."""
        jets = ev.jets
        if not callable(ud):
            ud_ = ud

            def rates(node, r):
                J = jets[node]
                dw = J.Jw @ ud_
                return J.Jv @ ud_ + cross(dw, r - J.r), dw
        else:
            rates = ud
        D = self._unbalanced(ev, rates)
        out = {}
        full_lam = np.zeros(len(self.constraint_names(all_rows=True)), np.asarray(lam).dtype)
        lam_h = lam[: lam.size - ev.B.shape[0]]
        if self.row_mask is not None:
            full_lam[self.row_mask] = lam_h
        elif lam_h.size:
            full_lam[:] = lam_h
        k = 0
        for e, rows, jac in ev.local:
            lr = full_lam[k:k + len(rows)]
            k += len(rows)
            for slot, node in enumerate(e.nodes):  # constraint wrenches on each frame of the rows
                w = -(jac[:, 6 * slot:6 * slot + 6].T @ lr)
                D[node][0] = D[node][0] - w[:3]
                D[node][1] = D[node][1] - w[3:]
            if e.kind == "flange":
                continue  # a gear's torques act on its joints' frames, as a flange element's do
            wb = -(jac[:, 6:].T @ lr)
            Rb = jets[e.node_b].R
            out[e.name] = (Rb.T @ wb[:3], Rb.T @ wb[3:])
        lam_nh = lam[lam.size - ev.B.shape[0]:] if ev.B.shape[0] else np.zeros(0)
        k = 0
        nh_on_b = {}
        for e, rows, jac in ev.local_nh:
            lr = lam_nh[k:k + len(rows)]
            k += len(rows)
            wa, wb = -(jac[:, :6].T @ lr), -(jac[:, 6:].T @ lr)
            for node, w in ((e.node_a, wa), (e.node_b, wb)):
                D[node] = [D[node][0] - w[:3], D[node][1] - w[3:]]
            nh_on_b[e.name] = wb
        for e in reversed(self.topology.tree):
            F, Mc = D[e.child]
            rc, rp = jets[e.child].r, jets[e.parent].r
            D[e.parent][0] = D[e.parent][0] + F
            D[e.parent][1] = D[e.parent][1] + Mc + cross(rc - rp, F)
            if e.forward:
                fb, tb, Rb = F, Mc, jets[e.child].R
            else:
                rb = jets[e.parent].r
                fb, tb, Rb = -F, -Mc + cross(rc - rb, -F), jets[e.parent].R
            out[e.name] = (Rb.T @ fb, Rb.T @ tb)
        for name, wb in nh_on_b.items():
            Rb = jets[self._edge[name].node_b].R
            f0, t0 = out.get(name, (np.zeros(3), np.zeros(3)))
            out[name] = (f0 + Rb.T @ wb[:3], t0 + Rb.T @ wb[3:])
        return out

    def _unbalanced(self, ev, rates):
        """Per frame node ``[F, T]`` (world, about the world origin's parallel through the node's
        origin): the bodies' and rotors' inertia and weight less the applied wrenches -- what the
        joints must carry (:meth:`reactions`); ``rates`` as there."""
        jets = ev.jets
        D = {n: [np.zeros(3), np.zeros(3)] for n in jets}
        for path, comp, node in self.topology.bodies:
            J = jets[node]
            m, rho, Iw = self.body_inertia(comp, path, J)
            a_lin, a_ang = rates(node, J.r + rho)
            acc = a_lin + J.a + cross(J.alpha, rho) + cross(J.w, cross(J.w, rho))
            F = m * (acc - self.g)
            D[node][0] = D[node][0] + F
            D[node][1] = D[node][1] + Iw @ (a_ang + J.alpha) + cross(J.w, Iw @ J.w) + cross(rho, F)
        for node, Iw, gyro in rotors(self, jets):
            dw = np.zeros(3) + rates(node, jets[node].r)[1]  # rates give a scalar 0 on the ground
            D[node][1] = D[node][1] + Iw @ dw + rotor_wrench(jets[node], Iw, gyro)
        for node, (F, T) in self.applied(ev.t, ev.q, ev.u, jets).items():
            D[node][0] = D[node][0] - F
            D[node][1] = D[node][1] - T
        return D

    def row_multipliers(self, ev: Evaluation, lam):
        """Multipliers by joint and row name: ``{joint: {row: lam}}`` (holonomic rows of cut
        joints, then nonholonomic rows; rows dropped as redundant are missing)."""
        names = self.constraint_names(all_rows=True)
        mask = self.row_mask if self.row_mask is not None else np.ones(len(names), bool)
        nh = ev.B.shape[0]
        out = {}
        for name, val in zip([n for n, k in zip(names, mask) if k], lam[: lam.size - nh]):
            joint, row = name.rsplit(".", 1)
            out.setdefault(joint, {})[row] = val
        k = lam.size - nh
        for e, rows, _ in ev.local_nh:
            for r in rows:
                out.setdefault(e.name, {})[r] = lam[k]
                k += 1
        return out

    def summary(self):
        """Human-readable description: bodies, DOF, coordinates, constraints, eliminations."""
        from .summary import summary

        return summary(self)
