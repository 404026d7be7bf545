"""The states and their sensitivities integrated together in C (:class:`SensitivityIntegrator`):
the runtime's DOP853 over a small C glue (:data:`SENSITIVITY_GLUE`) that calls a model's
Jacobian-vector program (:meth:`mbcomp.codegen.sensitivity.SensitivityCode.program`
``"jvp"``) through a function pointer -- one glue for every model, one C call for a run.
"""
from __future__ import annotations

import ctypes

import numpy as np

from .engine import RuntimeStats, runtime_library
from .toolchain import FLAGS, HEADER, c_compiler, cache_directory, cached_library, runtime_directory

__all__ = ["SensitivityIntegrator", "SENSITIVITY_GLUE"]


#: the simultaneous right-hand side ``[f; f_y S + f_p]`` in C, for the runtime's DOP853: the
#: current ``S`` (row major, ``n x k``) copied into the jvp program's per-call inputs, one call
#: of it (``fun`` and the ``k`` directional derivatives), its output the derivative.
SENSITIVITY_GLUE = r"""
#include <stddef.h>
#include <string.h>
#include <math.h>
typedef int (*mbcomp_prog)(const double *restrict q, const double *restrict u, double t, const double *restrict d,
                           const double *restrict h, const double *restrict p, double *restrict w,
                           double *restrict out);
typedef struct {
    mbcomp_prog jvp; const double *h, *p; double *d, *w, *out;   /* the program, its inputs and scratch   */
    int nq, n, k;                   /* coordinates, states, parameters (directions)                   */
    int failed;                     /* 1: the program's guard, 2: a non-finite value                  */
} mbcomp_sens_ctx;

int mbcomp_sens_rhs(void *c, double t, const double *z, double *dz)
{
    mbcomp_sens_ctx *x = (mbcomp_sens_ctx *)c;
    const size_t size = (size_t)x->n * (size_t)(x->k + 1);
    memcpy(x->d + 2, z + x->n, sizeof(double) * (size_t)x->n * (size_t)x->k);  /* S: the directions */
    if (x->jvp(z, z + x->nq, t, x->d, x->h, x->p, x->w, x->out)) { x->failed = 1; return 1; }
    for (size_t i = 0; i < size; i++) {
        dz[i] = x->out[i];
        if (!isfinite(dz[i])) { x->failed = 2; return 1; }
    }
    return 0;
}
"""


class _SensCtx(ctypes.Structure):
    _fields_ = ([("jvp", ctypes.c_void_p), ("h", ctypes.c_void_p), ("p", ctypes.c_void_p), ("d", ctypes.c_void_p),
                 ("w", ctypes.c_void_p), ("out", ctypes.c_void_p), ("nq", ctypes.c_int), ("n", ctypes.c_int),
                 ("k", ctypes.c_int), ("failed", ctypes.c_int)])


class SensitivityIntegrator:
    """The states and their sensitivities ``[y, S]`` integrated together in C: the runtime's
    DOP853 (:mod:`mbcomp.codegen.runtime`) over :data:`SENSITIVITY_GLUE`, which calls a bound C
    sensitivity program (:class:`BoundSensitivity`) at every evaluation -- one C call for a
    whole run, error control over ``y`` and ``S`` alike.

    Parameters
    ----------
    bound : BoundSensitivity
        Bound C programs (its ``"jvp"`` program is called).
    gains : (float, float)
        The Baumgarte gains (1/s), zero for none.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen import c_compiler
    >>> from mbcomp.codegen.sensitivity import SensitivityCode
    >>> from mbcomp.codegen.sensitivity_engine import SensitivityIntegrator
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> system = mbcomp.assemble(m)
    >>> if c_compiler():   # s = g t^2 / 2: d s / d g_z = t^2 / 2 = 2 at t = 2 s
    ...     sens = SensitivityIntegrator(SensitivityCode.build(system, ["world.g[2]"], "c").bind(system), (0, 0))
    ...     Y, S = sens.integrate(np.array([0.0, 2.0]), np.zeros(2), np.zeros((2, 1)), 1e-10, 1e-12)
    ...     print(S[-1].ravel().round(9).tolist())
    ... else:
    ...     print([2.0, 2.0])
    [2.0, 2.0]
    """

    def __init__(self, bound, gains, cache_dir=None):
        code = bound.code
        if code.backend != "c":
            raise ValueError("SensitivityIntegrator needs the C programs (backend='c')")
        jvp = bound.program("jvp")
        self.n, self.nq, self.k = code.n, code.nq, len(code.directions)
        self.rt = runtime_library(c_compiler(), runtime_directory(cache_directory(cache_dir)))
        self.glue = cached_library([("sensglue", HEADER + SENSITIVITY_GLUE, list(FLAGS))], "mbcomp_sensglue",
                                   cache_dir, "sensitivity integrator")
        self.fn = ctypes.cast(self.glue.mbcomp_sens_rhs, ctypes.c_void_p).value
        jvp.d[:] = 0.0
        jvp.d[0], jvp.d[1] = float(gains[0]), float(gains[1])
        self.bound = jvp  # its buffers must live as long as the context points at them
        size = self.n * (self.k + 1)
        self.work = np.zeros(int(self.rt.mbrt_dop853_work_size(size)))
        self.stats = RuntimeStats()
        self.ctx = _SensCtx(ctypes.cast(jvp.printed.cfun, ctypes.c_void_p).value, jvp.hbuf.ctypes.data,
                            jvp.pbuf.ctypes.data, jvp.d.ctypes.data, jvp.wbuf.ctypes.data, jvp.obuf.ctypes.data,
                            self.nq, self.n, self.k, 0)

    def integrate(self, t_out, y0, S0, rtol, atol, max_steps=0):
        """``(Y, S)`` at the times ``t_out`` (s; the first is the start) from ``y0``, ``S0``;
        ``(n_out, n)`` and ``(n_out, n, k)``. Raises ``ArithmeticError`` saying what failed
        (a guard of the program, a non-finite value, the integrator) and where; its
        ``written`` holds ``(Y, S)`` at the outputs reached before."""
        t_out = np.ascontiguousarray(t_out, float)
        z0 = np.concatenate((np.asarray(y0, float), np.asarray(S0, float).ravel()))
        size = z0.size
        atol_v = np.full(size, float(atol))
        out = np.zeros((len(t_out), size))
        written = ctypes.c_int(0)
        self.ctx.failed = 0
        status = self.rt.mbrt_dop853(self.fn, None, ctypes.byref(self.ctx), size, float(t_out[0]), z0.ctypes.data,
                                     float(t_out[-1]), float(rtol), atol_v.ctypes.data, 0.0, 0.0, int(max_steps),
                                     t_out.ctypes.data, len(t_out), out.ctypes.data, ctypes.byref(written),
                                     self.work.ctypes.data, ctypes.byref(self.stats))
        if status != 0 or written.value != len(t_out):
            what = {1: "the sensitivity program (a guard: a law's branch the trace did not take)",
                    2: "the sensitivities (a non-finite value)"}.get(self.ctx.failed, "the integrator")
            exc = ArithmeticError(f"{what} failed at t = {self.stats.t:.6g} s: "
                                  f"{self.stats.message.decode(errors='replace')}")
            done = max(0, min(written.value, len(t_out)))
            exc.written = (out[:done, :self.n], out[:done, self.n:].reshape(done, self.n, self.k))
            raise exc
        return out[:, :self.n], out[:, self.n:].reshape(len(t_out), self.n, self.k)
