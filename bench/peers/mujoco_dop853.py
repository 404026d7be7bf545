"""MuJoCo's dynamics stepped by mbcomp's C DOP853: the C construct of ``bench/peers.py``.

``mujoco_dop853.c`` calls ``mj_forward`` as the right-hand side ``[qvel, qacc]`` of
``y = [qpos, qvel]`` inside ``mbrt_dop853`` (the runtime mbcomp's C engine runs: the same
tableau, step control and dense output), so a trajectory costs no Python per call. It links
against the ``libmujoco`` the ``mujoco`` wheel ships (with its headers) and the runtime's C
sources (``mbcomp.codegen.runtime.SOURCES``), compiled once per process into a temporary
directory by the C compiler mbcomp finds (``-O2``, as mbcomp's programs).

``available()`` says why the construct cannot be built (no compiler, no headers or library
in the wheel), or ``None``. ``build_from_mjcf(text) -> Construct``: ``rhs(t, y)`` (one
``mj_forward`` through ctypes, for the cross-check) and ``integrate(y0, grid, rtol, atol)
-> (Y, nfev)`` (the whole run in C; timed by the caller).
"""
import atexit
import ctypes
import glob
import os
import shutil
import subprocess
import tempfile

import numpy as np

__all__ = ["available", "build_from_mjcf", "Construct"]

HERE = os.path.dirname(os.path.abspath(__file__))
_LIB = {}


def _mujoco_paths():
    import mujoco

    d = os.path.dirname(mujoco.__file__)
    libs = sorted(glob.glob(os.path.join(d, "libmujoco.so*")))
    inc = os.path.join(d, "include")
    return d, (libs[0] if libs else None), inc


def available():
    """``None`` if the construct can be built, else why not (one sentence)."""
    try:
        d, lib, inc = _mujoco_paths()
    except ImportError as exc:
        return f"mujoco not installed ({exc})"
    from mbcomp.codegen.toolchain import c_compiler

    if c_compiler() is None:
        return "no C compiler"
    if lib is None or not os.path.isfile(os.path.join(inc, "mujoco", "mujoco.h")):
        return f"the mujoco wheel in {d} ships no libmujoco.so or no include/mujoco/mujoco.h"
    return None


def _library():
    if "lib" in _LIB:
        return _LIB["lib"]
    from mbcomp.codegen.runtime import RUNTIME_DIR, SOURCES
    from mbcomp.codegen.toolchain import c_compiler

    d, lib, inc = _mujoco_paths()
    out = tempfile.mkdtemp(prefix="mjd853-")
    atexit.register(shutil.rmtree, out, True)
    so = os.path.join(out, "mujoco_dop853.so")
    cmd = [c_compiler(), "-O2", "-fPIC", "-shared", "-o", so, os.path.join(HERE, "mujoco_dop853.c"),
           *map(str, SOURCES), f"-I{RUNTIME_DIR}", f"-I{inc}", lib, f"-Wl,-rpath,{d}", "-lm"]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode:
        raise RuntimeError(f"building the MuJoCo + C DOP853 construct failed: {r.stderr[-400:]}")
    L = ctypes.CDLL(so)
    dp = ctypes.POINTER(ctypes.c_double)
    L.mjd_load.restype = ctypes.c_void_p
    L.mjd_load.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_int]
    L.mjd_size.argtypes = [ctypes.c_void_p]
    L.mjd_rhs.argtypes = [ctypes.c_void_p, ctypes.c_double, dp, dp]
    L.mjd_integrate.argtypes = [ctypes.c_void_p, ctypes.c_double, dp, ctypes.c_double, ctypes.c_double,
                                ctypes.c_double, dp, ctypes.c_int, dp, ctypes.POINTER(ctypes.c_long),
                                ctypes.c_char_p, ctypes.c_int]
    L.mjd_free.argtypes = [ctypes.c_void_p]
    _LIB["lib"] = L
    return L


def _ptr(a):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


class Construct:
    """A loaded MuJoCo model under the C DOP853 (``n`` = nq = nv)."""

    def __init__(self, mjcf_text):
        self.lib = _library()
        fd, path = tempfile.mkstemp(suffix=".xml", prefix="mjd853-")
        with os.fdopen(fd, "w") as fh:
            fh.write(mjcf_text)
        err = ctypes.create_string_buffer(500)
        try:
            self.handle = self.lib.mjd_load(path.encode(), err, 500)
        finally:
            os.unlink(path)
        if not self.handle:
            raise RuntimeError(f"MuJoCo refused the model: {err.value.decode()}")
        self.n = self.lib.mjd_size(self.handle)

    def rhs(self, t, y):
        y = np.ascontiguousarray(y, float)
        dy = np.empty(2 * self.n)
        self.lib.mjd_rhs(self.handle, t, _ptr(y), _ptr(dy))
        return dy

    def integrate(self, y0, grid, rtol, atol):
        """``(Y, nfev)``: the states at ``grid`` (rows) from ``y0`` at ``grid[0]``; raises on a
        failed run (the integrator's message)."""
        y0 = np.ascontiguousarray(y0, float)
        grid = np.ascontiguousarray(grid, float)
        Y = np.empty((len(grid), 2 * self.n))
        nfev = ctypes.c_long(0)
        msg = ctypes.create_string_buffer(300)
        rc = self.lib.mjd_integrate(self.handle, float(grid[0]), _ptr(y0), float(grid[-1]), rtol, atol, _ptr(grid),
                                    len(grid), _ptr(Y), ctypes.byref(nfev), msg, 300)
        if rc:
            raise RuntimeError(f"C DOP853 over MuJoCo: status {rc}: {msg.value.decode()}")
        return Y, nfev.value

    def __del__(self):
        if getattr(self, "handle", None):
            self.lib.mjd_free(self.handle)
            self.handle = None


def build_from_mjcf(text):
    return Construct(text)
