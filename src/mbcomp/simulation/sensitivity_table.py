"""The sensitivities of a run's outputs (``res.sensitivities``): the states' as integrated
(:mod:`mbcomp.simulation.sensitivity`), every other column's through the derivatives of the
output program (:class:`mbcomp.codegen.sensitivity.ColumnCode`), made at first need.

Examples
--------
>>> import numpy as np, mbcomp
>>> from mbcomp.library import World, Prismatic, PointMass
>>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
>>> s = m.add("s", Prismatic(n=(0, 0, 1))); b = m.add("b", PointMass(m=2.0))
>>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
>>> r = mbcomp.simulate(m, t_end=1.0, n_out=3, sensitivities=["b.m"])
>>> r.sensitivity("energy.potential", "b.m").round(7).tolist()     # V = -m g.r: dV/dm = V / m
[0.0, -12.0295125, -48.11805]
"""
from __future__ import annotations

import numpy as np

from ..codegen.graph import CodegenError
from ..codegen.sensitivity import ColumnCode
from ..errors import SimulationError

__all__ = ["SensitivityTable"]


class SensitivityTable:
    """The sensitivities of a run's outputs (``res.sensitivities``; read them with
    :meth:`mbcomp.simulation.result.Result.sensitivity`).

    Attributes
    ----------
    params : list of str
        The parameters, as named in ``simulate(..., sensitivities=...)``.
    time : ndarray (n_out,)
        The output times (s).
    states : ndarray (n_out, nq + nu, n_params)
        ``d [q, u] / dp`` at the output times (NaN after :attr:`stopped`).
    stopped : tuple or None
        ``(t, why)`` when the sensitivities end before the run (a program that stops holding:
        a law's branch the trace did not take).

    The columns other than coordinates and speeds (reactions, energies, ...) have no
    sensitivity (NaN) in a segment whose modes hold rows (an engaged stop, a stuck friction):
    their program does not hold those rows.

    Examples
    --------
    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Prismatic, PointMass
    >>> m = mbcomp.Model(); w = m.add("world", World(g=(0, 0, -9.81)))
    >>> s = m.add("s", Prismatic(n=(0, 0, 1), v0=1.0)); b = m.add("b", PointMass(m=2.0))
    >>> m.connect(w.frame_b, s.frame_a); m.connect(s.frame_b, b.frame_a)
    >>> r = mbcomp.simulate(m, t_end=1.0, n_out=3, sensitivities=["s.v0", "world.g[2]"])
    >>> r.sensitivities.states[-1].round(9).tolist()      # s = v0 t + g t^2 / 2, v = v0 + g t
    [[1.0, 0.5], [1.0, 1.0]]
    """

    def __init__(self, refs, time, Y, states, systems, gains, stopped, held=(), state_names=(), aliases=None):
        self.params = [r.name for r in refs]
        self._refs = list(refs)
        self.time, self.states, self.stopped = time, states, stopped
        self._Y, self._systems, self._gains = Y, systems, gains
        self._programmed = [j for j, r in enumerate(refs) if r.kind == "param"]
        self._held = set(held)  # segments whose held rows no column program has: NaN there
        self._columns = None
        self.state_names = list(state_names)  # q_names + u_names: the rows of states
        self._aliases = dict(aliases or {})

    def __getstate__(self):  # the segments' systems (compiled programs) do not pickle; the arrays do
        state = dict(self.__dict__)
        state["_systems"] = None
        return state

    def index(self, param):
        """The position of ``param`` in :attr:`params` (a ``KeyError`` naming the ones there)."""
        if param not in self.params:
            raise KeyError(f"no sensitivity with respect to {param!r} was asked -> simulate(..., "
                           f"sensitivities=[{param!r}, ...]); asked: {', '.join(self.params)}")
        return self.params.index(param)

    def of(self, column, param):
        """``d column / d param`` at the output times (see :meth:`Result.sensitivity`)."""
        j = self.index(param)
        column, state_names = self._aliases.get(column, column), self.state_names
        if column in state_names:
            return self.states[:, state_names.index(column), j].copy()
        cols = self._column_table()
        if column not in cols:
            raise KeyError(f"no sensitivity of column {column!r}: it is neither a coordinate or speed nor a column of "
                           "the output program (reactions, joints' outputs, poses, twists, energies, residuals); "
                           f"columns with sensitivities: {', '.join(list(cols)[:12])}"
                           + (", ..." if len(cols) > 12 else ""))
        return cols[column][:, j].copy()

    def _column_table(self):
        """``{column: (n_out, n_params)}`` of every output-program column, made at first need."""
        if self._columns is not None:
            return self._columns
        if self._systems is None:
            raise KeyError("this result was pickled before the sensitivities of its other columns were read: only "
                           "the coordinates' and speeds' are kept -> read res.sensitivity(column, param) before "
                           "pickling, or simulate again")
        codes, out = {}, {}
        n_out = len(self.time)
        for k in range(n_out):
            system = self._systems[k]
            key = id(system)
            if key not in codes:
                try:
                    code = ColumnCode.build(system, self.params, "c" if system.backend == "c" else "python")
                except CodegenError as exc:
                    raise SimulationError(f"sensitivities of the columns: {exc}") from exc
                codes[key] = (code, code.bind(system))
            code, call = codes[key]
            S = self.states[k]
            D = call(self.time[k], self._Y[k], *self._gains) if np.isfinite(S).all() and key not in self._held else None
            for c, name in enumerate(code.names):
                arr = out.setdefault(name, np.full((n_out, S.shape[1]), np.nan))
                if D is not None:
                    arr[k] = D[c, : S.shape[0]] @ S
                    arr[k, self._programmed] += D[c, S.shape[0]:]
        self._columns = out
        return out
