"""Fingerprints: hashable values equal for two things nothing computed from them can tell
apart -- plain data by value, objects it cannot see into by identity.

What the assembly's topology plans (:mod:`mbcomp.assembly.plan`) and the generated programs'
structure cache (:mod:`mbcomp.codegen.structure_key`) key on. :func:`model_structure` is
the structure of a flat model's components: the path and class of every leaf (with the plain
data its class holds), every attribute a component keeps besides its declared parameters,
the connections in order, the bodies marked free. Parameter values are not in it.

A value the fingerprint cannot see into is taken by identity (and kept alive in ``refs``, so
that an equal fingerprint never meets a recycled ``id``): a wrong match would be a silent
wrong answer, a mismatch only costs the work being redone.

Examples
--------
>>> import numpy as np
>>> from mbcomp.modeling.fingerprint import fingerprint
>>> refs = []
>>> fingerprint((1.0, np.zeros(2)), refs) == fingerprint((1.0, np.zeros(2)), refs)
True
>>> fingerprint(1.0, refs) == fingerprint(1, refs)     # the type is part of it
False
"""
from __future__ import annotations

import operator
import types
import weakref

import numpy as np

__all__ = ["fingerprint", "model_structure", "Key"]

#: attributes every component has that no program reads (its name, look, raw constructor values,
#: construction-time parameters: the runtime values are the system's and are keyed there)
COMPONENT_OWN = frozenset(("name", "parent", "look", "_raw", "_bad", "p"))
_PLAIN = (type(None), bool, int, float, complex, str, bytes, np.bool_, np.integer, np.floating)
#: how deep a plain object's attributes are looked into before it is keyed by identity
_DEPTH = 6
_HEAPTYPE = 1 << 9  # Py_TPFLAGS_HEAPTYPE: a class defined in Python


class Key:
    """A hashable ``value`` (a large tuple) with its hash taken once, and the objects ``refs``
    its fingerprint holds by identity, kept alive with it: a dictionary keyed by it hashes
    the tuple once, not at every lookup.

    Examples
    --------
    >>> a, b = Key(("joint", 1.0)), Key(("joint", 1.0))
    >>> a == b, hash(a) == hash(b), a == Key(("joint", 2.0)), {a: 1}[b]
    (True, True, False, 1)
    """

    __slots__ = ("value", "hash_value", "refs", "__weakref__")

    def __init__(self, value, refs=()):
        self.value, self.hash_value, self.refs = value, hash(value), refs

    def __hash__(self):
        return self.hash_value

    def __eq__(self, other):
        return self is other or (type(other) is Key and self.hash_value == other.hash_value
                                 and self.value == other.value)

    def __repr__(self):
        return f"Key({self.value!r:.60})"


#: the model structures seen and alive, each kept once: equal structures are one object, which
#: the caches keyed on it compare by identity (a comparison of two equal structures of a
#: 20-link chain is ~20 us, and two caches look one up per run)
_STRUCTURES = weakref.WeakValueDictionary()


def _plain_class(cls):
    """Whether instances of ``cls`` keep their whole state in ``__dict__`` (every class of its
    MRO but ``object`` defined in Python, no ``__slots__``)."""
    return all(c.__flags__ & _HEAPTYPE and "__slots__" not in vars(c) for c in cls.__mro__[:-1])


def _code_names(code, out):
    """The global names a code object (and the code nested in it) reads."""
    out.update(code.co_names)
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            _code_names(c, out)
    return out


def _function(f, refs, depth):
    """A Python function: itself, its defaults, its closure's values and the globals it reads
    (a law reading ``K`` traces ``K``'s value into the program as a constant)."""
    refs.append(f)
    g = f.__globals__
    code_names = _code_names(f.__code__, set())
    names = sorted(n for n in code_names if n in g)
    cells = []
    for c in f.__closure__ or ():
        try:
            cells.append(fingerprint(c.cell_contents, refs, depth + 1))
        except ValueError:  # an empty cell
            cells.append(("empty",))
    return ("fn", f, fingerprint(f.__defaults__, refs, depth + 1), fingerprint(f.__kwdefaults__, refs, depth + 1),
            tuple(cells), tuple((n, _global(g[n], code_names, refs, depth + 1)) for n in names))


def _global(v, code_names, refs, depth):
    """A global a law reads; a module also by the values of the attributes the law's code
    names (``cfg.K``: a changed ``K`` is another program, as a changed global ``K`` is)."""
    if not isinstance(v, types.ModuleType):
        return fingerprint(v, refs, depth)
    refs.append(v)
    attrs = tuple((n, fingerprint(getattr(v, n), refs, depth)) for n in sorted(code_names)
                  if n in vars(v) and not isinstance(vars(v)[n], (types.ModuleType, types.FunctionType, type)))
    return ("module", v, attrs)


def fingerprint(v, refs, depth=0):
    """A hashable value equal for two values nothing computed from them can tell apart;
    objects it cannot see into by identity (``v`` appended to the list ``refs`` to keep it alive).

    Plain data (numbers, strings, float arrays, tuples, lists, dicts, sets, objects of Python
    classes keeping their state in ``__dict__``) by value, ``depth`` levels deep; a Python
    function by identity and by the values of its defaults, its closure and the globals it
    reads; anything else by identity."""
    if isinstance(v, _PLAIN):
        return (type(v).__name__, v.item() if isinstance(v, np.generic) else v)
    if depth < _DEPTH:
        if type(v) in (tuple, list):
            return (type(v).__name__,) + tuple(fingerprint(x, refs, depth + 1) for x in v)
        if type(v) is np.ndarray and v.dtype != object:
            return ("nd", v.dtype.str, v.shape, v.tobytes())
        if type(v) is dict:
            return ("dict",) + tuple((fingerprint(k, refs, depth + 1), fingerprint(x, refs, depth + 1))
                                     for k, x in v.items())
        if type(v) in (set, frozenset):
            return ("set",) + tuple(sorted((fingerprint(x, refs, depth + 1) for x in v), key=repr))
        if isinstance(v, types.FunctionType):
            return _function(v, refs, depth)
        if isinstance(v, types.MethodType):
            return ("method", fingerprint(v.__func__, refs, depth + 1), fingerprint(v.__self__, refs, depth + 1))
        # plain data (a surface, an input, a callable object): a Python class whose state is its __dict__
        if not isinstance(v, (type, types.ModuleType)) and hasattr(v, "__dict__") and _plain_class(type(v)):
            return ("obj", type(v)) + tuple((k, fingerprint(x, refs, depth + 1))
                                            for k, x in sorted(vars(v).items()))
    try:
        hash(v)
        refs.append(v)
        return ("is", v) if not isinstance(v, type) else ("class", v)
    except TypeError:
        refs.append(v)
        return ("id", id(v))


#: class -> (the keys and values of its own namespace when last read, as tuples; the plain data
#: among them: (name, fingerprint, value), the fingerprint None for a value that may change in
#: place -- an array, a tuple holding one -- fingerprinted again at every use)
_NAMESPACES = {}
#: component class -> (the namespaces' entries it was made of, its plain data, whether that
#: holds no value that may change in place): the same data object while equal
_CLASS_DATA = {}


def _frozen(x):
    """Whether ``x`` is plain data that cannot change in place (a number, a string, a tuple of such)."""
    return isinstance(x, _PLAIN) or (type(x) is tuple and all(map(_frozen, x)))


def _own_data(c, seen):
    """The plain data of class ``c``'s own namespace (see :data:`_NAMESPACES`): read again
    only when the namespace holds another key or object than when last read; checked once
    per structure taken (``seen``: class -> data)."""
    got = seen.get(c)
    if got is None:
        ns = vars(c)
        keys, values = tuple(ns), tuple(ns.values())
        old = _NAMESPACES.get(c)
        if old is None or len(old[0]) != len(keys) or not (all(map(operator.is_, old[0], keys))
                                                             and all(map(operator.is_, old[1], values))):
            data = tuple((k, fingerprint(x, []) if _frozen(x) else None, x) for k, x in sorted(ns.items())
                         if not k.startswith("__") and isinstance(x, (_PLAIN, tuple, np.ndarray)))
            old = _NAMESPACES[c] = (keys, values, data)
        got = seen[c] = old[2]
    return got


def _class_data(cls, refs, seen):
    """The plain data a component's class (and its bases) holds: numbers, strings, tuples
    and arrays its methods may read (a changed class constant is another program); the same
    object while equal (equal structures compare it by identity). ``seen``: see :func:`_own_data`."""
    parts = tuple(_own_data(c, seen) for c in cls.__mro__[:-1])
    last = _CLASS_DATA.get(cls)
    if last is not None and last[2] and len(last[0]) == len(parts) and all(map(operator.is_, last[0], parts)):
        return last[1]
    data = tuple((c.__name__, k, fingerprint(x, refs) if fp is None else fp)
                 for c, own in zip(cls.__mro__[:-1], parts) for k, fp, x in own)
    if last is not None and data == last[1]:
        data = last[1]
    _CLASS_DATA[cls] = (parts, data, all(fp is not None for own in parts for _, fp, _ in own))
    return data


def model_structure(components, connections, free):
    """The structure of a flat model's leaves ``components`` (``{path: component}``), its
    ``connections`` (pairs of ports, in order) and the paths of its bodies marked ``free``
    (see the module notes): a :class:`Key` whose value is ``(components, connections,
    free)`` and whose ``refs`` hold what the fingerprint holds by identity; equal structures
    alive at once are one :class:`Key` object. A port of a component not among
    ``components`` is named ``None``.

    Examples
    --------
    >>> from mbcomp import Model
    >>> from mbcomp.library import World, Revolute
    >>> def structure(phi0):
    ...     m = Model(); w = m.add("world", World()); j = m.add("j", Revolute(phi0=phi0))
    ...     m.connect(w.frame_b, j.frame_a)
    ...     flat = m.flatten()
    ...     return model_structure(flat.components, flat.connections, flat.free)
    >>> a, b = structure(0.1), structure(0.2)
    >>> a is b, a.value[1]
    (True, (('world', 'frame_b', 'j', 'frame_a'),))
    """
    comps, refs = [], []
    classes, seen = {}, {}
    own = COMPONENT_OWN
    for path, comp in components.items():
        d = vars(comp)
        if d.keys() == own:  # most components keep nothing besides their own attributes
            extra = ()
        else:
            extra = tuple((k, fingerprint(d[k], refs)) for k in sorted(d.keys() - own))
        cls = type(comp)
        data = classes.get(cls)
        if data is None:
            data = classes[cls] = _class_data(cls, refs, seen)
        comps.append((path, cls, data, extra))
    where = {id(c): path for path, c in components.items()}
    conns = tuple((where.get(id(a.component)), a.name, where.get(id(b.component)), b.name) for a, b in connections)
    key = Key((tuple(comps), conns, tuple(sorted(free))), refs)
    seen = _STRUCTURES.get(key)
    if seen is not None:
        return seen  # the same objects by identity (an equal key's ids are alive in seen.refs)
    _STRUCTURES[key] = key
    return key
