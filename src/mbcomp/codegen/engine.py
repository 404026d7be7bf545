"""The compiled engine: the Lagrange right-hand side program stepped by the C runtime's
explicit integrators (:mod:`mbcomp.codegen.runtime`: DOPRI5, DOP853), so a whole stretch of
a run is one C call; and the runtime's mechanics kernels over a model's evaluation program
(the D'Alembert right-hand side, the projection onto the constraint manifold).

A generated C library whose model has a Lagrange program (``mbcomp_fun``) and no drives
(their motion laws are Python, evaluated per call) also gets a small glue unit
(:data:`GLUE`): ``mbcomp_integrate`` runs a runtime integrator over ``mbcomp_fun`` with the
program's parameter values, writes the states at the requested output times and records the
last accepted step (time and state), so that a run stopped by a failed guard (a law's branch,
a singular matrix) can go on from there on the Python path. Given a :class:`Mech` of the
model's evaluation program it projects ``[q, u]`` onto the constraint manifold after every
accepted step (``mbrt_project``, the steps of
:meth:`mbcomp.formulations.LagrangeIndex1.project`); the outputs are the dense output of the
unprojected steps, as the Python driver's, which projects them when it keeps them. The
runtime is compiled once per machine (or copied from what the install built) into the
machine's runtime directory (:func:`runtime_objects`, :mod:`~mbcomp.codegen.runtime_build`):
its core, which every such library links, and RADAU5 apart, a library of its own built at a
run's first radau5 step in C (:func:`part_library`).

The mechanics kernels need only the evaluation program, which lives in another library than
``mbcomp_fun`` (and exists with drives too): they reach it through function pointers
(:class:`Mech`), from a model-independent library of the runtime alone
(:func:`runtime_library`, built once per machine). :class:`DAlembertProgram` is the
D'Alembert right-hand side in one call of it.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.codegen import c_compiler, compile_system
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> if c_compiler():
...     eng = compile_system(mbcomp.assemble(m), "c").evaluator.integrator(0.0, 0.0)
...     out = eng.integrate(8, 0.0, np.array([0.5, 0.0]), 1.0, np.array([0.5, 1.0]), 1e-10, 1e-12)
...     print(out.status, out.Y.shape, abs(out.Y[-1, 0] - out.Y[0, 0]) > 0.1)
... else:
...     print(0, (2, 2), True)
0 (2, 2) True
"""
from __future__ import annotations

import ctypes
import hashlib
import os
import subprocess
import tempfile
from types import SimpleNamespace

import numpy as np

from .graph import CodegenError
from .c_events import LinearEvents, RuntimeStats
from .runtime_build import GLUE, RuntimeBuildError, build_objects
from .toolchain import c_compiler, load_library, runtime_directory

__all__ = ["GLUE", "Integrator", "LinearEvents", "Mech", "DAlembertProgram", "runtime_objects", "runtime_library",
           "part_library",
           "coordinate_map", "mech_of", "dalembert_program", "DAEProgram", "dae_program", "STATUS", "MECH_STATUS",
           "PROJECT_MAX_ITER"]

#: the runtime's status codes (``mbrt.h``)
STATUS = {0: "reached t_end", 1: "a guard of the program failed", 2: "step size too small",
          3: "too many steps", 4: "non-finite state", 5: "stopped", 6: "bad argument",
          7: "the problem became stiff", 8: "an event was located"}


def runtime_objects(cc, cache_dir, part="core"):
    """Object files of a part of the runtime (:mod:`~mbcomp.codegen.runtime_build`): ``"core"``
    the runtime's sources but RADAU5 and :data:`GLUE`, ``"radau"`` RADAU5's; each built once
    (copied from the install's, else compiled in parallel) and cached in ``cache_dir`` under a
    hash of its part's sources and flags."""
    try:
        return build_objects(cc, cache_dir, part)
    except RuntimeBuildError as exc:
        raise CodegenError(f"{exc} -> fix: use backend='python'") from exc


def _link(cc, objs, lib):
    """Link ``objs`` into the shared library ``lib`` (replaced atomically)."""
    with tempfile.TemporaryDirectory(dir=os.path.dirname(lib)) as tmp:
        out = os.path.join(tmp, "mbrt.so")
        res = subprocess.run([cc, "-shared", "-o", out, *objs, "-lm"], capture_output=True, text=True)
        if res.returncode != 0:
            raise CodegenError(f"the C linker failed on the runtime ({cc}): {res.stderr[-2000:]} -> fix: use "
                               "backend='python'")
        os.replace(out, lib)


def runtime_library(cc, cache_dir):
    """The runtime alone (no model) as a shared library, built once per machine from the
    objects of :func:`runtime_objects` and cached beside them; loaded once per process, with
    the ctypes signatures of the mechanics kernels (``mbrt_dalembert_rhs``, ``mbrt_project``,
    ``mbrt_mech_work_size``, ``mbrt_cond2``). Models reach it through function pointers to
    their programs (:class:`Mech`), so one library serves every model."""
    objs = [o for o in runtime_objects(cc, cache_dir) if not o.endswith("_mbcomp_glue.o")]
    key = hashlib.sha256("\0".join(objs).encode()).hexdigest()[:16]
    lib = os.path.join(cache_dir, f"mbrt_{key}.so")
    dll = _LIBRARIES.get(lib)
    if dll is not None:
        return dll
    if not os.path.exists(lib):
        _link(cc, objs, lib)
    dll = load_library(lib)
    vp, i, d = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    dll.mbrt_mech_work_size.argtypes = [vp]
    dll.mbrt_mech_work_size.restype = ctypes.c_size_t
    dll.mbrt_dalembert_rhs.argtypes = [vp, d, vp, vp, vp, i, vp, vp, vp, vp, vp]
    dll.mbrt_dalembert_rhs.restype = i
    dll.mbrt_project.argtypes = [vp, d, vp, d, i, d, vp, vp]
    dll.mbrt_project.restype = i
    dll.mbrt_cond2.argtypes = [i, vp, vp]
    dll.mbrt_cond2.restype = d
    dll.mbrt_dae_fun.argtypes = [vp, i, d, vp, vp, vp, vp, vp, vp]
    dll.mbrt_dae_fun.restype = i
    dll.mbrt_dae_size.argtypes = [vp, i]
    dll.mbrt_dae_size.restype = i
    dll.mbrt_dae_work_size.argtypes = [vp, i]
    dll.mbrt_dae_work_size.restype = ctypes.c_size_t
    dll.mbrt_dop853_work_size.argtypes = [i]  # the integrator alone, over a C glue's right-hand side
    dll.mbrt_dop853_work_size.restype = ctypes.c_size_t
    dll.mbrt_dop853.argtypes = [vp, vp, vp, i, d, vp, d, d, vp, d, d, ctypes.c_long, vp, i, vp, vp, vp, vp]
    dll.mbrt_dop853.restype = i
    _LIBRARIES[lib] = dll
    return dll


_LIBRARIES = {}


def part_library(cc, cache_dir, part):
    """A part of the runtime built apart from the core (:data:`~mbcomp.codegen.runtime_build.PARTS`:
    ``"radau"``, RADAU5: ``mbrt_radau5``, ``mbrt_radau5_dense``, the work sizes, the program
    callbacks ``mbrt_prog_ode_rhs``/``_jac``; ``"pass"``, the passage of singular positions:
    ``mbrt_pass_integrate``, ``mbrt_pass_rhs``) as a shared library of its own: the part's objects
    (:func:`runtime_objects`) and the core's but the glue (whatever of them the part calls),
    compiled and linked the first time a run uses the part (a machine's first run that does not
    use it does not wait for it), cached in ``cache_dir``, loaded once per process. It reaches
    a model's programs through function pointers (``mbrt_prog_ode``, ``mbrt_mech``)."""
    dll = _PARTS.get((cc, cache_dir, part))  # asked before in this process: no sources hashed again
    if dll is not None:
        return dll
    objs = runtime_objects(cc, cache_dir, part)
    objs += [o for o in runtime_objects(cc, cache_dir) if not o.endswith("_mbcomp_glue.o")]
    key = hashlib.sha256("\0".join(objs).encode()).hexdigest()[:16]
    lib = os.path.join(cache_dir, f"mbrt_{part}_{key}.so")
    dll = _LIBRARIES.get(lib)
    if dll is None:
        if not os.path.exists(lib):
            _link(cc, objs, lib)
        dll = _LIBRARIES[lib] = load_library(lib)
    _PARTS[(cc, cache_dir, part)] = dll
    return dll


_PARTS = {}

#: ``mbrt_mech.c``'s status codes (``mbrt.h``)
MECH_STATUS = {0: "ok", 1: "fallback", 2: "singular", 3: "mass singular", 4: "no convergence", -1: "bad argument"}
#: Newton steps of a projection at most: :func:`mbcomp.assembly.manifold.close_positions`' default
PROJECT_MAX_ITER = 8


class _Mech(ctypes.Structure):
    _fields_ = ([(n, ctypes.c_void_p) for n in ("eval", "qrate", "d", "h", "p", "w")]
                + [(n, ctypes.c_int) for n in ("nq", "nu", "n_out", "mh", "mn", "nrows")]
                + [("rows", ctypes.c_void_p)]
                + [(f"off_{n}", ctypes.c_int) for n in ("M", "f", "Phi", "Phid", "C", "cb", "B", "Bb", "Psi")]
                + [("nseg", ctypes.c_int), ("seg", ctypes.c_void_p)])


class Mech:
    """A C evaluation program as the runtime's mechanics kernels see it (``mbrt_mech`` in
    ``mbrt.h``): pointers to the program's ``mbcomp_eval`` and ``mbcomp_qrate`` and to the
    bound parameter set's buffers, the layout of the flat output, and the holonomic rows
    kept by the system's row mask.

    Parameters
    ----------
    bound : mbcomp.codegen.compiler.Bound
        The *evaluation* program (C backend) bound to its parameter values.
    system : MultibodySystem
        Its system (the row mask is read now: build after consistent initialization).

    Attributes
    ----------
    struct : ctypes.Structure
        The ``mbrt_mech``; it points into ``bound``'s buffers and :attr:`rows`, which this
        object keeps alive.
    work : ndarray
        ``mbrt_mech_work_size`` doubles of scratch.
    """

    def __init__(self, bound, system, lib):
        code = bound.code
        self.bound, self.lib = bound, lib
        sl = code.slices
        mh = sl["Phi"][1] - sl["Phi"][0]
        mn = sl["Psi"][1] - sl["Psi"][0]
        rm = system.row_mask
        if rm is not None and len(rm) != mh:
            raise ValueError(f"the row mask has {len(rm)} entries for {mh} holonomic rows")
        self.rows = np.ascontiguousarray(np.arange(mh) if rm is None else np.flatnonzero(rm), dtype=np.intc)
        self.rows_ref = rm
        self.nq, self.nu, self.mh, self.mn = bound.nq, bound.nu, mh, mn
        self.m = len(self.rows) + mn
        fn = ctypes.cast(code.dll.mbcomp_eval, ctypes.c_void_p).value
        qr = None if code.qrate_identity else ctypes.cast(code.dll.mbcomp_qrate, ctypes.c_void_p).value
        cmap = coordinate_map(system)
        self.moves = cmap is not None  # mbrt_project can move these coordinates
        self.seg = np.ascontiguousarray(cmap if cmap is not None else np.zeros((0, 4)), dtype=np.intc)
        self.struct = _Mech(fn, qr, bound.dbuf.ctypes.data, bound.hbuf.ctypes.data, bound.pbuf.ctypes.data,
                            bound.wbuf.ctypes.data, bound.nq, bound.nu, code.n_out, mh, mn, len(self.rows),
                            self.rows.ctypes.data if len(self.rows) else None,
                            *(sl[n][0] for n in ("M", "f", "Phi", "Phid", "C", "cb", "B", "Bb", "Psi")),
                            len(self.seg), self.seg.ctypes.data if len(self.seg) else None)
        self.ptr = ctypes.addressof(self.struct)
        self.work = np.zeros(int(lib.mbrt_mech_work_size(self.ptr)))

    def project(self, t, y, tol, accept, max_iter=PROJECT_MAX_ITER):
        """``y = [q, u]`` moved onto the manifold by ``mbrt_project`` (see ``mbrt.h``):
        ``(status, y, |Phi|)`` with ``status`` a key of :data:`MECH_STATUS`; ``y`` is the
        projected copy on success, else the input."""
        y = np.array(y, dtype=float)
        norm = ctypes.c_double(0.0)
        rc = self.lib.mbrt_project(self.ptr, float(t), y.ctypes.data, float(tol), int(max_iter), float(accept),
                                   ctypes.addressof(norm), self.work.ctypes.data)
        return int(rc), y, norm.value


class DAlembertProgram:
    """The D'Alembert right-hand side in one C call (``mbrt_dalembert_rhs``) over a C
    evaluation program: dependent speeds, the second evaluation, ``N``, ``w``,
    ``N^T M N`` by Cholesky and the conditioning figures of the partition.

    Parameters
    ----------
    bound : mbcomp.codegen.compiler.Bound
        The evaluation program (C backend) bound to its parameter values.
    system : MultibodySystem
        Its (initialized) system.
    lib : ctypes.CDLL
        :func:`runtime_library`.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen import c_compiler, compile_system
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World())
    >>> j = m.add("j", Revolute(phi0=0.5)); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> if c_compiler():     # an open tree: N = I, dv/dt = M^-1 f = -g sin(phi) / l
    ...     ev = compile_system(mbcomp.assemble(m), "c").evaluator
    ...     status, dy, growth, cond = ev.dalembert_fun(0.0, np.array([0.5, 0.0]), np.zeros(0, int), np.arange(1))
    ...     print(status, round(float(dy[1]), 6))
    ... else:
    ...     print(0, -4.703165)
    0 -4.703165
    """

    def __init__(self, bound, system, lib):
        self.mech = Mech(bound, system, lib)
        self.bound, self.fn = bound, lib.mbrt_dalembert_rhs
        nq, nu = bound.nq, bound.nu
        self.nq = nq
        self.y = np.zeros(nq + nu + 1)
        self.dy = np.zeros(nq + nu + 1)
        self.fig = np.zeros(2)
        self.iwork = np.zeros(2 * nu + 1, dtype=np.intc)
        self.dep = self.ind = np.zeros(1, dtype=np.intc)
        self._part = (None, None)
        d = self.fig.ctypes.data
        self._ptrs = (self.y.ctypes.data, self.dy.ctypes.data, d, d + 8, self.mech.work.ctypes.data,
                      self.iwork.ctypes.data)

    def _partition(self, dep, ind):
        if self._part[0] is dep and self._part[1] is ind:
            return
        # copies: the arrays the caller holds may change later, these must not
        self.dep = np.ascontiguousarray(np.append(np.asarray(dep, int), 0), dtype=np.intc)
        self.ind = np.ascontiguousarray(np.append(np.asarray(ind, int), 0), dtype=np.intc)
        self._part = (dep, ind)
        self._nd, self._ni = len(dep), len(ind)
        self._pdep, self._pind = self.dep.ctypes.data, self.ind.ctypes.data

    def fun(self, t, y, dep, ind):
        """``(status, dy, growth, cond)`` at ``y = [q, v]`` with the partition ``dep``/``ind``
        (index arrays of ``u``): ``status`` a key of :data:`MECH_STATUS`; ``dy`` (``[dq/dt,
        dv/dt]``, 1/s times the state's units), the largest ``|A_d^-1 A_i|`` (ratio of speeds'
        units) and the 2-norm condition number of ``A_d`` when the status is 0."""
        self._partition(dep, ind)
        n = y.size
        self.y[:n] = y
        b = self.bound
        if b.drive_comps or b.code.inputs:
            b.per_call(t)
        py, pdy, pg, pc, pw, piw = self._ptrs
        rc = self.fn(self.mech.ptr, float(t), py, self._pdep, self._pind, self._nd, pdy, pg, pc, pw, piw)
        if rc:
            return int(rc), None, None, None
        return 0, self.dy[: self.nq + self._ni].copy(), float(self.fig[0]), float(self.fig[1])


class DAEProgram:
    """The residual ``F(t, y)`` of a multiplier form as a semi-explicit DAE
    (:mod:`mbcomp.formulations.dae`), and with it the Jacobian ``dF/dy``, in one C call
    each (``mbrt_dae_fun``) over a C evaluation program.

    Parameters
    ----------
    bound : mbcomp.codegen.compiler.Bound
        The evaluation program (C backend) bound to its parameter values.
    system : MultibodySystem
        Its (initialized) system.
    lib : ctypes.CDLL
        :func:`runtime_library`.
    form : {1, 2, 3}
        ``Index1``, ``GGL`` or ``Index3`` (``mbrt.h``'s ``MBRT_DAE_*``).
    gains : (float, float) or None
        Index 1: the Baumgarte ``alpha``, ``beta`` (1/s), None without.
    """

    def __init__(self, bound, system, lib, form, gains=None):
        self.mech = Mech(bound, system, lib)
        self.bound, self.fn, self.form = bound, lib.mbrt_dae_fun, int(form)
        self.n = int(lib.mbrt_dae_size(self.mech.ptr, self.form))
        if self.n < 0:
            raise ValueError(f"unknown DAE form {form}")
        self.work = np.zeros(int(lib.mbrt_dae_work_size(self.mech.ptr, self.form)))
        self.gains = None if gains is None else np.array(gains, float)
        self.y, self.F = np.zeros(self.n), np.zeros(self.n)
        self.nfev = ctypes.c_int(0)
        self._p = (self.y.ctypes.data, None if gains is None else self.gains.ctypes.data, self.F.ctypes.data,
                   ctypes.addressof(self.nfev), self.work.ctypes.data)

    def __call__(self, t, y, jac=False):
        """``(status, F, J, nfev)``: status a key of :data:`MECH_STATUS`; ``F`` (n,), ``J``
        (n, n) when ``jac`` (else None), both None unless the status is 0; ``nfev`` the
        residual evaluations made (1, plus one per finite-difference column)."""
        self.y[:] = y
        b = self.bound
        if b.drive_comps or b.code.inputs:
            b.per_call(t)
        J = np.empty((self.n, self.n)) if jac else None
        py, pg, pF, pn, pw = self._p
        rc = self.fn(self.mech.ptr, self.form, float(t), py, pg, pF, J.ctypes.data if jac else None, pn, pw)
        if rc:
            return int(rc), None, None, self.nfev.value
        return 0, self.F.copy(), J, self.nfev.value


def _library_for(code):
    """:func:`runtime_library` in the machine's runtime directory (the programs' cache of ``code``
    where that cannot be written), or None without a compiler."""
    cc = c_compiler()
    return runtime_library(cc, runtime_directory(os.path.dirname(code.lib_path))) if cc is not None else None


def mech_of(bound, system):
    """:class:`Mech` of a C evaluation program bound to its parameter values, or None without
    a compiler."""
    lib = _library_for(bound.code)
    return Mech(bound, system, lib) if lib is not None else None


def dalembert_program(bound, system):
    """:class:`DAlembertProgram` of a C evaluation program bound to its parameter values, or
    None without a compiler."""
    lib = _library_for(bound.code)
    return DAlembertProgram(bound, system, lib) if lib is not None else None


def dae_program(bound, system, form, gains=None):
    """:class:`DAEProgram` of a C evaluation program bound to its parameter values, or None
    without a compiler."""
    lib = _library_for(bound.code)
    return DAEProgram(bound, system, lib, form, gains) if lib is not None else None


def coordinate_map(system):
    """How the C projection moves the coordinates along the speeds, as ``mbrt_mech``'s segments
    (rows ``(kind, q0, u0, n)``: kind 0 adds ``du[u0:u0+n]`` to ``q[q0:q0+n]``, kind 1 turns the
    unit quaternion ``q[q0:q0+4]`` by the rotation vector ``du[u0:u0+3]``); an empty map when
    every coordinate moves additively (``q + du``); None when some joint's
    :meth:`~mbcomp.roles.Joint.increment` is neither (then the projection stays in Python).

    Each joint is judged by what its own ``increment`` does on two random arguments: the same
    numbers, exactly, as ``q + du`` (additive), :func:`mbcomp.modeling.free_joint.quat_increment`
    (a ball joint's quaternion) or position plus quaternion (a free joint)."""
    from ..modeling.free_joint import quat_increment

    rng = np.random.default_rng(20240601)
    segs, additive = [], True
    for e in system.topology.tree:
        nq, nu = e.q.stop - e.q.start, e.u.stop - e.u.start
        if nq == 0:
            continue
        comp, p = e.comp, system.P[e.name]
        kinds = []
        for _ in range(2):
            q, du = rng.uniform(-1.0, 1.0, nq), rng.uniform(-0.5, 0.5, nu)
            if nq == nu + 1 and nq >= 4:
                q[-4:] /= np.linalg.norm(q[-4:])
            try:
                got = np.asarray(comp.increment(q.copy(), du.copy(), p), float)
            except Exception:  # noqa: BLE001 - whatever it is, it is not one of ours
                return None
            if got.shape != (nq,):
                return None
            if nq == nu and np.array_equal(got, q + du):
                kinds.append("add")
            elif nq == 4 and nu == 3 and np.array_equal(got, quat_increment(q, du)):
                kinds.append("quat")
            elif nq == 7 and nu == 6 and np.array_equal(got[:3], q[:3] + du[:3]) and \
                    np.array_equal(got[3:], quat_increment(q[3:], du[3:])):
                kinds.append("free")
            else:
                return None
        if kinds[0] != kinds[1]:
            return None
        q0, u0 = e.q.start, e.u.start
        if kinds[0] == "add":
            segs.append((0, q0, u0, nq))
        elif kinds[0] == "quat":
            segs.append((1, q0, u0, 1))
            additive = False
        else:
            segs += [(0, q0, u0, 3), (1, q0 + 3, u0 + 3, 1)]
            additive = False
    if additive and system.nq == system.nu:
        return np.zeros((0, 4), int)
    return np.array(segs, int).reshape(-1, 4)


class _Ctx(ctypes.Structure):
    _fields_ = [("nq", ctypes.c_int), ("n", ctypes.c_int), ("d", ctypes.c_void_p), ("h", ctypes.c_void_p),
                ("p", ctypes.c_void_p), ("w", ctypes.c_void_p), ("y_last", ctypes.c_void_p),
                ("t_last", ctypes.c_double), ("h_last", ctypes.c_double), ("mech", ctypes.c_void_p),
                ("mech_work", ctypes.c_void_p), ("proj_tol", ctypes.c_double), ("proj_accept", ctypes.c_double),
                ("proj_iter", ctypes.c_int), ("declined", ctypes.c_int), ("nproj", ctypes.c_long),
                ("stiff_steps", ctypes.c_int), ("events", ctypes.c_void_p)]


class Integrator:
    """A bound program's right-hand side stepped in C (see the module notes).

    Parameters
    ----------
    bound : mbcomp.codegen.compiler.Bound
        A C program bound to its parameter values, with ``mbcomp_fun`` and no drives.
    alpha, beta : float
        Baumgarte gains (1/s; zero for none).
    mech : Mech, optional
        The evaluation program of the same system: project ``[q, u]`` onto the constraint
        manifold after every accepted step (``mbrt_project``: Newton with minimum-norm steps
        to ``|Phi| <= tol``, accepted below ``accept``, then the minimum-norm speed
        correction), as :meth:`mbcomp.formulations.LagrangeIndex1.project` does; the
        coordinates move as :func:`coordinate_map` says (it must not be None).
    tol, accept : float
        The projection's closure and acceptance limits on ``|Phi|`` (m, rad).
    """

    def __init__(self, bound, alpha, beta, mech=None, tol=1e-12, accept=1e-9):
        code = bound.code
        self.bound, self.fn = bound, code.dll.mbcomp_integrate
        self.n = bound.nq + bound.nu
        self.d = np.array([alpha, beta], float)
        self.y_last = np.zeros(self.n)
        self.work = {}
        self.mech = mech
        self.ctx = _Ctx(bound.nq, self.n, self.d.ctypes.data, bound.hbuf.ctypes.data, bound.pbuf.ctypes.data,
                        bound.wbuf.ctypes.data, self.y_last.ctypes.data, 0.0, 0.0,
                        mech.ptr if mech is not None else None,
                        mech.work.ctypes.data if mech is not None else None, tol, accept, PROJECT_MAX_ITER, 0, 0)
        self.stats = RuntimeStats()

    def linear_events(self, index, sign, at, direction, tol):
        """The :class:`LinearEvents` ``sign_k (y[index_k] - at_k)`` over this engine, for
        :meth:`integrate`'s ``events``."""
        return LinearEvents(self, index, sign, at, direction, tol)

    @property
    def projects(self):
        """Whether the C loop projects after every accepted step."""
        return self.mech is not None

    def new_stats(self):
        """A fresh :class:`RuntimeStats` (``mbrt_stats``) for a C call over this program (the
        struct's one ctypes mirror, for the callers in the layers above codegen)."""
        return RuntimeStats()

    def part_library(self, part):
        """:func:`part_library` (a part of the runtime built apart, at its first use: ``"radau"``,
        ``"pass"``)
        in the machine's runtime directory: it reaches this engine's program through function
        pointers."""
        code = self.bound.code
        return part_library(c_compiler(), runtime_directory(os.path.dirname(code.lib_path)), part)

    def _work(self, order):
        w = self.work.get(order)
        if w is None:
            w = self.work[order] = np.zeros(int(self.bound.code.dll.mbcomp_work_size(order, self.n)))
        return w

    def integrate(self, order, t0, y0, t_end, t_out, rtol, atol, h0=0.0, hmax=0.0, max_steps=0, stiff_steps=0,
                  events=None, fresh=-1, event_tol=None):
        """Integrate ``[q, u]`` from ``(t0, y0)`` to ``t_end`` by DOPRI5 (``order`` 5) or
        DOP853 (8); ``stiff_steps > 0``: stop with status 7 at the step where Hairer's
        stiffness test (``mbrt.h``, ``mbrt_dop853_events``) held for that many steps. Returns a
        namespace: ``status`` (:data:`STATUS`), ``message``, ``Y``
        (the states at the ``t_out`` reached, from the dense output of the unprojected
        steps), ``t_last``, ``y_last``, ``h_last`` (the last accepted step, projected),
        ``nfev``, ``naccept``, ``nreject``, ``projections`` and ``declined`` (the
        :data:`MECH_STATUS` of a projection that stopped the stretch at ``t_last`` with
        ``y_last`` unprojected, status 5; else 0). With ``events`` (:class:`LinearEvents`;
        ``fresh`` the one acted on at ``t0``, or -1; ``event_tol`` the location tolerance,
        s) the stretch ends at the first event located (status 8): ``which``, ``t_event``, ``y_event`` (``which`` -1 otherwise), the
        outputs at ``t_out <= t_event`` written."""
        y0 = np.ascontiguousarray(y0, float)
        t_out = np.ascontiguousarray(t_out, float)
        atol_v = np.ascontiguousarray(np.broadcast_to(np.asarray(atol, float), (self.n,)))
        Y = np.zeros((len(t_out), self.n))
        nw = ctypes.c_int(0)
        st = self.stats
        self.ctx.stiff_steps = int(stiff_steps)
        self.ctx.events = events.arm(fresh, event_tol) if events is not None else None
        status = self.fn(order, ctypes.byref(self.ctx), ctypes.c_double(t0), y0.ctypes.data, ctypes.c_double(t_end),
                         ctypes.c_double(rtol), atol_v.ctypes.data, ctypes.c_double(h0), ctypes.c_double(hmax),
                         ctypes.c_long(max_steps), t_out.ctypes.data, len(t_out), Y.ctypes.data, ctypes.byref(nw),
                         self._work(order).ctypes.data, ctypes.byref(st))
        return SimpleNamespace(status=int(status), message=st.message.decode(errors="replace"), Y=Y[: nw.value],
                               t_last=self.ctx.t_last, y_last=self.y_last.copy(), h_last=self.ctx.h_last,
                               nfev=int(st.nfev), naccept=int(st.naccept), nreject=int(st.nreject),
                               projections=int(self.ctx.nproj), declined=int(self.ctx.declined),
                               which=int(events.struct.which) if events is not None else -1,
                               t_event=float(events.struct.t_event) if events is not None else float("nan"),
                               y_event=events.y_event.copy() if events is not None else None)


def integrate_signature(fn):
    """Set the ctypes signature of ``mbcomp_integrate`` and ``mbcomp_work_size`` in a library."""
    fn.mbcomp_integrate.restype = ctypes.c_int
    fn.mbcomp_integrate.argtypes = [ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p, ctypes.c_double,
                                    ctypes.c_double, ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                                    ctypes.c_long, ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p,
                                    ctypes.c_void_p, ctypes.c_void_p]
    fn.mbcomp_work_size.restype = ctypes.c_size_t
    fn.mbcomp_work_size.argtypes = [ctypes.c_int, ctypes.c_int]
    fn.mbrt_events_work_size.restype = ctypes.c_size_t
    fn.mbrt_events_work_size.argtypes = [ctypes.c_int, ctypes.c_int]
