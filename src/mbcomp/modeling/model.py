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

__all__ = ["Model", "FlatModel"]


class Model(Component):
    """A composition of components and connections.

    A ``Model`` is a component: add it to another model and reach its inner ports through
    :meth:`expose` (``sub.frame_a``) or directly (``sub["link"].frame_a``).
    """

    role = "model"

    def __init__(self):
        super().__init__()
        self._components: dict[str, Component] = {}
        self._connections: list[tuple[PortRef, PortRef]] = []
        self._aliases: dict[str, str] = {}
        self._outputs: dict[str, tuple] = {}
        self._exposed: dict[str, PortRef] = {}

    # --- building -------------------------------------------------------------------------
    def add(self, name: str, component: Component) -> Component:
        """Add ``component`` under ``name`` and return it."""
        if not isinstance(name, str) or not name.isidentifier():
            raise ValueError(f"component name {name!r} must be a Python identifier (letters, digits, _)")
        if not isinstance(component, Component):
            raise TypeError(f"{name}: {component!r} is not a Component; build it from mbcomp.library or subclass a role")
        if name in self._components:
            raise ValueError(f"{self._label()}: a component named {name!r} already exists; choose another name")
        if component.parent is not None:
            raise ValueError(f"{name}: this component object is already part of {component.parent._label()} "
                             f"as {component.name!r}; create a new instance for each use")
        component.name, component.parent = name, self
        self._components[name] = component
        return component

    def connect(self, a: PortRef, b: PortRef):
        """Connect two ports of the same kind (frame to frame, flange to flange)."""
        for x in (a, b):
            if not isinstance(x, PortRef):
                raise TypeError(f"connect() takes ports such as body.frame_a, got {x!r}")
        if a.kind != b.kind:
            raise ValueError(f"cannot connect {a.path} ({a.kind}) to {b.path} ({b.kind}): "
                             "connect frames to frames and flanges to flanges")
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

    def __getitem__(self, name):
        comp = self
        for part in name.split("."):
            comp = comp._components[part]
        return comp

    def components(self):
        return dict(self._components)

    def _label(self):
        return "model" if self.parent is None else f"model {self.path}"

    # --- flattening and validation --------------------------------------------------------
    def flatten(self) -> "FlatModel":
        """Leaf components by dotted path, every connection, and aliases with full paths."""
        leaves, conns, aliases, outputs = {}, [], {}, {}

        def walk(model, prefix):
            for name, comp in model._components.items():
                if isinstance(comp, Model):
                    walk(comp, f"{prefix}{name}.")
                else:
                    leaves[f"{prefix}{name}"] = comp
            conns.extend(model._connections)
            for k, v in model._aliases.items():
                aliases[f"{prefix}{k}"] = f"{prefix}{v}"
            for k, (fn, vs) in model._outputs.items():
                outputs[f"{prefix}{k}"] = (fn, tuple(f"{prefix}{v}" for v in vs))

        walk(self, "")
        return FlatModel(leaves, conns, aliases, outputs)

    def validate(self):
        """Collect every problem (parameters, unconnected ports, foreign components) and raise
        one :class:`~mbcomp.errors.ModelError` listing them; return the flat model if valid."""
        flat = self.flatten()
        probs = []
        owned = {id(c) for c in flat.components.values()}
        for comp in flat.components.values():
            probs.extend(comp.problems())
        connected = set()
        for a, b in flat.connections:
            for x in (a, b):
                if id(x.component) not in owned:
                    probs.append(Problem(x.path, "is connected but its component was never added to the model",
                                         f"add it with model.add(name, ...) before connecting {x.name}"))
                connected.add(x)
        for path, comp in flat.components.items():
            for pname, port in comp.ports().items():
                if port.optional or PortRef(comp, pname, port.kind) in connected:
                    continue
                probs.append(Problem(f"{path}.{pname}", f"{port.kind} of {type(comp).__name__} is not connected",
                                     f"connect {path}.{pname} to another {port.kind} with model.connect(...)"))
        if not flat.components:
            probs.append(Problem(self._label(), "contains no components", "add components with model.add(name, ...)"))
        if probs:
            raise ModelError(probs)
        return flat


class FlatModel:
    """Leaf components by path, connections between their ports, aliases and derived
    outputs (immutable hand-off)."""

    def __init__(self, components, connections, aliases, outputs=None):
        self.components = dict(components)
        self.connections = tuple(connections)
        self.aliases = dict(aliases)
        self.outputs = dict(outputs or {})
