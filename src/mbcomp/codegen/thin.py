"""The right-hand side as an integrator calls it, in one C call from Python: ``fun(t, y)``.

A :class:`~mbcomp.codegen.compiler.Bound` Lagrange program called through :mod:`ctypes`
costs ~5 us around ~0.1 us of C at N = 5: the state copied into a buffer, eight pointer
arguments converted, the result copied out, two ``np.isfinite`` checks and three Python
layers. :func:`thin_fun` instead gives a callable written in C (a tiny CPython extension,
``_mbcomp_thin``, compiled once per machine and Python and cached beside the programs) that
reads ``y`` in place (the buffer protocol: a contiguous float64 vector), checks that it is
finite, calls the program's ``mbcomp_fun`` through its address into a new numpy array, and
checks the result; any failure (a guard, a domain error, a non-finite value, a ``y`` it cannot
read in place) returns ``None`` and the caller takes its full path, which says what went
wrong. Only programs without per-call inputs qualify (drives evaluated in Python, external
inputs); the Baumgarte gains are the thin call's own (not the bound program's buffer, which
other callers set).

Without Python's headers, numpy's or a compiler the extension is not built (once per process
it is tried) and :func:`thin_fun` returns None: the callers keep the ctypes path.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.codegen import compile_system
>>> from mbcomp.codegen.thin import thin_fun
>>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World())
>>> j = m.add("j", Revolute()); rod = m.add("rod", FixedTranslation(r=(0, -1.0, 0)))
>>> bob = m.add("bob", PointMass(m=1.0))
>>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
>>> system = compile_system(mbcomp.assemble(m), "auto", lazy=True)
>>> f = system.evaluator.lagrange_thin(10.0, 10.0)
>>> f is None or round(float(f(0.0, np.array([0.5, 0.0]))[1]), 6)   # du/dt = -g sin(phi) / l
-4.703165
>>> f is None or f(0.0, np.array([np.nan, 0.0])) is None            # the caller's full path says why
True
"""
from __future__ import annotations

import ctypes
import hashlib
import importlib.machinery
import importlib.util
import os
import subprocess
import sys
import sysconfig
import tempfile

import numpy as np

from .toolchain import c_compiler, cache_directory

__all__ = ["thin_fun", "extension", "forget"]

_SOURCE = r"""
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>
#include <math.h>

typedef int (*prog_t)(const double *, const double *, double, const double *, const double *,
                      const double *, double *, double *);

typedef struct {
    PyObject_HEAD
    prog_t f;
    const double *d, *h, *p;
    double *w;
    Py_ssize_t nq, n;
    PyObject *keep;
} Thin;

static void Thin_dealloc(Thin *self) {
    Py_XDECREF(self->keep);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static int Thin_init(Thin *self, PyObject *args, PyObject *kw) {
    unsigned long long f, d, h, p, w;
    Py_ssize_t nq, n;
    PyObject *keep;
    if (!PyArg_ParseTuple(args, "KKKKKnnO", &f, &d, &h, &p, &w, &nq, &n, &keep)) return -1;
    if (!f || nq < 0 || n < 1 || nq > n) {
        PyErr_SetString(PyExc_ValueError, "Thin: a null program or bad sizes");
        return -1;
    }
    self->f = (prog_t)(uintptr_t)f;
    self->d = (const double *)(uintptr_t)d;
    self->h = (const double *)(uintptr_t)h;
    self->p = (const double *)(uintptr_t)p;
    self->w = (double *)(uintptr_t)w;
    self->nq = nq;
    self->n = n;
    Py_INCREF(keep);
    Py_XSETREF(self->keep, keep);
    return 0;
}

/* fun(t, y) -> a new float64 array of n, or None (the caller's full path says why) */
static PyObject *Thin_call(Thin *self, PyObject *args, PyObject *kw) {
    if (kw != NULL || PyTuple_GET_SIZE(args) != 2) {
        PyErr_SetString(PyExc_TypeError, "fun(t, y)");
        return NULL;
    }
    double t = PyFloat_AsDouble(PyTuple_GET_ITEM(args, 0));
    if (t == -1.0 && PyErr_Occurred()) { PyErr_Clear(); Py_RETURN_NONE; }
    Py_buffer view;
    if (PyObject_GetBuffer(PyTuple_GET_ITEM(args, 1), &view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) != 0) {
        PyErr_Clear();
        Py_RETURN_NONE;
    }
    PyObject *res = Py_None;
    const double *y = (const double *)view.buf;
    Py_ssize_t n = self->n, k;
    if (view.itemsize != 8 || view.len != 8 * n || view.format == NULL || view.format[0] != 'd'
        || view.format[1] != 0 || !isfinite(t))
        goto done;
    for (k = 0; k < n; k++)
        if (!isfinite(y[k])) goto done;
    {
        npy_intp dims[1] = {n};
        PyObject *out = PyArray_SimpleNew(1, dims, NPY_DOUBLE);
        if (out == NULL) { PyBuffer_Release(&view); return NULL; }
        double *o = (double *)PyArray_DATA((PyArrayObject *)out);
        if (self->f(y, y + self->nq, t, self->d, self->h, self->p, self->w, o) != 0) {
            Py_DECREF(out);
            goto done;
        }
        for (k = 0; k < n; k++)
            if (!isfinite(o[k])) { Py_DECREF(out); goto done; }
        res = out;
        PyBuffer_Release(&view);
        return res;
    }
done:
    PyBuffer_Release(&view);
    Py_RETURN_NONE;
}

static PyTypeObject ThinType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "_mbcomp_thin.Thin",
    .tp_basicsize = sizeof(Thin),
    .tp_dealloc = (destructor)Thin_dealloc,
    .tp_call = (ternaryfunc)Thin_call,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_init = (initproc)Thin_init,
    .tp_new = PyType_GenericNew,
    .tp_doc = "Thin(program, d, h, p, w, nq, n, keep): fun(t, y) of a generated program in one C call",
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_mbcomp_thin", NULL, -1, NULL};

PyMODINIT_FUNC PyInit__mbcomp_thin(void) {
    import_array();
    if (PyType_Ready(&ThinType) < 0) return NULL;
    PyObject *m = PyModule_Create(&module);
    if (m == NULL) return NULL;
    Py_INCREF(&ThinType);
    if (PyModule_AddObject(m, "Thin", (PyObject *)&ThinType) < 0) { Py_DECREF(&ThinType); Py_DECREF(m); return NULL; }
    return m;
}
"""

_EXT = {}  # "module": the loaded extension, or None when it cannot be built here


def _build(cc, cache_dir):
    """The extension's path in the cache, built if missing (raises on failure)."""
    inc_py = sysconfig.get_paths()["include"]
    inc_np = np.get_include()
    if not os.path.exists(os.path.join(inc_py, "Python.h")):
        raise OSError(f"no Python.h in {inc_py}")
    suffix = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
    key = hashlib.sha256("\0".join([_SOURCE, cc, sys.version, suffix, np.__version__, inc_py, inc_np])
                         .encode()).hexdigest()[:20]
    d = cache_directory(cache_dir)
    path = os.path.join(d, f"_mbcomp_thin_{key}{suffix}")
    if not os.path.exists(path):
        with tempfile.TemporaryDirectory(dir=d) as tmp:
            src = os.path.join(tmp, "thin.c")
            with open(src, "w") as fh:
                fh.write(_SOURCE)
            out = os.path.join(tmp, "thin" + suffix)
            subprocess.run([cc, "-O2", "-shared", "-fPIC", "-I", inc_py, "-I", inc_np, src, "-o", out],
                           check=True, capture_output=True, timeout=120)
            os.replace(out, path)  # atomic: the cache may be shared by processes
    return path


def extension(cache_dir=None):
    """The ``_mbcomp_thin`` extension module, or None where it cannot be built or loaded
    (no compiler, no Python or numpy headers): tried once per process."""
    if "module" not in _EXT:
        mod = None
        cc = c_compiler()
        if cc is not None:
            try:
                path = _build(cc, cache_dir)
                loader = importlib.machinery.ExtensionFileLoader("_mbcomp_thin", path)
                spec = importlib.util.spec_from_file_location("_mbcomp_thin", path, loader=loader)
                mod = importlib.util.module_from_spec(spec)
                loader.exec_module(mod)
            except (OSError, subprocess.SubprocessError, ImportError):
                mod = None
        _EXT["module"] = mod
    return _EXT["module"]


def forget():
    """Forget whether the extension could be built here: the next use tries again (after
    installing Python's headers or a compiler, or in a test of the fallback)."""
    _EXT.clear()


class _Gains:
    """The per-call inputs of a program without drives or inputs: the two Baumgarte gains,
    in a buffer of the thin call's own."""

    def __init__(self, alpha, beta):
        self.d = np.array([alpha, beta, 0.0], float)


def thin_fun(bound, alpha, beta, cache_dir=None):
    """``fun(t, y)`` of the bound Lagrange program ``bound`` with Baumgarte gains ``alpha``,
    ``beta`` (1/s) as one C call (see the module notes), or None: a Python program, a program
    with per-call inputs (drives evaluated in Python, external inputs), no extension here."""
    code = bound.code
    if code.backend != "c" or not code.has_fun or bound.drive_comps or code.inputs:
        return None
    n = bound.nq + bound.nu
    if n == 0:
        return None
    ext = extension(cache_dir)
    if ext is None:
        return None
    gains = _Gains(alpha, beta)
    addr = ctypes.cast(code.dll.mbcomp_fun, ctypes.c_void_p).value
    return ext.Thin(addr, gains.d.ctypes.data, bound.hbuf.ctypes.data, bound.pbuf.ctypes.data,
                    bound.wbuf.ctypes.data, bound.nq, n, (bound, gains, code))
