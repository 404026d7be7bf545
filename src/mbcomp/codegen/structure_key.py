"""The structure of an assembled system as a key, computed without tracing: what a generated
program bakes in, so that a model rebuilt with other parameter or start values finds the
programs a first run traced and printed (:class:`StructureCache`).

A program is a function of the runtime parameters (every nonzero number of a numeric
parameter, :func:`~mbcomp.codegen.tracer.param_layout`) and of the state; everything else is
part of it. :func:`structure_key` gathers that everything:

* the components: path and class of every leaf, and every attribute a component keeps
  besides its declared parameters (by value where it is plain data, else by identity);
* the connections (in order: the spanning tree follows it), the bodies marked free (the
  fingerprint of :meth:`FlatModel.structure <mbcomp.modeling.model.FlatModel.structure>`,
  taken once per model: the assembly's topology plans key on it too);
* what the topology chose from parameter values (:meth:`~mbcomp.assembly.topology.Topology.choices`:
  the spanning tree, which fixed start values steer; the gravity source; the free joints' kinds);
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

from ..modeling.fingerprint import Key, fingerprint
from .toolchain import c_compiler
from .tracer import param_signature
from .tracing import drives

__all__ = ["structure_key", "StructureCache", "STRUCTURES", "compiler"]

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


def structure_key(system, backend, options=(), signature=None):
    """``(key, refs)``: the structure of ``system`` as a hashable key (see the module notes)
    for programs printed for ``backend`` with ``options`` (hashable: node limit, compiler,
    flags); ``refs``, the objects the key holds by identity, to keep alive while it is used.
    ``signature``: :func:`~mbcomp.codegen.tracer.param_signature` ``(system)`` when the caller has it."""
    topo = system.topology
    structure, own = topo.flat.structure()  # taken once per model: the assembly's plan keyed on it too
    refs = [own]
    driving = drives(system)
    drive_params = tuple((path, fingerprint(sorted(vars(system.P[path]).items()), refs)) for path in driving)
    if signature is None:
        signature = param_signature(system)
    # the non-numeric values beyond what the signature holds by value (None and strings: nothing more)
    laws = tuple(fingerprint(x, refs) for x in signature if x[2] == "o" and not (x[3][0] == "v" and (
        x[3][1] is None or type(x[3][1]) is str)))
    nonholonomic = tuple(e.name for e in system.nonholonomic)
    key = (backend, tuple(options), structure, topo.choices(), drive_params, signature, laws, nonholonomic)
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
        key = Key(key)  # hashed once for the lookup and the reordering
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
