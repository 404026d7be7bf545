"""Turning a trace into callables: the Python program (``compile``) or the C program (a
shared library built by :mod:`~mbcomp.codegen.toolchain`, cached on disk, loaded with
:mod:`ctypes`).

A :class:`Code` is shared by every system that differs only in parameter values; a
:class:`Bound` is a code bound to one parameter set (the hoisted values, the C buffers) and
runs it. C libraries are cached in ``cache_dir``, ``$MBCOMP_CACHE`` or ``~/.cache/mbcomp``
under a hash of the generated source, the flags, the compiler and the platform.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.codegen.compiler import Bound, Code
>>> from mbcomp.codegen.tracer import trace
>>> from mbcomp.library import World, Prismatic, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
>>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> system = mbcomp.assemble(m)
>>> code = Code(trace(system, max_nodes=1000), "python")
>>> Bound(code, system.with_params({"b.m": 3.0})).run(0.0, np.zeros(1), np.zeros(1))[:2].tolist()   # M, f
[3.0, -29.43]
"""
from __future__ import annotations

import concurrent.futures
import ctypes
import hashlib
import os
import threading
import time

import numpy as np

from .engine import integrate_signature, runtime_objects
from .graph import CodegenError, Fallback, Retrace, no_gc
from .printers import PY_ENV, ParamProgram, Program
from .runtime_build import copy_installed_extensions
from .thin import extension
from .toolchain import (FLAGS, HEADER, c_compiler, cache_directory, chunk, compile_objects, compile_units, load_library,
                        n_units,
                        object_path, runtime_directory, unit_key)
from .tracer import FIELDS, param_vector

__all__ = ["Code", "Bound", "prepare_runtime"]

#: kept for compatibility: every program is now compiled at -O2
OPT_O2 = OPT_O1 = float("inf")


#: (compiler, cache directory) -> the futures (runtime objects, thin extension); also the
#: arguments and environment a call was made with -> the same futures
_PREPARED = {}
_PREPARED_LOCK = threading.Lock()


def _forget_prepared():
    """In a forked child: the parent's threads are not there, so neither are their futures."""
    global _PREPARED_LOCK
    _PREPARED.clear()
    _PREPARED_LOCK = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_prepared)


def _in_thread(fn, *args):
    """``fn(*args)`` run on a new (non-daemon: the interpreter waits for it at exit, so no
    compiler is left half-way) thread, as a future."""
    fut = concurrent.futures.Future()

    def work():
        try:
            fut.set_result(fn(*args))
        except BaseException as exc:  # handed to whoever waits for it
            fut.set_exception(exc)
    threading.Thread(target=work, name="mbcomp-runtime", daemon=False).start()
    return fut


def prepare_runtime(cache_dir=None):
    """Start building what every C program of this machine shares, if it is not built: the
    runtime's core objects (:func:`~mbcomp.codegen.engine.runtime_objects`: the explicit
    integrators, events, mechanics kernels, ~0.8 s of gcc, copied instead from what the install
    built where it did: :mod:`~mbcomp.codegen.runtime_build`; RADAU5 is built at its first use)
    and the thin call's extension (:func:`~mbcomp.codegen.thin.extension`),
    each on a thread of its own, once per process and directory. They go to
    :func:`~mbcomp.codegen.toolchain.runtime_directory` (``$MBCOMP_RUNTIME``, else
    ``~/.cache/mbcomp``), not into each programs' cache: built once per machine, linked by the
    programs of every cache. Returns the two futures ``(runtime, thin)``, or None without a C
    compiler.

    :func:`mbcomp.simulate` calls it first (before importing and tracing anything), so that on a
    machine's first run the compiler works while Python does; a program's build waits for what
    it links (:class:`Code`). With everything built it costs a hash of the runtime's sources and
    a few file checks, off the calling thread, once; ~2 us when asked again.

    Examples
    --------
    >>> from mbcomp.codegen.compiler import prepare_runtime
    >>> jobs = prepare_runtime()
    >>> jobs is None or all(o.endswith(".o") for o in jobs[0].result())   # the runtime's object files
    True
    >>> jobs is None or jobs is prepare_runtime()                         # once per process
    True
    """
    asked = (cache_dir,) + tuple(os.environ.get(k) for k in ("CC", "MBCOMP_CACHE", "MBCOMP_RUNTIME", "HOME", "PATH"))
    jobs = _PREPARED.get(asked)  # asked before: no compiler search, no directory made (~1 us)
    if jobs is not None and not (jobs[0].done() and jobs[0].exception() is not None):
        return jobs
    cc = c_compiler()
    if cc is None:
        return None
    d = runtime_directory(cache_dir)
    with _PREPARED_LOCK:
        jobs = _PREPARED.get((cc, d))
        if jobs is None or (jobs[0].done() and jobs[0].exception() is not None):  # a failure is tried again
            jobs = _PREPARED[(cc, d)] = (_in_thread(runtime_objects, cc, d), _in_thread(_extension, d))
        _PREPARED[asked] = jobs
    return jobs


def _extension(d):
    """The thin call's extension in the runtime directory ``d``: the install's copied there
    where it built one for this Python and numpy, else compiled."""
    copy_installed_extensions(d)
    return extension(d)


class Code:
    """A traced model turned into callables (shared by systems differing only in parameter values)."""

    def __init__(self, tr, backend, cache_dir=None):
        with no_gc():
            self._make(tr, backend, cache_dir)

    def _make(self, tr, backend, cache_dir):
        t0 = time.perf_counter()
        self.layout, self.signature, self.drives, self.inputs = tr.layout, tr.signature, tr.drives, tr.inputs
        self.shapes, self.baked, self.qrate_identity = tr.shapes, tr.baked, tr.qrate_identity
        off, self.slices, self.layout_out = 0, {}, []
        for name in FIELDS:
            shape = self.shapes[name]
            n = int(np.prod(shape, dtype=int))
            self.slices[name] = (off, off + n, shape)
            empty = None
            if n == 0:  # one shared read-only empty array instead of a view per call
                empty = np.zeros(shape)
                empty.setflags(write=False)
            self.layout_out.append((name, off, off + n, shape if len(shape) > 1 else None, empty))
            off += n
        self.n_out = off
        prog = Program(tr.graph, tr.groups, guard_groups=tr.guard_groups)
        self.n_ops = prog.n_ops("eval")
        self.n_ops_qrate = 0 if tr.qrate_identity else prog.n_ops("qrate")
        self.n_hoisted = len(prog.hoisted)
        self.n_guards = (len(prog.param_guards), len(prog.state_guards))
        self.state_guards = {name: len(prog.guards_of[name]) for name in tr.groups}
        self.n_nodes = len(tr.graph)
        env = dict(PY_ENV, _Fallback=Fallback, _Retrace=Retrace)
        self.pre = ParamProgram(prog)
        self.n_ops_params = len(self.pre)
        self.backend = backend
        self.cache = None
        self.nq = len(tr.groups["qrate"])
        self.has_fun = "fun" in tr.groups
        self.n_ops_fun = prog.n_ops("fun") if self.has_fun else 0
        if backend == "python":
            src = prog.python_main("eval", "main") + "\n\n" + prog.python_main("qrate", "qrate")
            if self.has_fun:
                src += "\n\n" + prog.python_main("fun", "fun")
            exec(compile(src, "<mbcomp.codegen program>", "exec"), env)
            self.main, self.qrate, self.fun = env["main"], env["qrate"], env.get("fun")
            self.source = src
        else:
            self._build_c(prog, cache_dir)
            self.source = self.c_source
        self.compile_time = time.perf_counter() - t0

    has_engine = False

    def _build_c(self, prog, cache_dir):
        cc = c_compiler()
        if cc is None:
            raise CodegenError("backend='c' needs a C compiler (gcc or cc on PATH, or $CC) -> fix: install one, "
                               "or use backend='python' (no compiler needed) or backend='auto'")
        # see "Compile policy" in docs/design/generated-programs.md: -O2 on every program, output
        # expressions of one shape rolled into loops (M's O(N^2) entries), the straight-line
        # rest in functions of CHUNK statements split into translation units compiled in
        # parallel and cached one by one (the Lagrange program's build reuses what is equal)
        units, n_work = [], 1
        groups = [("eval", "mbcomp_eval"), ("qrate", "mbcomp_qrate")] + ([("fun", "mbcomp_fun")] if self.has_fun else [])
        self.n_statements = {}
        for group, fname in groups:
            def n_parts(n, group=group):
                self.n_statements[group] = n
                return n_units(n)

            parts, n_w = prog.c_parts(group, fname, chunk, n_parts=n_parts)
            n_work = max(n_work, n_w)
            for k, src in enumerate(parts):
                units.append((f"{group}{k}" if len(parts) > 1 else group, HEADER + src, list(FLAGS)))
        self.n_work = n_work
        self.c_source = "\n".join(src for _, src, _ in units)
        self.opt = {group: FLAGS[0] for group, _ in groups}
        self.n_units = len(units)
        d = cache_directory(cache_dir)
        # the C engine (the runtime's integrators over mbcomp_fun) when no drive needs Python per call
        self.has_engine = self.has_fun and not self.drives and not self.inputs
        self.objects = {"compiled": [], "reused": []}
        extra = []
        if self.has_engine:
            # the runtime's objects and the thin call's extension (built once per machine, maybe
            # started already by simulate) while this program's units compile
            runtime, thin = prepare_runtime(cache_dir)
            if not all(os.path.exists(object_path(cc, d, src, fl)) for _, src, fl in units):
                self.objects = compile_objects(cc, units, d)[1]
                thin.result()  # (None where it cannot be built) its compiler ran beside this program's
            extra = runtime.result()
        key = hashlib.sha256("\0".join([unit_key(cc, src, fl) for _, src, fl in units] + list(extra))
                             .encode()).hexdigest()[:32]
        lib = os.path.join(d, f"mbcomp_{key}.so")
        if os.path.exists(lib):
            self.cache = "hit"
        else:
            self.cache = "miss"
            done = compile_units(cc, units, lib, d, extra)
            self.objects["compiled"] += done["compiled"]
            self.objects["reused"] = [n for n in done["reused"] if n not in self.objects["compiled"]]
        self.lib_path = lib
        self.dll = load_library(lib)
        argt = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p,
                ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
        for fn in (self.dll.mbcomp_eval, self.dll.mbcomp_qrate) + ((self.dll.mbcomp_fun,) if self.has_fun else ()):
            fn.argtypes = argt
            fn.restype = ctypes.c_int
        if self.has_engine:
            integrate_signature(self.dll)


class Bound:
    """A :class:`Code` bound to one parameter set (hoisted values, buffers)."""

    def __init__(self, code, system, first=False):
        self.code = code
        pv = param_vector(system, code.layout)
        self.pv = pv
        self.nq, self.nu = system.nq, system.nu
        # the traced values themselves: the trace-time values; new ones: the parameter program
        # (which raises Retrace when a parameter guard fails)
        self.h = list(code.pre.shadow) if first else code.pre.run(pv)
        self.drive_comps = [(system.topology.flat.components[d], system.P[d]) for d in code.drives]
        if code.backend == "c":
            self.hbuf = np.array(self.h + [0.0], float)
            self.pbuf = np.array(pv + [0.0], float)
            self.qbuf = np.zeros(max(system.nq, 1))
            self.ubuf = np.zeros(max(system.nu, 1))
            # drives' (s, v, a), then Baumgarte alpha, beta, then the external inputs' values
            self.dbuf = np.zeros(3 * len(code.drives) + 2 + len(code.inputs))
            self.ybuf = np.zeros(system.nq + system.nu + 1)
            self.wbuf = np.zeros(code.n_work)
            self.obuf = np.zeros(max(code.n_out, 1))
            self.qdbuf = np.zeros(max(system.nq, 1))
            self.ptrs = [a.ctypes.data for a in (self.qbuf, self.ubuf, self.dbuf, self.hbuf, self.pbuf, self.wbuf,
                                                 self.obuf, self.qdbuf, self.ybuf)]
            # run_fun's input: y = [q, u] copied once into one buffer, q and u pointers into it
            self.yin = np.zeros(system.nq + system.nu + 1)
            base = self.yin.ctypes.data
            self.fun_args = (base, base + 8 * system.nq)
            self.gains = None

    def drive_values(self, t):
        d = []
        for comp, p in self.drive_comps:
            d.extend(comp.motion(t, p))
        return d

    def input_values(self, t):
        """The external inputs' values at ``t`` (s), in their slots' order."""
        return [inp.value(t) for inp in self.code.inputs]

    def per_call(self, t):
        """Write the per-call inputs at ``t`` into the C buffer: the drives' ``(s, v, a)`` and,
        after the two gains' slots, the external inputs' values."""
        nd = 3 * len(self.drive_comps)
        if nd:
            self.dbuf[:nd] = self.drive_values(t)
        if self.code.inputs:
            self.dbuf[nd + 2:] = self.input_values(t)

    def run(self, t, q, u):
        code = self.code
        if code.backend == "python":
            d = (self.drive_values(t) + [0.0, 0.0] + self.input_values(t)) if code.inputs else (
                self.drive_values(t) if self.drive_comps else ())
            return np.array(code.main(q.tolist(), u.tolist(), float(t), d, self.h), float)
        self.qbuf[: q.size] = q
        self.ubuf[: u.size] = u
        if self.drive_comps or code.inputs:
            self.per_call(t)
        pq, pu, pd, ph, pp, pw, po, _, _ = self.ptrs
        if code.dll.mbcomp_eval(pq, pu, float(t), pd, ph, pp, pw, po):
            raise Fallback
        return self.obuf[: code.n_out].copy()

    def run_qrate(self, q, u):
        code = self.code
        if code.backend == "python":
            return np.array(code.qrate(q.tolist(), u.tolist(), 0.0, (), self.h), float)
        self.qbuf[: q.size] = q
        self.ubuf[: u.size] = u
        pq, pu, pd, ph, pp, pw, _, pqd, _ = self.ptrs
        if code.dll.mbcomp_qrate(pq, pu, 0.0, pd, ph, pp, pw, pqd):
            raise Fallback
        return self.qdbuf[: code.nq].copy()

    def c_pointers(self):
        """The arguments of the C ``mbcomp_fun`` over this binding's buffers, ``(q, u, t, d, h,
        p, w, out)`` with ``t`` = 0 (the state last given to :meth:`run_fun`): the bare C call
        a benchmark compares the Python callers with."""
        _, _, pd, ph, pp, pw, _, _, py = self.ptrs
        return (*self.fun_args, 0.0, pd, ph, pp, pw, py)

    def run_fun(self, t, y, alpha, beta):
        """``dy/dt`` of the Lagrange index-1 form at ``y = [q, u]`` with Baumgarte gains
        ``alpha``, ``beta`` (1/s; zero for none); raises Fallback when a guard fails."""
        code = self.code
        nd = 3 * len(self.drive_comps)
        if code.backend == "python":
            d = (self.drive_values(t) if self.drive_comps else []) + [alpha, beta] + self.input_values(t)
            out = np.array(code.fun(y[: self.nq].tolist(), y[self.nq:].tolist(), float(t), d, self.h), float)
            if not np.isfinite(out).all():  # a domain error: the numeric path raises or agrees
                raise Fallback
            return out
        if nd or code.inputs:
            self.per_call(t)
        if self.gains != (alpha, beta):  # the gains change once per run, not per call
            self.dbuf[nd] = alpha
            self.dbuf[nd + 1] = beta
            self.gains = (alpha, beta)
        n = y.size
        self.yin[:n] = y
        _, _, pd, ph, pp, pw, _, _, py = self.ptrs
        pq, pu = self.fun_args
        if code.dll.mbcomp_fun(pq, pu, float(t), pd, ph, pp, pw, py):
            raise Fallback
        out = self.ybuf[: y.size].copy()
        if not np.isfinite(out).all():  # a domain error (0/0 in a law): the numeric path raises or agrees
            raise Fallback
        return out
