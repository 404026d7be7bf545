"""Events watched inside the C integrators' loop: the runtime's ``mbrt_events`` (``mbrt.h``,
``mbrt_events.c``) over event functions affine in one state entry each
(``mbrt_linear_event_values``), as the hybrid layer's declared rows give them
(:class:`mbcomp.modeling.events.EventRow`, a joint's coordinate against its stops).

After every accepted step the runtime evaluates them at the step's end; a sign change in an
event's direction is located on the step's continuous extension (Brent's method; an event
acted on at the start is found only when it returns through zero), and the stretch ends at
the earliest (status 8) with the state there. :class:`LinearEvents` holds the ctypes
structures an :class:`mbcomp.codegen.engine.Integrator` hands to its C call.
"""
from __future__ import annotations

import ctypes

import numpy as np

__all__ = ["LinearEvents"]


class _LinearEvents(ctypes.Structure):
    _fields_ = [("n_ev", ctypes.c_int), ("index", ctypes.c_void_p), ("sign", ctypes.c_void_p),
                ("at", ctypes.c_void_p)]


class _Events(ctypes.Structure):
    _fields_ = [("g", ctypes.c_void_p), ("gctx", ctypes.c_void_p), ("n_ev", ctypes.c_int),
                ("direction", ctypes.c_void_p), ("tol", ctypes.c_double), ("fresh", ctypes.c_int),
                ("work", ctypes.c_void_p), ("y_event", ctypes.c_void_p), ("which", ctypes.c_int),
                ("t_event", ctypes.c_double), ("nevals", ctypes.c_long)]


class LinearEvents:
    """Event functions ``g_k = sign_k (y[index_k] - at_k)`` watched inside the C loop
    (``mbrt_events`` / ``mbrt_linear_events`` in ``mbrt.h``): after every accepted step, a
    sign change in ``direction_k`` is located on the step's continuous extension to ``tol``
    (s) and the stretch ends there (status 8).

    Parameters
    ----------
    integrator : Integrator
        The engine whose library evaluates them (``mbrt_linear_event_values``).
    index : sequence of int
        Entries of the state ``y = [q, u]``.
    sign, at : sequence of float
        Per event (``at`` in the entry's unit).
    direction : sequence of int
        -1 (falling through zero), +1 (rising) or 0.
    tol : float
        Location tolerance (s).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen import c_compiler, compile_system
    >>> from mbcomp.library import World, Revolute, FixedTranslation, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, 0)))
    >>> j = m.add("j", Revolute(phi0=0.0, w0=2.0)); rod = m.add("rod", FixedTranslation(r=(1.0, 0, 0)))
    >>> bob = m.add("bob", PointMass(m=1.0))
    >>> m.connect(w.frame_b, j.frame_a); m.connect(j.frame_b, rod.frame_a); m.connect(rod.frame_b, bob.frame_a)
    >>> if c_compiler():
    ...     eng = compile_system(mbcomp.assemble(m), "c").evaluator.integrator(0.0, 0.0)
    ...     ev = LinearEvents(eng, index=[0], sign=[-1.0], at=[1.0], direction=[-1], tol=1e-13)
    ...     out = eng.integrate(8, 0.0, np.array([0.0, 2.0]), 3.0, np.array([3.0]), 1e-10, 1e-12, events=ev)
    ...     print(out.status, out.which, round(out.t_event, 12))     # phi = 1 rad at 2 rad/s
    ... else:
    ...     print(8, 0, 0.5)
    8 0 0.5
    """

    def __init__(self, integrator, index, sign, at, direction, tol):
        n = integrator.n
        self.index = np.ascontiguousarray(index, dtype=np.intc)
        self.sign = np.ascontiguousarray(sign, dtype=float)
        self.at = np.ascontiguousarray(at, dtype=float)
        self.direction = np.ascontiguousarray(direction, dtype=np.intc)
        m = len(self.index)
        if not (m and len(self.sign) == m and len(self.at) == m and len(self.direction) == m):
            raise ValueError(f"LinearEvents: index, sign, at and direction need one entry per event ({m} indices)")
        if self.index.min() < 0 or self.index.max() >= n:
            raise ValueError(f"LinearEvents: the indices {self.index.tolist()} must be state entries 0..{n - 1}")
        if not np.all(np.isin(self.direction, (-1, 0, 1))) or not np.all(np.isfinite(self.at)):
            raise ValueError("LinearEvents: directions are -1, 0 or +1 and the values finite")
        if not tol > 0:
            raise ValueError(f"LinearEvents: tol={tol!r} must be positive (s)")
        dll = integrator.bound.code.dll
        self.lin = _LinearEvents(m, self.index.ctypes.data, self.sign.ctypes.data, self.at.ctypes.data)
        self.work = np.zeros(int(dll.mbrt_events_work_size(n, m)))
        self.y_event = np.zeros(n)
        g = ctypes.cast(dll.mbrt_linear_event_values, ctypes.c_void_p).value
        self.struct = _Events(g, ctypes.addressof(self.lin), m, self.direction.ctypes.data, float(tol), -1,
                              self.work.ctypes.data, self.y_event.ctypes.data, -1, 0.0, 0)
        self.ptr = ctypes.addressof(self.struct)

    def arm(self, fresh=-1, tol=None):
        """The pointer the engine's context takes, with event ``fresh`` (acted on at the
        start: found in the first step only when it returns through zero) or -1, and the
        location tolerance ``tol`` (s; default: as made)."""
        self.struct.fresh = int(fresh)
        if tol is not None:
            if not tol > 0:
                raise ValueError(f"LinearEvents: tol={tol!r} must be positive (s)")
            self.struct.tol = float(tol)
        self.struct.which = -1
        return self.ptr
