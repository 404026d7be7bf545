"""``Model``: components plus connections; itself usable as a component (nesting).

Examples
--------
A pendulum: a hinge at the world origin and a point mass 1 m below it.

>>> from mbcomp import Model
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = Model()
>>> world = m.add("world", World())
>>> hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.3))
>>> rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(world.frame_b, hinge.frame_a)
>>> m.connect(hinge.frame_b, rod.frame_a)
>>> m.connect(rod.frame_b, bob.frame_a)
>>> m.alias("theta", "hinge.phi")
>>> flat = m.validate()
"""
from __future__ import annotations

from ..modeling.component import Component, PortRef
from ..errors import ModelError, Problem
from .fingerprint import model_structure
from .lock import lock, locked_joints
from .roles import MissingFlange

__all__ = ["Model", "FlatModel", "is_rigid_offset"]


class Model(Component):
    """A composition of components and connections.

    A ``Model`` is a component: add it to another model and reach its inner ports through
    :meth:`expose` (``sub.frame_a``) or directly (``sub["link"].frame_a``).

    Examples
    --------
    A pendulum of length 1 m, then the same pendulum as a sub-model of a larger one:

    >>> import mbcomp
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model()
    >>> world = m.add("world", World()); hinge = m.add("hinge", Revolute(n=(0, 0, 1), phi0=0.1))
    >>> rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0))); bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(world.frame_b, hinge.frame_a); m.connect(hinge.frame_b, rod.frame_a)
    >>> m.connect(rod.frame_b, bob.frame_a)
    >>> mbcomp.assemble(m).q_names
    ['hinge.phi']
    >>> scene = mbcomp.Model(); scene.add("left", m)["bob"].p.m
    1.0
    """

    role = "model"

    def __init__(self):
        super().__init__()
        self._components: dict[str, Component] = {}
        self._connections: list[tuple[PortRef, PortRef]] = []
        self._aliases: dict[str, str] = {}
        self._outputs: dict[str, tuple] = {}
        self._exposed: dict[str, PortRef] = {}
        self._free: set[str] = set()

    # --- building -------------------------------------------------------------------------
    def add(self, name: str, component: Component, free: bool = False) -> Component:
        """Add ``component`` under ``name`` and return it.

        Parameters
        ----------
        name : str
            A Python identifier, unique in this model.
        component : Component
            A library component, a user's component or a :class:`Model`.
        free : bool
            Only for a body: it floats on purpose, joined to nothing that reaches the world
            (a thrown ball, a satellite, a wheel touching the ground only through a contact).
            The topology then gives it a 6-DOF :class:`~mbcomp.library.FreeMotion` from the
            world to its ``frame_a``, named ``<name>.free`` (start values as parameters
            ``<name>.free.r0``, ``.v0``, ``.R0``, ``.w0``). Without it, a body that reaches the
            world through no joint is an error (a forgotten connection would fall freely).
            Connecting the body through an explicit ``FreeMotion`` from the world is the same.

        Examples
        --------
        >>> import numpy as np
        >>> from mbcomp import Model
        >>> from mbcomp.library import World, RigidBody
        >>> m = Model(); _ = m.add("world", World())
        >>> ball = m.add("ball", RigidBody(m=0.1, I=1e-5 * np.eye(3)), free=True)
        """
        if not isinstance(name, str) or not name.isidentifier():
            raise ValueError(f"component name {name!r} must be a Python identifier (letters, digits, _)")
        if not isinstance(component, Component):
            raise TypeError(f"{name}: {component!r} is not a Component; build it from mbcomp.library or subclass a role")
        if name in self._components:
            raise ValueError(f"{self.label()}: a component named {name!r} already exists; choose another name")
        if component.parent is not None:
            raise ValueError(f"{name}: this component object is already part of {component.parent.label()} "
                             f"as {component.name!r}; create a new instance for each use")
        if free and getattr(component, "role", None) != "body":
            raise ValueError(f"{name}: free=True marks a body that floats on purpose; a {type(component).__name__} "
                             "is no body -> mark the body itself free, or join the part to the world with joints")
        component.name, component.parent = name, self
        self._components[name] = component
        if free:
            self._free.add(name)
        return component

    def connect(self, a: PortRef, b: PortRef):
        """Connect two ports of the same kind (frame to frame, flange to flange)."""
        for x in (a, b):
            if not isinstance(x, PortRef):
                raise TypeError(f"connect() takes ports such as body.frame_a, got {x!r}")
        for x, y in ((a, b), (b, a)):
            if isinstance(x, MissingFlange):
                raise ModelError([_missing_flange(x, y)], header="cannot connect")
        if a.kind != b.kind:
            raise ValueError(f"cannot connect {a.path} ({a.kind}) to {b.path} ({b.kind}): "
                             "connect frames to frames and flanges to flanges")
        if a == b:  # the same port, perhaps reached once by name and once through expose()
            other = ("a frame of another component, e.g. the next body's frame_a or the world's frame_b"
                     if a.kind == "frame" else "a flange of another component, e.g. a Torque's flange_b")
            raise ModelError([Problem(a.path, f"is connected to itself (a {a.kind} joined to itself joins nothing)",
                                      f"connect {a.path} to {other}")], header="cannot connect")
        self._connections.append((a, b))

    def alias(self, name: str, variable: str):
        """Expose ``variable`` (e.g. ``"crank.phi"``) in results under ``name``."""
        self._aliases[name] = variable

    def output(self, name: str, function, *variables: str):
        """Derived output ``name = function(*series)`` computed from result variables.

        Parameters
        ----------
        name : str
            Column name in results (prefixed with the model's path when nested).
        function : callable
            Takes one numpy array per variable (same length, one value per output time)
            and returns an array of that length; units are the caller's.
        *variables : str
            Result variables relative to this model, e.g. ``"top.Q.x"``.

        Examples
        --------
        >>> import numpy as np
        >>> from mbcomp import Model
        >>> m = Model()
        >>> m.output("phi_deg", np.degrees, "hinge.phi")
        """
        if not callable(function):
            raise TypeError(f"output {name!r}: function must be callable, got {function!r}")
        self._outputs[name] = (function, tuple(variables))

    def expose(self, name: str, port: PortRef):
        """Make an inner port reachable as ``model.<name>`` from an enclosing model."""
        self._exposed[name] = port
        setattr(self, name, port)

    def draw(self, path, params=None):
        """Draw the assembled topology to ``path`` (``.svg``, ``.png`` or ``.pdf``): bodies and
        frames as nodes, joints as edges, the spanning tree solid, cut joints dashed with their
        constraint rows, dropped redundant and nonholonomic rows marked, the independent
        coordinates named -- what ``mbcomp info`` prints, as a picture
        (:func:`mbcomp.visual.topology_drawing.draw_topology`). Returns ``path``.

        Parameters
        ----------
        path : str or os.PathLike
            The file to write; its suffix picks the format.
        params : dict, optional
            Parameter overrides ``{"comp.param": value}`` for the assembly.

        Examples
        --------
        >>> import os, tempfile
        >>> from mbcomp import Model
        >>> from mbcomp.library import World, Revolute, RigidBody
        >>> m = Model(); w = m.add("world", World()); j = m.add("j", Revolute(n=(0, 0, 1)))
        >>> b = m.add("b", RigidBody(m=1.0, r_cm=(0.5, 0, 0)))
        >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, b.frame_a)
        >>> out = m.draw(os.path.join(tempfile.mkdtemp(), "topo.svg"))
        >>> open(out).read().lstrip().startswith(("<?xml", "<svg"))
        True
        """
        from ..visual.topology_drawing import draw_topology

        return draw_topology(self, path, params=params)

    def _repr_html_(self):
        """The assembled topology drawn inline in a notebook (:meth:`draw`'s picture as SVG,
        made in memory); a model that does not assemble shows why, in one paragraph."""
        import html

        from ..visual.topology_drawing import topology_svg

        try:
            return f'<div class="mbcomp-model">{topology_svg(self)}</div>'
        except ValueError as exc:  # a ModelError: a model still being built; say why there is no picture
            return (f"<p><b>mbcomp Model</b> with {len(self.components())} components: no topology drawing "
                    f"({html.escape(type(exc).__name__)}: {html.escape(str(exc))})</p>")

    def remove(self, name: str) -> Component:
        """Take the component at ``name`` (a dotted path into nested models) out of the model,
        with every connection to its ports; return it, free to be added again.

        Examples
        --------
        >>> from mbcomp import Model
        >>> from mbcomp.library import World, Revolute
        >>> m = Model(); w = m.add("world", World()); j = m.add("j", Revolute())
        >>> m.connect(w.frame_b, j.frame_a)
        >>> m.remove("j") is j, list(m.components()), j.parent
        (True, ['world'], None)
        """
        head, _, rest = name.partition(".")
        comp = self._components.get(head)
        if comp is None or (rest and not isinstance(comp, Model)):
            raise KeyError(f"{self.label()}: no component {name!r}; its components: {', '.join(self._components)}")
        if rest:
            gone = comp.remove(rest)
        else:
            gone = self._components.pop(head)
            self._free.discard(head)
            gone.name, gone.parent = None, None
        self._connections = [(a, b) for a, b in self._connections
                             if a.component is not gone and b.component is not gone]
        return gone

    def lock(self, joints, at=None) -> "Model":
        """A new model with ``joints`` held still at ``at`` (this one is not changed): each
        becomes a rigid connection under its name, so the bodies on both sides move as one
        body -- fewer coordinates, their inertia merged (a humanoid's arm study without its
        legs and fingers, as Pinocchio's ``buildReducedModel``). :func:`mbcomp.reduce` locks
        every moving joint but those kept. Rules and what is dropped: :mod:`mbcomp.modeling.lock`.

        Parameters
        ----------
        joints : str, Joint or sequence of them
            The joints to lock, by path (``"arm.elbow"``) or as components of this model.
        at : dict, optional
            ``{joint: coordinates}`` (rad or m, in the joint's coordinate order; a scalar for a
            1-DOF joint; a ``FreeMotion``'s ``r`` then its quaternion); a joint left out is
            held at its start values (0 where none are given).

        Returns
        -------
        Model
            With :attr:`locked` and ``lock_notes`` (the elements dropped from the locked
            joints' flanges, also said in one ``UserWarning``).

        Examples
        --------
        >>> import mbcomp
        >>> from mbcomp.library import World, Revolute, PointMass
        >>> m = mbcomp.Model(); w = m.add("world", World())
        >>> a = m.add("a", Revolute()); b = m.add("b", Revolute())
        >>> pa = m.add("pa", PointMass()); pb = m.add("pb", PointMass())
        >>> m.connect(w.frame_b, a.frame_a); m.connect(a.frame_b, pa.frame_a)
        >>> m.connect(pa.frame_a, b.frame_a); m.connect(b.frame_b, pb.frame_a)
        >>> held = m.lock("a", at={"a": 0.2})
        >>> mbcomp.assemble(held).q_names, held.locked, m.locked
        (['b.phi'], {'a': {'phi': 0.2}}, {})
        """
        return lock(self, joints, at)

    @property
    def locked(self) -> dict:
        """``{joint path: {coordinate: value}}`` of the joints :meth:`lock` held still (rad or
        m; a quaternion's entries 1); empty for a model with none."""
        return locked_joints(self)

    def __getitem__(self, name):
        head, _, rest = name.partition(".")
        comp = self._components[head]
        return comp[rest] if rest else comp

    def components(self):
        return dict(self._components)

    def label(self):
        """How messages name this model: ``"model"`` at the top, ``"model <path>"`` when nested."""
        return "model" if self.parent is None else f"model {self.path}"

    # --- flattening and validation --------------------------------------------------------
    def flatten(self) -> "FlatModel":
        """Leaf components by dotted path, every connection, and aliases with full paths (a
        nested model flattens itself; its paths get its name as a prefix; its connections,
        aliases and outputs come before this model's own)."""
        leaves, conns, aliases, outputs, free = {}, [], {}, {}, set()
        for name, comp in self._components.items():
            if not isinstance(comp, Model):
                leaves[name] = comp
                continue
            inner, pre = comp.flatten(), f"{name}."
            leaves.update((pre + k, c) for k, c in inner.components.items())
            conns.extend(inner.connections)
            free.update(pre + k for k in inner.free)
            aliases.update((pre + k, pre + v) for k, v in inner.aliases.items())
            outputs.update((pre + k, (fn, tuple(pre + v for v in vs))) for k, (fn, vs) in inner.outputs.items())
        conns.extend(self._connections)
        free.update(self._free)
        aliases.update(self._aliases)
        outputs.update(self._outputs)
        return FlatModel(leaves, conns, aliases, outputs, free)

    def validate(self):
        """Collect every problem (parameters, unconnected ports, foreign components) and raise
        one :class:`~mbcomp.errors.ModelError` listing them; return the flat model if valid."""
        flat = self.flatten()
        probs = []
        owned = {id(c) for c in flat.components.values()}
        for comp in flat.components.values():
            probs.extend(comp.problems())
        connected = set()  # (id(component), port name): a port's own hash and __eq__ are Python calls
        for a, b in flat.connections:
            for x in (a, b):
                if id(x.component) not in owned:
                    probs.append(Problem(x.path, "is connected but its component was never added to the model",
                                         f"add it with model.add(name, ...) before connecting {x.name}"))
                connected.add((id(x.component), x.name))
        carried = _rotor_carried(flat)
        declared = {}  # class -> its ports (a class's declaration, read once per class here)
        for path, comp in flat.components.items():
            ports = declared.get(type(comp))
            if ports is None:
                ports = declared[type(comp)] = comp.ports()
            key = id(comp)
            open_ = [n for n, port in ports.items() if not port.optional and (key, n) not in connected]
            if open_:
                probs.extend(_open_ports(path, comp, ports, open_, carried))
        if not flat.components:
            probs.append(Problem(self.label(), "contains no components", "add components with model.add(name, ...)"))
        if probs:
            raise ModelError(probs)
        return flat


def is_rigid_offset(comp):
    """True for a 0-DOF joint that is a tree edge (``FixedTranslation``, ``FixedRotation``,
    ``Weld``): one of its frames may stay open, a harmless frame that moves with the other.

    Examples
    --------
    >>> from mbcomp.library import FixedTranslation, Revolute
    >>> is_rigid_offset(FixedTranslation()), is_rigid_offset(Revolute())
    (True, False)
    """
    return comp.role == "joint" and comp.nu == 0 and comp.tree_edge


def _rotor_carried(flat):
    """Ids of the joints whose ``axis`` flange carries a rotor (a ``FlangeInertia`` connected to
    it, directly or through other flange ports): their frame_b turns the rotor, so it may stay
    open (a shaft without a body, :class:`~mbcomp.library.Inertia`)."""
    find, parent = flat.flange_groups()
    rotors = {find(x) for x in list(parent) if x.component.role == "flange_inertia"}
    return {id(x.component) for x in list(parent)
            if x.component.role == "joint" and x.name == "axis" and find(x) in rotors}


def _open_ports(path, comp, ports, open_, carried=frozenset()):
    """Problems of the ports ``open_`` of ``comp`` (its ``ports``) left unconnected (a rigid
    offset may leave one frame open; so may a joint's frame_b that turns a rotor on its axis,
    ``carried``)."""
    frames = [n for n, port in ports.items() if port.kind == "frame"]
    if id(comp) in carried and "frame_a" not in open_:
        open_ = [n for n in open_ if n != "frame_b"]  # the shaft is the rotor's: a frame that moves it
    out = []
    for pname in open_:
        kind = ports[pname].kind
        what = f"{kind} of {type(comp).__name__} is not connected"
        fix = f"connect {path}.{pname} to another {kind} with model.connect(...)"
        if is_rigid_offset(comp):
            if len(set(frames) - set(open_)) >= 1:
                continue  # an open frame at the end of a rigid offset: a harmless marker frame
            what = f"{what}, nor is its other frame: the {type(comp).__name__} is joined to nothing"
        elif comp.role == "joint" and kind == "frame":
            what = (f"{what}: a joint with {comp.nu} degree{'s' * (comp.nu != 1)} of freedom must join two frames "
                    "(its motion would move nothing, so it is undetermined); only rigid offsets (FixedTranslation, "
                    "FixedRotation) may end in an open frame, and a joint whose axis turns a rotor (Inertia) in frame_b")
        out.append(Problem(f"{path}.{pname}", what, fix))
    return out


def _missing_flange(x, y):
    """The problem of connecting ``y`` to the flange ``x`` its joint does not have."""
    joint = x.component
    kinds = {"drive": "drive", "flange_force": "flange element"}
    user = (f"{kinds[y.component.role]} {y.component.path!r}" if y.component.role in kinds
            else f"{y.path}")
    needs = "a drive" if y.component.role == "drive" else "a flange element (spring, damper, Torque, Force)"
    return Problem(f"{user} on joint {joint.path!r} ({type(joint).__name__})",
                   f"{needs} needs a 1-DOF joint's {x.name} flange (Revolute, Prismatic); a "
                   f"{type(joint).__name__} has {joint.nu} degrees of freedom and no {x.name} flange",
                   f"connect it to {x.name} of a Revolute or Prismatic: build the {type(joint).__name__}'s "
                   "motion from 1-DOF joints in series (e.g. three Revolutes for a Spherical) and act on one of them")


class FlatModel:
    """Leaf components by path, connections between their ports, aliases, derived outputs
    and the paths of the bodies marked ``free`` (immutable hand-off).

    Examples
    --------
    >>> from mbcomp import Model
    >>> from mbcomp.library import World, Revolute
    >>> def flat(phi0):
    ...     m = Model(); w = m.add("world", World()); j = m.add("j", Revolute(phi0=phi0))
    ...     m.connect(w.frame_b, j.frame_a)
    ...     return m.flatten()
    >>> a, b = flat(0.1), flat(0.7)
    >>> list(a.components), a.structure()[0] == b.structure()[0]   # other start values: one structure
    (['world', 'j'], True)
    """

    def __init__(self, components, connections, aliases, outputs=None, free=()):
        self.free = frozenset(free)
        self.components = dict(components)
        self.connections = tuple(connections)
        self.aliases = dict(aliases)
        self.outputs = dict(outputs or {})
        self._structure = None

    def flange_groups(self):
        """The flange ports joined by connections: ``(find, parent)``, a union-find whose
        ``find(port)`` is the port standing for its group and whose ``parent`` holds every
        connected flange port (a port connected to nothing is in no group)."""
        parent = {}

        def find(x):
            while parent.setdefault(x, x) != x:
                x = parent[x]
            return x

        for a, b in self.connections:
            if a.kind == "flange" and b.kind == "flange":
                parent[find(a)] = find(b)
        return find, parent

    def structure(self):
        """``(key, refs)``: the structure of the components, connections and free bodies as a
        hashable :class:`~mbcomp.modeling.fingerprint.Key` (:func:`~mbcomp.modeling.fingerprint.model_structure`:
        paths, classes, attributes besides the parameters, connections; no parameter values)
        and the objects it holds by identity, to keep alive while the key is used. Taken once,
        when first asked (a model's components are not changed once it is validated); taken
        again for a flat model whose components, connections or free bodies were replaced since."""
        got = getattr(self, "_structure", None)  # (a flat model pickled before it had one)
        if got is None or got[0] is not self.components or got[1] is not self.connections or got[2] is not self.free:
            got = self._structure = (self.components, self.connections, self.free,
                                     model_structure(self.components, self.connections, self.free))
        return got[3], got[3].refs

    def __getstate__(self):  # pickled and copied without the structure: what it holds by identity may not pickle
        state = dict(vars(self))
        state["_structure"] = None
        return state
