"""The structure of an assembled system as a key, computed without tracing: what a generated
program bakes in, so that a model rebuilt with other parameter or start values finds the
programs a first run traced and printed (:class:`StructureCache`).

A program is a function of the runtime parameters (every nonzero number of a numeric
parameter, :func:`~mbcomp.codegen.tracer.param_layout`) and of the state; everything else is
part of it. :func:`structure_key` gathers that everything:

* the components: path and class of every leaf, and every attribute a component keeps
  besides its declared parameters (by value where it is plain data, else by identity);
* the connections (in order: the spanning tree follows it), the bodies marked free;
* the parameter signature of :func:`~mbcomp.codegen.tracer.param_layout` (which entries are
  zero, the shapes, the laws) and every non-numeric parameter value (a law, a surface, an
  input) by value where it is plain data, else by identity; a law written as a Python
  function by identity *and* by the values of its defaults, its closure and the globals it
  reads (they are traced into the program as constants);
* the drives' parameters *by value*, numbers too: a drive's law is traced into the
  right-hand side with its numbers as constants;
* the nonholonomic rows, the backend, the node limit, the compiler and its flags.

What the key holds by identity (a callable law, an object with behaviour) is kept alive by the
cache entry, so an equal key never meets a recycled ``id``. A value the key cannot see into is
never taken by value: a wrong hit would be a silent wrong answer, a miss only costs a trace.
Decisions a component took on a parameter's *value* (``if p.d:``) are not in the key: they are
the programs' parameter guards, checked when a program is bound to new values (it is traced
again when one fails), as for :meth:`~mbcomp.assembly.system.MultibodySystem.with_params`.

Examples
--------
>>> import mbcomp
>>> from mbcomp.codegen.structure_key import structure_key
>>> from mbcomp.library import World, Prismatic, PointMass
>>> def model(m, n=(0, 0, 1)):
...     mdl = mbcomp.Model(); w = mdl.add("world", World(g=(0, 0, -9.81)))
...     s = mdl.add("s", Prismatic(n=n)); b = mdl.add("b", PointMass(m=m))
...     mdl.connect(w.frame_b, s.frame_a); mdl.connect(s.frame_b, b.frame_a)
...     return mbcomp.assemble(mdl)
>>> k1, _ = structure_key(model(1.0), "c")
>>> k2, _ = structure_key(model(2.0), "c")              # another mass: the same structure
>>> k3, _ = structure_key(model(1.0, n=(0, 1, 1)), "c")  # a zero became nonzero: another one
>>> k1 == k2, k1 == k3
(True, False)
"""
from __future__ import annotations

from collections import OrderedDict

import os
import types

import numpy as np

from .toolchain import c_compiler
from .tracer import param_layout
from .tracing import drives

__all__ = ["structure_key", "StructureCache", "STRUCTURES", "compiler"]

#: attributes every component has that no program reads (its name, look, raw constructor values,
#: construction-time parameters: the runtime values are the system's and are keyed there)
_COMPONENT_OWN = frozenset(("name", "parent", "look", "_raw", "_bad", "p"))
_PLAIN = (type(None), bool, int, float, complex, str, bytes, np.bool_, np.integer, np.floating)
#: how deep a plain object's attributes are looked into before it is keyed by identity
_DEPTH = 6


_COMPILERS = {}


def compiler():
    """:func:`~mbcomp.codegen.toolchain.c_compiler` looked up once per ``$CC`` and ``$PATH`` (a
    search of the path is ~50 us; a short run asked four times).

    Examples
    --------
    >>> from mbcomp.codegen.structure_key import compiler
    >>> from mbcomp.codegen.toolchain import c_compiler
    >>> compiler() == c_compiler()
    True
    """
    key = (os.environ.get("CC"), os.environ.get("PATH"))
    if key not in _COMPILERS:
        _COMPILERS[key] = c_compiler()
    return _COMPILERS[key]


_HEAPTYPE = 1 << 9  # Py_TPFLAGS_HEAPTYPE: a class defined in Python


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
    names = sorted(n for n in _code_names(f.__code__, set()) if n in g)
    cells = []
    for c in f.__closure__ or ():
        try:
            cells.append(_fingerprint(c.cell_contents, refs, depth + 1))
        except ValueError:  # an empty cell
            cells.append(("empty",))
    code_names = _code_names(f.__code__, set())
    return ("fn", f, _fingerprint(f.__defaults__, refs, depth + 1), _fingerprint(f.__kwdefaults__, refs, depth + 1),
            tuple(cells), tuple((n, _global(g[n], code_names, refs, depth + 1)) for n in names))


def _global(v, code_names, refs, depth):
    """A global a law reads; a module also by the values of the attributes the law's code
    names (``cfg.K``: a changed ``K`` is another program, as a changed global ``K`` is)."""
    if not isinstance(v, types.ModuleType):
        return _fingerprint(v, refs, depth)
    refs.append(v)
    attrs = tuple((n, _fingerprint(getattr(v, n), refs, depth)) for n in sorted(code_names)
                  if n in vars(v) and not isinstance(vars(v)[n], (types.ModuleType, types.FunctionType, type)))
    return ("module", v, attrs)


def _fingerprint(v, refs, depth=0):
    """A hashable value equal for two values a program cannot tell apart; objects it cannot
    see into by identity (``v`` appended to ``refs`` to keep it alive)."""
    if isinstance(v, _PLAIN):
        return (type(v).__name__, v.item() if isinstance(v, np.generic) else v)
    if depth < _DEPTH:
        if type(v) in (tuple, list):
            return (type(v).__name__,) + tuple(_fingerprint(x, refs, depth + 1) for x in v)
        if type(v) is np.ndarray and v.dtype != object:
            return ("nd", v.dtype.str, v.shape, v.tobytes())
        if type(v) is dict:
            return ("dict",) + tuple((_fingerprint(k, refs, depth + 1), _fingerprint(x, refs, depth + 1))
                                     for k, x in v.items())
        if type(v) in (set, frozenset):
            return ("set",) + tuple(sorted((_fingerprint(x, refs, depth + 1) for x in v), key=repr))
        if isinstance(v, types.FunctionType):
            return _function(v, refs, depth)
        if isinstance(v, types.MethodType):
            return ("method", _fingerprint(v.__func__, refs, depth + 1), _fingerprint(v.__self__, refs, depth + 1))
        # plain data (a surface, an input, a callable object): a Python class whose state is its __dict__
        if not isinstance(v, (type, types.ModuleType)) and hasattr(v, "__dict__") and _plain_class(type(v)):
            return ("obj", type(v)) + tuple((k, _fingerprint(x, refs, depth + 1))
                                            for k, x in sorted(vars(v).items()))
    try:
        hash(v)
        refs.append(v)
        return ("is", v) if not isinstance(v, type) else ("class", v)
    except TypeError:
        refs.append(v)
        return ("id", id(v))


def _class_data(cls, refs):
    """The plain data a component's class (and its bases) holds: numbers, strings, tuples
    and arrays its methods may read (a changed class constant is another program)."""
    out = []
    for c in cls.__mro__[:-1]:
        for k, x in sorted(vars(c).items()):
            if not k.startswith("__") and isinstance(x, (_PLAIN, tuple, np.ndarray)):
                out.append((c.__name__, k, _fingerprint(x, refs)))
    return tuple(out)


def _components(flat, refs):
    comps = []
    classes = {}
    for path, comp in flat.components.items():
        extra = tuple((k, _fingerprint(x, refs)) for k, x in sorted(vars(comp).items()) if k not in _COMPONENT_OWN)
        cls = type(comp)
        if cls not in classes:
            classes[cls] = _class_data(cls, refs)
        comps.append((path, cls, classes[cls], extra))
    where = {id(c): path for path, c in flat.components.items()}
    conns = tuple((where.get(id(a.component)), a.name, where.get(id(b.component)), b.name) for a, b in flat.connections)
    return tuple(comps), conns, tuple(sorted(flat.free))


def structure_key(system, backend, options=(), signature=None):
    """``(key, refs)``: the structure of ``system`` as a hashable key (see the module notes)
    for programs printed for ``backend`` with ``options`` (hashable: node limit, compiler,
    flags); ``refs``, the objects the key holds by identity, to keep alive while it is used.
    ``signature``: ``param_layout(system)[1]`` when the caller has it."""
    refs = []
    flat = system.topology.flat
    comps, conns, free = _components(flat, refs)
    driving = drives(system)
    drive_params = tuple((path, _fingerprint(sorted(vars(system.P[path]).items()), refs)) for path in driving)
    if signature is None:
        signature = param_layout(system)[1]
    laws = tuple(_fingerprint(x, refs) for x in signature if x[2] == "o")
    nonholonomic = tuple(e.name for e in system.nonholonomic)
    key = (backend, tuple(options), comps, conns, free, drive_params, signature, laws, nonholonomic)
    return key, refs


class StructureCache:
    """Programs by structure: ``entry(system, backend, options)`` -> the dict a
    :class:`~mbcomp.codegen.evaluator.ProgramEvaluator` keeps its codes in (the evaluation
    program under ``"eval"``, the right-hand sides by row mask, the output, Jacobian and DAE
    programs), shared by every system of that structure, and whether it was there already.
    Holds at most ``size`` structures (the least recently used leaves first).

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen.structure_key import StructureCache
    >>> from mbcomp.library import World, Revolute, PointMass
    >>> def model(m):
    ...     mdl = mbcomp.Model(); w = mdl.add("world", World()); j = mdl.add("j", Revolute())
    ...     b = mdl.add("b", PointMass(m=m)); mdl.connect(w.frame_b, j.frame_a); mdl.connect(j.frame_b, b.frame_a)
    ...     return mbcomp.assemble(mdl)
    >>> cache = StructureCache(size=2)
    >>> codes, hit = cache.entry(model(1.0), "python")
    >>> codes["eval"] = "a program"
    >>> codes2, hit2 = cache.entry(model(5.0), "python")
    >>> hit, hit2, codes2["eval"]
    (False, True, 'a program')
    """

    def __init__(self, size=16):
        self.size = size
        self._entries = OrderedDict()
        self.hits = self.misses = 0

    def entry(self, system, backend, options=(), signature=None):
        key, refs = structure_key(system, backend, options, signature)
        got = self._entries.get(key)
        if got is not None:
            self._entries.move_to_end(key)
            self.hits += 1
            return got[0], True
        self.misses += 1
        codes = {}
        self._entries[key] = (codes, refs)
        while len(self._entries) > self.size:
            self._entries.popitem(last=False)
        return codes, False

    def clear(self):
        """Forget every structure (the compiled libraries stay cached on disk)."""
        self._entries.clear()

    def __len__(self):
        return len(self._entries)


#: the process's programs by structure (what ``simulate`` reuses)
STRUCTURES = StructureCache()
