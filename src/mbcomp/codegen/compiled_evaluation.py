"""The generated program's result at one ``(t, q, u)``: :class:`CompiledEvaluation`, what
:meth:`ProgramEvaluator.evaluate <mbcomp.codegen.evaluator.ProgramEvaluator.evaluate>` returns
(the program's flat output sliced into the fields formulations read; the rest numeric, on first
access).
"""
from __future__ import annotations

import numpy as np

__all__ = ["CompiledEvaluation"]


class CompiledEvaluation:
    """The generated program's result at one ``(t, q, u)``: the attributes of
    :class:`mbcomp.assembly.system.Evaluation` that formulations use.

    ``M, f, Phi, Phid, C, cb, B, b, Bb, Psi`` and ``A`` come from the program (holonomic rows
    masked like the numeric evaluation); ``jets``, ``local`` and ``local_nh`` (needed for
    reactions and post-processing only) are computed numerically on first access.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.codegen import compile_system
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> ev = compile_system(mbcomp.assemble(m)).evaluate(0.0, np.zeros(1), np.zeros(1))
    >>> ev.M.tolist(), ev.f.tolist(), ev.A.shape
    ([[2.0]], [-19.62], (0, 1))
    """

    __slots__ = ("t", "q", "u", "M", "f", "Phi", "Phid", "C", "cb", "B", "b", "Bb", "Psi", "_sys", "_masked", "_num")

    def __init__(self, system, t, q, u, flat, masked, slices, mask):
        self.t, self.q, self.u = t, q, u
        for name, a, b, shape, empty in slices:
            setattr(self, name, empty if empty is not None else flat[a:b] if shape is None else flat[a:b].reshape(shape))
        if masked and mask is not None:
            self.Phi, self.Phid, self.C, self.cb = self.Phi[mask], self.Phid[mask], self.C[mask], self.cb[mask]
        self._sys, self._masked, self._num = system, masked, None

    @property
    def A(self):
        """All constraint rows acting on du/dt: holonomic ``C`` then nonholonomic ``B``."""
        return np.vstack((self.C, self.B)) if self.B.size else self.C

    def numeric(self):
        """The numeric :class:`~mbcomp.assembly.system.Evaluation` at the same point (computed once)."""
        if self._num is None:
            self._num = self._sys.evaluate_numeric(self.t, self.q, self.u, self._masked)
        return self._num

    @property
    def jets(self):
        return self.numeric().jets

    @property
    def local(self):
        return self.numeric().local

    @property
    def local_nh(self):
        return self.numeric().local_nh
