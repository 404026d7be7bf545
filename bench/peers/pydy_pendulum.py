"""pydy peer for the planar N-link pendulum of ``models/n_link_pendulum.py``: sympy's
``KanesMethod`` and pydy's ``generate_ode_function`` (Cython, else lambdify).

The derivation is ``sympy_pendulum.kane`` (frames rotated by relative angles about the
parent's z, rods of mass ``m``, length ``L``, central inertia ``diag(m L^2/12, 0, m L^2/12)``,
gravity along -y, ``q' = u``), here with ``L``, ``m``, ``g`` as symbols whose values pydy's
function takes at run time (as pydy users write it; sympy also derives faster so: 4.4 s
instead of 6.7 s at N = 8).

``build(N, timeout=60) -> Peer`` with ``rhs(t, y)`` (``y = [q, u]``, mbcomp's convention),
``build_seconds`` (derivation + code generation + compilation, CPU incl. the compiler),
``derive_seconds``, ``generator`` (``"cython"``, or ``"lambdify"`` when Cython or a C
compiler is missing: then ``note`` says so). A derivation exceeding ``timeout`` seconds
CPU seconds raises :class:`DerivationTimeout` (a SIGVTALRM stops sympy, which is pure Python;
CPU, not wall time: on a shared machine a wall-clock alarm skipped N = 10 whose derivation
takes 18 s of CPU).
"""
import signal
import time

import numpy as np

from .cpu_clock import cpu

__all__ = ["build", "available", "derive", "DerivationTimeout"]


class DerivationTimeout(Exception):
    pass


def available():
    try:
        import pydy  # noqa: F401
    except ImportError as exc:
        return f"pydy not installed ({exc}); pip install pydy"
    return None


def derive(N, L=0.5, m=1.0, g=9.81):
    """``(KanesMethod, q, u)`` of the N-link pendulum: ``sympy_pendulum.kane``."""
    from .sympy_pendulum import kane

    return kane(N, L, m, g)


def _cython_missing():
    try:
        import Cython  # noqa: F401
    except ImportError:
        return "Cython not installed"
    import shutil
    import sysconfig

    if not (shutil.which(sysconfig.get_config_var("CC").split()[0] if sysconfig.get_config_var("CC") else "cc")):
        return "no C compiler"
    return None


def _alarm(seconds):
    """Raise DerivationTimeout after ``seconds`` of this process's user CPU time."""
    def handler(signum, frame):
        raise DerivationTimeout(f"derivation > {seconds:g} s CPU")

    old = signal.signal(signal.SIGVTALRM, handler)
    signal.setitimer(signal.ITIMER_VIRTUAL, seconds)
    return old


class Peer:
    name = "pydy"

    def __init__(self, N, L, m, g, timeout, generator):
        import sympy as sp
        from pydy.codegen.ode_function_generators import generate_ode_function

        self.N = N
        c0 = cpu()
        w0 = time.perf_counter()
        old = _alarm(timeout) if timeout else None
        consts = sp.symbols("L m g")
        try:
            km, q, u = derive(N, *consts)
        finally:
            if timeout:
                signal.setitimer(signal.ITIMER_VIRTUAL, 0)
                signal.signal(signal.SIGVTALRM, old)
        self.derive_seconds = cpu() - c0
        self.derive_wall = time.perf_counter() - w0
        missing = _cython_missing() if generator == "cython" else None
        self.generator = "lambdify" if missing else generator
        self.note = f"lambdify instead of cython ({missing})" if missing else ""
        self._f = generate_ode_function(km.forcing, q, u, consts, mass_matrix=km.mass_matrix,
                                        coordinate_derivatives=sp.Matrix(u), generator=self.generator,
                                        constants_arg_type="array")
        self._p = np.array([L, m, g], float)
        self.build_seconds = cpu() - c0

    def rhs(self, t, y):
        # a copy: pydy's generated function returns the same output array at every call, and
        # scipy's Runge-Kutta steppers keep earlier stages (DOP853 silently went wrong)
        return np.array(self._f(y, t, self._p))


def build(N, L=0.5, m=1.0, g=9.81, timeout=60.0, generator="cython"):
    return Peer(int(N), L, m, g, timeout, generator)
