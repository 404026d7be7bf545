"""A printed program loaded to run: one output group of a :class:`~mbcomp.codegen.printers.Program`
as a Python function or a C function (compiled and cached by
:func:`~mbcomp.codegen.toolchain.cached_library`), with its parameter program.

Every derivative program (the exact Jacobians, the DAE forms', the sensitivities', the
adjoint's) is printed and loaded the same way; :class:`LoadedProgram` is that one way. The
function's arguments are those of every generated program: ``(q, u, t, d, h, p, w, out)`` --
coordinates, speeds, time (s), per-call inputs, hoisted parameter values, parameters, work
array, output (C: pointers; Python: ``fun(q, u, t, d, h)`` returning the output list).

Examples
--------
>>> from mbcomp.codegen.graph import Graph
>>> from mbcomp.codegen.printers import Program
>>> from mbcomp.codegen.loaded import LoadedProgram
>>> with Graph() as g:
...     x, k = g.input("q", 0, 0.5), g.input("p", 0, 4.0, state=False)
...     y = k * k * x
>>> lp = LoadedProgram(Program(g, {"out": [y]}), "out", "mbcomp_out", "python", None, "an example program")
>>> lp.fun([0.5], [], 0.0, [], lp.pre.run([4.0]))
[8.0]
"""
from __future__ import annotations

import ctypes

from .graph import CodegenError, Fallback, Retrace
from .printers import PY_ENV, ParamProgram
from .toolchain import FLAGS, HEADER, cached_library, chunk, n_units

__all__ = ["LoadedProgram", "PROGRAM_ARGTYPES", "bind_cached"]

#: the ctypes argument types of every generated program: ``q, u, t, d, h, p, w, out``
PROGRAM_ARGTYPES = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double] + [ctypes.c_void_p] * 5


class LoadedProgram:
    """Group ``group`` of the program ``prog`` as a function named ``fname``.

    Parameters
    ----------
    prog : Program
    group : str
        The output group printed.
    fname : str
        The function's name (C: its symbol; the cache key of its library).
    backend : {"python", "c"}
    cache_dir : str or None
        Where the compiled library is cached (None: the default cache).
    what : str
        What the program is, for the error messages ("Jacobian program").

    Raises
    ------
    ValueError
        When ``backend`` is neither ``"python"`` nor ``"c"`` (before any compile).

    Attributes
    ----------
    pre : ParamProgram
        The hoisted parameter program: ``pre.run(parameter values)`` gives ``h``.
    fun : callable
        Python backend: ``fun(q, u, t, d, h) -> list``.
    dll, cfun : ctypes objects
        C backend: the library and the function (argument types set).
    n_work : int
        C backend: doubles of work array the function needs.
    n_ops : int
        Operations per call.
    """

    def __init__(self, prog, group, fname, backend, cache_dir, what):
        if backend not in ("python", "c"):
            raise ValueError(f"{what}: backend {backend!r} is unknown; use 'python' or 'c'")
        self.backend, self.fname = backend, fname
        self.pre = ParamProgram(prog)
        self.n_ops = prog.n_ops(group)
        self.n_work = 0
        if backend == "python":
            env = dict(PY_ENV, _Fallback=Fallback, _Retrace=Retrace)
            exec(compile(prog.python_main(group, fname), f"<mbcomp.codegen {fname}>", "exec"), env)
            self.fun = env[fname]
        else:
            parts, self.n_work = prog.c_parts(group, fname, chunk, n_parts=n_units)
            units = [(f"{fname}{k}", HEADER + src, list(FLAGS)) for k, src in enumerate(parts)]
            self.dll = cached_library(units, fname, cache_dir, what)
            self.cfun = getattr(self.dll, fname)
            self.cfun.argtypes = PROGRAM_ARGTYPES
            self.cfun.restype = ctypes.c_int


def bind_cached(codes, key, build, system):
    """``code.bind(system)`` with the code taken from ``codes[key]`` or made by ``build()`` and
    put there (a dict shared by systems differing only in parameter values): made again once
    when the cached code does not bind (the parameters changed a decision baked into it). None
    when ``build()`` gives None or raises :class:`~mbcomp.codegen.graph.CodegenError` (remembered:
    not tried again), or a fresh code does not bind either.

    Examples
    --------
    >>> from mbcomp.codegen.loaded import bind_cached
    >>> class Code:                     # binds to systems (here: numbers) below its limit
    ...     def __init__(self, limit): self.limit = limit
    ...     def bind(self, system): return (self, system) if system < self.limit else None
    >>> codes = {}
    >>> bind_cached(codes, "k", lambda: Code(10), 3)[1], codes["k"].limit
    (3, 10)
    >>> bind_cached(codes, "k", lambda: Code(100), 50)[0].limit     # no longer binds: made again
    100
    """
    for _ in range(2):
        code = codes.get(key, False)
        if code is False:
            try:
                code = build()
            except CodegenError:
                code = None
            codes[key] = code
        if code is None:
            return None
        bound = code.bind(system)
        if bound is not None:
            return bound
        codes[key] = False
    return None
