"""The output program: every result column of a whole output grid in one compiled call.

The post-processing (:mod:`mbcomp.simulation.postprocess`) computes, at every output time,
the columns of :func:`mbcomp.assembly.outputs.output_values` (coordinates and their rates,
reactions, joints' own outputs, drive efforts, poses and twists, energies, residuals,
multipliers). Traced once (:func:`mbcomp.codegen.tracer.trace` with ``program="outputs"``),
it is one more straight-line program; its C version comes with a loop over the grid
(``mbcomp_outputs_grid``), so 100,000 output points cost one call and O(N) work each. A point
where a guard fails (a law's other branch, a singular recursion) is flagged and left to the
caller's numeric route.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.codegen.outputs import OutputProgram
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute()); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=2.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> s = mbcomp.assemble(m)
>>> prog = OutputProgram.build(s, "python", baumgarte=False)
>>> names, V, R, ok = prog.grid(s, np.array([0.0, 1.0]), np.array([[0.0, 2.0], [0.0, 0.0]]), None)
>>> V[names.index("j.f.y")].round(9).tolist(), ok.tolist()   # m (g + w^2 l); m g at rest
([27.62, 19.62], [True, True])
"""
from __future__ import annotations

import concurrent.futures
import ctypes
import os
import threading
import time

import numpy as np

from ..geometry.kinematics import matrix_to_quat
from .graph import CodegenError, Fallback, Retrace
from .printers import PY_ENV, ParamProgram, Program
from .toolchain import FLAGS, HEADER, c_compiler, cached_library, chunk, n_units
from .tracer import param_vector, trace

__all__ = ["OutputProgram"]


_GRID_DECL = """
int mbcomp_outputs(const double *restrict q, const double *restrict u, double t, const double *restrict d,
                   const double *restrict h, const double *restrict p, double *restrict w, double *restrict out);
"""

#: C of ``mbcomp_quat``: the unit quaternion of a rotation matrix (also in exported FMUs)
QUAT_C = r"""
/* unit quaternion (w, x, y, z), w >= 0, of the rotation matrix R (row major), by Shepperd's
   choice of the largest of 4w^2, 4x^2, 4y^2, 4z^2 (as mbcomp.kinematics.matrix_to_quat) */
static void mbcomp_quat(const double *restrict R, double *restrict Q)
{
    const double tr = R[0] + R[4] + R[8];
    double c[4] = {tr, R[0], R[4], R[8]};
    int k = 0;
    for (int j = 1; j < 4; ++j)
        if (c[j] > c[k]) k = j;
    const double s = k == 0 ? 1.0 + tr : 1.0 + 2.0 * c[k] - tr;
    const double big = 0.5 * sqrt(s > 0.0 ? s : 0.0), d = 1.0 / (4.0 * big);
    const double s21 = (R[7] - R[5]) * d, s02 = (R[2] - R[6]) * d, s10 = (R[3] - R[1]) * d;
    const double p01 = (R[1] + R[3]) * d, p02 = (R[2] + R[6]) * d, p12 = (R[5] + R[7]) * d;
    double q[4];
    switch (k) {
    case 0: q[0] = big; q[1] = s21; q[2] = s02; q[3] = s10; break;
    case 1: q[0] = s21; q[1] = big; q[2] = p01; q[3] = p02; break;
    case 2: q[0] = s02; q[1] = p01; q[2] = big; q[3] = p12; break;
    default: q[0] = s10; q[1] = p02; q[2] = p12; q[3] = big; break;
    }
    const double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    const double sg = q[0] >= 0.0 ? 1.0 / n : -1.0 / n;
    for (int j = 0; j < 4; ++j) Q[j] = q[j] * sg;
}
"""

_GRID_C = QUAT_C + r"""
int mbcomp_outputs_grid(long n, const double *restrict T, const double *restrict Y, long nq, long nu,
                        const double *restrict D, long nd, const double *restrict h, const double *restrict p,
                        double *restrict w, double *restrict row, long nout, long nrot,
                        double *restrict cols, double *restrict quat, signed char *restrict ok)
{
    /* the output program at every grid point k: state row Y[k] = [q, u], time T[k], per-call
       inputs D[k] (drives' (s, v, a), then the Baumgarte gains), into row[nout]; its first
       nout - 9 nrot values are the columns, stored column by column: cols[j n + k]; the last
       9 nrot are rotation matrices, stored as nrot quaternions quat[(b n + k) 4 ...];
       ok[k] = 0 where a guard failed (that point's values are left as they were) */
    const long ncol = nout - 9 * nrot;
    long failed = 0;
    for (long k = 0; k < n; ++k) {
        const double *y = Y + k * (nq + nu);
        int bad = mbcomp_outputs(y, y + nq, T[k], D + k * nd, h, p, w, row);
        ok[k] = (signed char)!bad;
        failed += bad;
        if (bad) continue;
        for (long j = 0; j < ncol; ++j) cols[j * n + k] = row[j];
        for (long b = 0; b < nrot; ++b) mbcomp_quat(row + ncol + 9 * b, quat + 4 * (b * n + k));
    }
    return (int)(failed > 0);
}
"""


class OutputProgram:
    """The traced result columns of one system structure, runnable on output grids.

    Attributes
    ----------
    names : list of str
        The columns' names, in the post-processing's order.
    rotation_paths : list of str
        The bodies whose rotation matrices follow the columns (9 values each, row by row).
    backend : {"python", "c"}
    n_ops : int
        Operations of the program.
    compile_time : float
        Seconds spent printing and compiling (C) or compiling (Python).

    Use :meth:`build` to make one and :meth:`grid` to run it (see the module's example).
    """

    def __init__(self, tr, backend, cache_dir=None):
        t0 = time.perf_counter()
        self.names, self.rotation_paths = tr.output_names, tr.rotation_paths
        self.layout, self.signature, self.drives, self.inputs = tr.layout, tr.signature, tr.drives, tr.inputs
        self.n_out = len(tr.groups["outputs"])
        prog = Program(tr.graph, {"outputs": tr.groups["outputs"]}, guard_groups={"outputs": tr.guard_groups["outputs"]})
        self.n_ops = prog.n_ops("outputs")
        self.pre = ParamProgram(prog)
        self.backend = backend
        if backend == "python":
            env = dict(PY_ENV, _Fallback=Fallback, _Retrace=Retrace)
            exec(compile(prog.python_main("outputs", "outputs"), "<mbcomp.codegen outputs>", "exec"), env)
            self.fun = env["outputs"]
        else:
            self._build_c(prog, cache_dir)
        self.compile_time = time.perf_counter() - t0

    @classmethod
    def build(cls, system, backend="c", baumgarte=True, cache_dir=None, max_nodes=3_000_000):
        """Trace ``system``'s result columns (multipliers with Baumgarte terms if ``baumgarte``)
        and compile them; None when the trace point is singular (no program: the numeric
        route computes every point). Raises :class:`CodegenError` for untraceable laws."""
        return cls._make(cls._traced(system, backend, baumgarte, max_nodes), backend, cache_dir)

    @staticmethod
    def _traced(system, backend, baumgarte, max_nodes):
        if backend == "c" and c_compiler() is None:
            raise CodegenError("backend='c' needs a C compiler (gcc or cc on PATH, or $CC) -> fix: install one, "
                               "or use backend='python'")
        return trace(system, max_nodes, program="outputs", baumgarte=baumgarte)

    @classmethod
    def _make(cls, tr, backend, cache_dir):
        return cls(tr, backend, cache_dir) if "outputs" in tr.groups else None

    @classmethod
    def start(cls, system, backend="c", baumgarte=True, cache_dir=None, max_nodes=3_000_000):
        """:meth:`build` with the printing and the C compiler on a thread of its own: traced
        now (the tracer is single-threaded), the rest beside the caller, which goes on
        integrating (a first run's post-processing waited ~80 ms for gcc after the run).
        Returns a :class:`PendingOutputs`; raises as :meth:`build` does while tracing."""
        tr = cls._traced(system, backend, baumgarte, max_nodes)
        return PendingOutputs(lambda: cls._make(tr, backend, cache_dir))

    def _build_c(self, prog, cache_dir):
        # the compile policy of the other programs (docs/design/generated-programs.md): -O2, outputs of one
        # shape rolled into loops, functions of a few hundred statements in translation units
        # compiled in parallel and cached one by one; the grid loop is one more small unit
        parts, n_work = prog.c_parts("outputs", "mbcomp_outputs", chunk, n_parts=n_units)
        # -O2 at every size: the outputs written at the end (constants, inputs) are copied from
        # static tables (printers._tail_c), so gcc's time stays linear (the 1000-link chain's
        # 180,000 operations: 24 s CPU, was 65 s with 5,000 straight-line stores in one function)
        units = [(f"outputs{k}", HEADER + src, list(FLAGS)) for k, src in enumerate(parts)]
        units.append(("outputs_grid", HEADER + _GRID_DECL + _GRID_C, list(FLAGS)))
        self.dll = cached_library(units, "mbcomp_out", cache_dir, "output program")
        fn = self.dll.mbcomp_outputs_grid
        L, P = ctypes.c_long, ctypes.c_void_p
        fn.argtypes = [L, P, P, L, L, P, L, P, P, P, P, L, L, P, P, P]
        fn.restype = ctypes.c_int
        self.n_work = max(n_work, 1)
        self.source = "\n".join(u[1] for u in units)

    def grid(self, system, t, Y, gains):
        """The columns at every output time.

        Parameters
        ----------
        system : MultibodySystem
            Of the structure traced; its parameter values and drives are used.
        t : ndarray (n,)
            Output times (s).
        Y : ndarray (n, nq + nu)
            States ``[q, u]``.
        gains : tuple or None
            Baumgarte gains ``(alpha, beta)`` (1/s) of the multipliers, as the program was
            built (``baumgarte``); None for none.

        Returns
        -------
        names : list of str
        values : ndarray (len(names), n)
            Column by column (NaN where not ``ok``).
        quaternions : dict
            Body path -> ndarray (n, 4): the unit quaternion ``(w, x, y, z)``, ``w >= 0``, of
            the body's rotation (:func:`mbcomp.kinematics.matrix_to_quat`; NaN where not ``ok``).
        ok : ndarray of bool (n,)
            False where a guard failed or a value is not finite (those rows are to be
            computed by the numeric route).

        Raises
        ------
        Retrace
            When ``system``'s parameter values change a decision baked into the program.
        """
        t = np.ascontiguousarray(t, float)
        Y = np.ascontiguousarray(Y, float)
        n, nq = t.size, system.nq
        pv = param_vector(system, self.layout)
        h = self.pre.run(pv)
        comps = [(system.topology.flat.components[d], system.P[d]) for d in self.drives]
        nd = 3 * len(comps)  # per-call inputs: the drives' (s, v, a), the gains, the external inputs
        D = np.zeros((n, nd + 2 + len(self.inputs)))
        for k in range(n) if comps else ():
            D[k, :nd] = [x for comp, p in comps for x in comp.motion(t[k], p)]
        D[:, nd: nd + 2] = gains if gains is not None else (0.0, 0.0)
        for j, inp in enumerate(self.inputs):
            D[:, nd + 2 + j] = [inp.value(tk) for tk in t]
        nb, ncol = len(self.rotation_paths), len(self.names)
        # column by column: every result column one contiguous row (rows not ok are NaN below)
        table, quat = np.empty((ncol, n)), np.empty((nb, n, 4))
        ok = np.ones(n, bool)
        if self.backend == "python":
            for k in range(n):
                try:
                    row = self.fun(Y[k, :nq].tolist(), Y[k, nq:].tolist(), float(t[k]), D[k].tolist(), h)
                except (Fallback, ArithmeticError, ValueError):
                    ok[k] = False
                    continue
                table[:, k] = row[:ncol]
                quat[:, k] = matrix_to_quat(np.reshape(row[ncol:], (nb, 3, 3)))
        else:
            hb = np.array(list(h) + [0.0], float)
            pb = np.array(list(pv) + [0.0], float)
            w, row = np.zeros(self.n_work), np.zeros(self.n_out)
            okc = np.ones(n, np.int8)
            self.dll.mbcomp_outputs_grid(n, t.ctypes.data, Y.ctypes.data, nq, Y.shape[1] - nq, D.ctypes.data,
                                         D.shape[1], hb.ctypes.data, pb.ctypes.data, w.ctypes.data, row.ctypes.data,
                                         self.n_out, nb, table.ctypes.data, quat.ctypes.data, okc.ctypes.data)
            ok = okc.astype(bool)
        ok &= np.isfinite(table).all(axis=0) & np.isfinite(quat).all(axis=(0, 2))
        table[:, ~ok] = np.nan
        quat[:, ~ok] = np.nan
        return self.names, table, dict(zip(self.rotation_paths, quat)), ok


class PendingOutputs:
    """An :class:`OutputProgram` being made on a thread (:meth:`OutputProgram.start`).

    The thread is not a daemon: the interpreter waits for it at exit, so no compiler is left
    half-way. A forked child has the future but not the thread, so it makes its own program.

    Parameters
    ----------
    make : callable
        Returns the program or None (:meth:`OutputProgram.build`'s results); run on the thread.

    Examples
    --------
    >>> from mbcomp.codegen.outputs import PendingOutputs
    >>> PendingOutputs(lambda: None).result() is None
    True
    """

    def __init__(self, make):
        self.pid = os.getpid()
        self._future = concurrent.futures.Future()

        def work():
            try:
                self._future.set_result(make())
            except BaseException as exc:  # handed to whoever waits for it (a CodegenError: no program)
                self._future.set_exception(exc)
        threading.Thread(target=work, name="mbcomp-outputs", daemon=False).start()

    def result(self):
        """The program (or None: the trace point was singular); raises what making it raised
        (:class:`CodegenError`); :data:`False` in a forked child (nothing is being made there)."""
        if os.getpid() != self.pid:
            return False
        return self._future.result()


def settled(programs, key):
    """The output program under ``key`` in a structure's ``programs`` (dict): the program,
    None (none can be made) or False (not made); one being made (:class:`PendingOutputs`) is
    waited for and put in its place.

    Examples
    --------
    >>> from mbcomp.codegen.outputs import PendingOutputs, settled
    >>> programs = {"k": PendingOutputs(lambda: None)}
    >>> settled(programs, "k"), programs, settled(programs, "other")
    (None, {'k': None}, False)
    """
    prog = programs.get(key, False)
    if isinstance(prog, PendingOutputs):
        try:
            prog = prog.result()
        except CodegenError:
            prog = None
        programs[key] = prog
    return prog
