"""Events watched inside the C integrators' loop: the runtime's ``mbrt_events`` (``mbrt.h``,
``mbrt_events.c``) over event functions affine in one state entry each
(``mbrt_linear_event_values``), as the hybrid layer's declared rows give them
(:class:`mbcomp.modeling.events.EventRow`, a joint's coordinate against its stops).

After every accepted step the runtime evaluates them at the step's end; a sign change in an
event's direction is located on the step's continuous extension (Brent's method; an event
acted on at the start is found only when it returns through zero), and the stretch ends at
the earliest (status 8) with the state there. :class:`LinearEvents` holds the ctypes
structures an :class:`mbcomp.codegen.engine.Integrator` hands to its C call.

:class:`LinearImpacts` goes one step further for the plainest action, a stop's rebound: the
runtime's ``mbrt_impacts_integrate`` runs a run's stretches one after the other and acts on
the impacts between them itself (Newton's restitution on the row, ``M`` from the evaluation
program), restarting as a new stepper would; whatever is not plainly a rebound (one that may
rest, chattering, no restitution) ends the loop at the event for the hybrid layer to decide.
"""
from __future__ import annotations

import ctypes
from types import SimpleNamespace

import numpy as np

__all__ = ["LinearEvents", "LinearImpacts", "MassProgram", "RuntimeStats"]


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
        if not set(self.direction.tolist()) <= {-1, 0, 1} or not np.all(np.isfinite(self.at)):
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


class _Mech(ctypes.Structure):  # mbrt_mech (mbrt.h)
    _fields_ = ([(n, ctypes.c_void_p) for n in ("eval", "qrate", "d", "h", "p", "w")]
                + [(n, ctypes.c_int) for n in ("nq", "nu", "n_out", "mh", "mn", "nrows")]
                + [("rows", ctypes.c_void_p)]
                + [(f"off_{n}", ctypes.c_int) for n in ("M", "f", "Phi", "Phid", "C", "cb", "B", "Bb", "Psi")]
                + [("nseg", ctypes.c_int), ("seg", ctypes.c_void_p)])


class MassProgram:
    """A C evaluation program as :class:`LinearImpacts` reads it (an ``mbrt_mech`` of ``M`` and
    ``f``, no rows used): the program's function and the bound parameter set's buffers, which
    this object keeps alive. ``rows`` is the program's number of holonomic and nonholonomic
    rows (the impacts in C need 0). Lighter than :class:`mbcomp.codegen.engine.Mech`, which
    also maps the coordinates for its projection.

    Parameters
    ----------
    bound : mbcomp.codegen.compiler.Bound
        The evaluation program (C backend) bound to its parameter values.

    Examples
    --------
    >>> import mbcomp
    >>> from mbcomp.codegen import c_compiler, compile_system
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World()); s = m.add("s", Prismatic(n=(0, 0, 1)))
    >>> b = m.add("b", PointMass(m=2.0)); m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> if c_compiler():
    ...     print(MassProgram(compile_system(mbcomp.assemble(m), "c").evaluator.dae_program(1).mech.bound).rows)
    ... else:
    ...     print(0)
    0
    """

    def __init__(self, bound):
        code, sl = bound.code, bound.code.slices
        self.bound = bound
        self.rows = (sl["Phi"][1] - sl["Phi"][0]) + (sl["Psi"][1] - sl["Psi"][0])
        fn = ctypes.cast(code.dll.mbcomp_eval, ctypes.c_void_p).value
        self.struct = _Mech(fn, None, bound.dbuf.ctypes.data, bound.hbuf.ctypes.data, bound.pbuf.ctypes.data,
                            bound.wbuf.ctypes.data, bound.nq, bound.nu, code.n_out, sl["Phi"][1] - sl["Phi"][0],
                            sl["Psi"][1] - sl["Psi"][0], 0, None,
                            *(sl[n][0] for n in ("M", "f", "Phi", "Phid", "C", "cb", "B", "Bb", "Psi")), 0, None)
        self.ptr = ctypes.addressof(self.struct)


def _signed(dll):
    """``dll`` with the impacts' runtime calls' ctypes signatures set (once: the library keeps
    its function objects)."""
    fn = dll.mbrt_impacts_integrate
    if fn.argtypes is None:
        dll.mbrt_impacts_work_size.restype = ctypes.c_size_t
        dll.mbrt_impacts_work_size.argtypes = [ctypes.c_void_p]
        fn.restype, fn.argtypes = ctypes.c_int, _ARGS
    return dll


class _Impacts(ctypes.Structure):
    _fields_ = [("n_ev", ctypes.c_int), ("iu", ctypes.c_void_p), ("sign", ctypes.c_void_p), ("e", ctypes.c_void_p),
                ("comp", ctypes.c_void_p), ("n_comp", ctypes.c_int), ("last", ctypes.c_void_p),
                ("gap", ctypes.c_void_p), ("shrinks", ctypes.c_void_p), ("chatter", ctypes.c_int),
                ("burst", ctypes.c_double), ("rest", ctypes.c_double), ("P", ctypes.c_void_p),
                ("work", ctypes.c_void_p), ("cap", ctypes.c_int), ("count", ctypes.c_int),
                ("log_t", ctypes.c_void_p), ("log_which", ctypes.c_void_p), ("log_y", ctypes.c_void_p),
                ("log_loss", ctypes.c_void_p)]


class RuntimeStats(ctypes.Structure):
    """The runtime integrators' ``mbrt_stats`` (``mbrt.h``): evaluations, steps, accepted and
    rejected steps, the status, the time reached (s) and a one-sentence message."""

    _fields_ = [("nfev", ctypes.c_long), ("nstep", ctypes.c_long), ("naccept", ctypes.c_long),
                ("nreject", ctypes.c_long), ("status", ctypes.c_int), ("t", ctypes.c_double),
                ("message", ctypes.c_char * 200)]


class _Stretches(ctypes.Structure):  # mbrt_stretches (mbrt.h)
    _fields_ = [("chunk", ctypes.c_int), ("chunk_max", ctypes.c_int), ("count", ctypes.c_int),
                ("max_stretches", ctypes.c_int), ("tol_scale", ctypes.c_double), ("h_restart", ctypes.c_double),
                ("h_last", ctypes.c_void_p), ("t_end", ctypes.c_double)]


_ARGS = ([ctypes.c_void_p, ctypes.c_int] + [ctypes.c_void_p] * 4 + [ctypes.c_int, ctypes.c_double, ctypes.c_void_p,
                                                                     ctypes.c_void_p, ctypes.c_int, ctypes.c_double,
                                                                     ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                                                                     ctypes.c_long] + [ctypes.c_void_p] * 5)


class LinearImpacts:
    """Stops' rebounds acted on inside the C loop (``mbrt_impacts`` / ``mbrt_impacts_integrate``
    in ``mbrt.h``): event ``k`` of ``events`` closes the row ``sign_k u[iu_k] >= 0`` with
    Newton's restitution ``e_k`` (``iu_k = -1``: never acted on in C), on a system without
    constraint rows whose evaluation program ``mech`` gives ``M`` and ``f``.

    Parameters
    ----------
    integrator : Integrator
        The engine (its ``mbcomp_integrate`` is the stretch function, its context the call's).
    mech : MassProgram or mbcomp.codegen.engine.Mech
        The evaluation program of the same system, bound to the same parameters (its ``ptr``).
    iu, sign, e, comp : sequence
        Per event: the speed entry of its row (0..nu-1, or -1), the row's sign (+-1), the
        restitution (1, in [0, 1]) and its component (0..n_comp-1).
    chatter, burst, rest : int, float, float
        Shrinking intervals that make chattering; s per ``max(1, |t|)`` within which an impact
        is the caller's; the resting height (m or rad).
    cap : int
        Impacts logged at most per call (then the caller acts on the next).

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen import c_compiler, compile_system
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1), s0=1.0)); b = m.add("b", PointMass(m=1.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> if c_compiler():            # a ball dropped from 1 m onto the floor, e = 0.5
    ...     ev = compile_system(mbcomp.assemble(m), "c")
    ...     eng, mech = ev.evaluator.integrator(0.0, 0.0), ev.evaluator.dae_program(1).mech
    ...     watch = LinearEvents(eng, index=[0], sign=[1.0], at=[0.0], direction=[-1], tol=1e-13)
    ...     imp = LinearImpacts(eng, mech, iu=[0], sign=[1.0], e=[0.5], comp=[0])
    ...     out = imp.integrate(watch, 8, 0.0, np.array([1.0, 0.0]), np.array([0.5, 1.0]), 1e-10, 1e-12, chunk=2,
    ...                         tol_scale=1e-13)
    ...     t1 = np.sqrt(2 / 9.81)      # the fall; the next after 2 v / g, v = e sqrt(2 g) (m/s)
    ...     times = [x[0] for x in out.impacts]
    ...     print(out.status, len(times), abs(times[0] - t1) < 1e-9, abs(times[1] - times[0] - t1) < 1e-9)
    ... else:
    ...     print(0, 2, True, True)
    0 2 True True
    """

    def __init__(self, integrator, mech, iu, sign, e, comp, chatter=30, burst=1e-9, rest=0.0, cap=64):
        dll = integrator.bound.code.dll
        self.integrator, self.mech, self.dll = integrator, mech, dll
        n, m = integrator.n, len(iu)
        self.iu = np.ascontiguousarray(iu, dtype=np.intc)
        self.sign = np.ascontiguousarray(sign, dtype=float)
        self.e = np.ascontiguousarray(e, dtype=float)
        self.comp = np.ascontiguousarray(comp, dtype=np.intc)
        if not (len(self.iu) == len(self.sign) == len(self.e) == len(self.comp) == m):
            raise ValueError(f"LinearImpacts: iu, sign, e and comp need one entry per watched event ({m})")
        acted = self.iu >= 0
        if np.any((self.e[acted] < 0.0) | (self.e[acted] > 1.0)) or not np.all(np.abs(self.sign[acted]) == 1.0):
            raise ValueError(f"LinearImpacts: restitution {self.e.tolist()} must lie in [0, 1] (0 plastic, 1 "
                             f"elastic) and the signs {self.sign.tolist()} be +1 or -1")
        n_comp = int(self.comp.max()) + 1 if m else 1
        self.last, self.gap = np.full(n_comp, -np.inf), np.full(n_comp, -1.0)
        self.shrinks = np.zeros(n_comp, dtype=np.intc)
        self.log_t, self.log_which = np.zeros(cap), np.zeros(cap, dtype=np.intc)
        self.log_y, self.log_loss = np.zeros((cap, 2 * n)), np.zeros(cap)
        _signed(dll)
        self.work = np.zeros(max(1, int(dll.mbrt_impacts_work_size(mech.ptr))))
        self.struct = _Impacts(m, self.iu.ctypes.data, self.sign.ctypes.data, self.e.ctypes.data,
                               self.comp.ctypes.data, n_comp, self.last.ctypes.data, self.gap.ctypes.data,
                               self.shrinks.ctypes.data, int(chatter), float(burst), float(rest), mech.ptr,
                               self.work.ctypes.data, int(cap), 0, self.log_t.ctypes.data,
                               self.log_which.ctypes.data, self.log_y.ctypes.data, self.log_loss.ctypes.data)
        self.fn, self.stretch = dll.mbrt_impacts_integrate, ctypes.cast(dll.mbcomp_integrate, ctypes.c_void_p).value
        self.stretch_work = {}
        self.y_start = np.zeros(n)

    def history(self, comp, last, gap, shrinks):
        """Component ``comp``'s impacts so far: the last one's time (s; -inf: none), the
        interval before it (s; negative: none) and how many successive intervals shrank."""
        self.last[comp], self.gap[comp], self.shrinks[comp] = last, gap, shrinks

    def integrate(self, events, order, t0, y0, t_out, rtol, atol, *, chunk, chunk_max=None, count=0,
                  max_stretches=1, tol_scale=1e-12, h0=0.0, h_restart=0.0, hmax=0.0, max_steps=0, stiff_steps=0,
                  fresh=-1):
        """The stretches watching ``events`` (:class:`LinearEvents`, one per entry of ``iu``)
        from ``(t0, y0)`` over the output times ``t_out`` (every one left, > t0), the impacts
        acted on between them (``mbrt_impacts_integrate``): a segment's k-th stretch holds
        ``min(chunk_max, chunk 2^k)`` outputs (``count`` stretches of this one made before),
        at most ``max_stretches`` ending without an event in this call, each going on with the
        last step of the one before; a new segment after each impact (first step ``h_restart``).
        Returns what :meth:`mbcomp.codegen.engine.Integrator.integrate` does, the counters
        summed over the stretches, with ``impacts``: ``[(t, event, [q, u-], [q, u+], energy
        lost J)]``, ``count`` (the current segment's stretches) and ``t_end`` (the last
        stretch's end, s)."""
        eng, n = self.integrator, self.integrator.n
        y0 = np.ascontiguousarray(y0, float)
        t_out = np.ascontiguousarray(t_out, float)
        atol_v = np.ascontiguousarray(np.broadcast_to(np.asarray(atol, float), (n,)))
        Y = np.zeros((len(t_out), n))
        work = self.stretch_work.get(order)
        if work is None:
            work = self.stretch_work[order] = np.zeros(int(self.dll.mbcomp_work_size(order, n)))
        if len(events.index) != len(self.iu):
            raise ValueError(f"LinearImpacts: {len(events.index)} events watched for {len(self.iu)} described")
        R = _Stretches(int(chunk), int(chunk if chunk_max is None else chunk_max), int(count), int(max_stretches),
                       float(tol_scale), float(h_restart), ctypes.addressof(eng.ctx) + type(eng.ctx).h_last.offset,
                       0.0)
        nw, st = ctypes.c_int(0), RuntimeStats()
        self.struct.count = 0
        eng.ctx.stiff_steps = int(stiff_steps)
        eng.ctx.events = events.arm(fresh)
        status = self.fn(self.stretch, order, ctypes.addressof(eng.ctx), events.ptr, ctypes.addressof(self.struct),
                         ctypes.addressof(R), n, t0, y0.ctypes.data, t_out.ctypes.data, len(t_out), rtol,
                         atol_v.ctypes.data, h0, hmax, int(max_steps), Y.ctypes.data, ctypes.addressof(nw),
                         work.ctypes.data, ctypes.addressof(st), self.y_start.ctypes.data)
        ev = events.struct
        k = self.struct.count
        impacts = [(float(self.log_t[j]), int(self.log_which[j]), self.log_y[j, :n].copy(), self.log_y[j, n:].copy(),
                    float(self.log_loss[j])) for j in range(k)]
        return SimpleNamespace(status=int(status), message=st.message.decode(errors="replace"), Y=Y[: nw.value],
                               t_last=eng.ctx.t_last, y_last=eng.y_last.copy(), h_last=eng.ctx.h_last,
                               nfev=int(st.nfev), naccept=int(st.naccept), nreject=int(st.nreject),
                               projections=int(eng.ctx.nproj), declined=int(eng.ctx.declined),
                               which=int(ev.which), t_event=float(ev.t_event), y_event=events.y_event.copy(),
                               impacts=impacts, count=int(R.count), t_end=float(R.t_end))
