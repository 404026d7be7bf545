"""The jump of forward sensitivities at an event (:class:`Jump`), for
:mod:`mbcomp.simulation.sensitivity`: with event function ``g`` and the state after the action
``y+ = R(y-, p)``::

    dtau/dp = -(g_y S- + g_p) / (g_y f-)
    S+ = R_y S- + R_p + (R_y f- - f+) dtau/dp

``g`` and ``R`` are the hybrid layer's own (:meth:`mbcomp.hybrid.events.Events.event_value`,
:meth:`~mbcomp.hybrid.events.Events.reset`); their derivatives along each column ``(S-_j, e_j)``
are central differences of the combined perturbation, the parameter moved in a numeric twin
of the system (:meth:`~mbcomp.hybrid.events.Events.twin`).

Examples
--------
>>> from types import SimpleNamespace
>>> from mbcomp.simulation.sensitivity_events import with_value
>>> from mbcomp.codegen.sensitivity import ParameterRef
>>> ref = ParameterRef("rod.r[1]", "rod", "r", (1,), "param", -1.0)
>>> with_value(SimpleNamespace(r=[0.0, -1.0, 0.0]), ref, -1.5).r.tolist()
[0.0, -1.5, 0.0]
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..errors import SimulationError

__all__ = ["Jump", "EVENT_STEP", "moved_params", "with_value"]

#: relative step of the central differences of event functions and reset maps
EVENT_STEP = 1e-6


def with_value(P, ref, value):
    """A copy of the parameter namespace ``P`` with ``ref``'s entry set to ``value``."""
    new = SimpleNamespace(**vars(P))
    old = getattr(P, ref.param)
    if ref.index is None:
        setattr(new, ref.param, value)
    else:
        arr = np.array(old, float)
        arr[ref.index] = value
        setattr(new, ref.param, arr)
    return new


class Jump:
    """The jump of the sensitivities at one event (see the module notes): made before the
    events act (the event function's pieces need the state and the modes before), applied
    after (the reset map needs the modes after)."""

    def __init__(self, sens, run, cut, events):
        self.t, self.cut, self.events = float(cut.t), cut, events
        system = run.form.system
        self.y_minus = y_minus = np.asarray(cut.state, float)
        self.f_minus = sens.derivative(system, cut.t, y_minus, sens.S)[0]
        self.before = dict(events.modes)
        self.S = S = sens.S.copy()
        self.g_f = self._g_rate(events, y_minus)
        # the event function along each column (S-_j, e_j) by central differences; the parameter
        # moved in a numeric twin of the system
        self.eps, self.values, self.g_dir = [], [], np.zeros(sens.k)
        for j, ref in enumerate(sens.refs):
            eps = EVENT_STEP * max(abs(ref.value), 1e-2) / max(1.0, float(np.max(np.abs(S[:, j])))
                                                               / max(1.0, float(np.max(np.abs(y_minus)))))
            values = [None if ref.kind == "start" else moved_params(system, ref, ref.value + s * eps) for s in (1.0, -1.0)]
            g = [(events if v is None else events.twin(v)).event_value(cut.key, self.t, y_minus + s * eps * S[:, j])
                 for v, s in zip(values, (1.0, -1.0))]
            self.eps.append(eps)
            self.values.append(values)
            self.g_dir[j] = (g[0] - g[1]) / (2 * eps)

    def _g_rate(self, events, y):
        """``g_y f- + g_t``: the event function's rate along the motion before the event."""
        h = EVENT_STEP * 1e-1 * max(1.0, abs(self.t))
        f = self.f_minus
        gp = events.event_value(self.cut.key, self.t + h, y + h * f)
        gm = events.event_value(self.cut.key, self.t - h, y - h * f)
        return (gp - gm) / (2 * h)

    def apply(self, sens, new_system, y_plus):
        """``S+`` once the events acted (their modes now the ones after; ``new_system`` the new
        segment's system, ``y_plus`` the state after)."""
        if abs(self.g_f) < 1e-300:
            raise SimulationError(f"sensitivities: the event at t={self.t:.12g} s is grazing (its function's rate is "
                                  "zero): the event time has no derivative there -> move the start or the parameters "
                                  "off the grazing motion (a touch without crossing), or end the run before it")
        events, before, after = self.events, self.before, dict(self.events.modes)
        R_dir = np.zeros((sens.n, sens.k))
        for j, (eps, values) in enumerate(zip(self.eps, self.values)):
            R = [(events if v is None else events.twin(v)).reset(self.cut, self.y_minus + s * eps * self.S[:, j],
                                                                   before, after)
                 for v, s in zip(values, (1.0, -1.0))]
            R_dir[:, j] = (R[0] - R[1]) / (2 * eps)
        dtau = -self.g_dir / self.g_f  # (k,)
        f_plus = sens.derivative(new_system, self.t, y_plus, self.S)[0]
        h = EVENT_STEP * 1e-1 * max(1.0, abs(self.t))
        R_f = (events.reset(self.cut, self.y_minus + h * self.f_minus, before, after)
               - events.reset(self.cut, self.y_minus - h * self.f_minus, before, after)) / (2 * h)
        return R_dir + np.outer(R_f - f_plus, dtau)


def moved_params(system, ref, value):
    """``{"component.param": value}`` of ``system`` with ``ref``'s entry at ``value`` (the whole
    array for an array's entry), for :meth:`mbcomp.hybrid.events.Events.twin`."""
    return {f"{ref.path}.{ref.param}": getattr(with_value(system.P[ref.path], ref, value), ref.param)}
