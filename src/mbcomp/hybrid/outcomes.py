"""What the hybrid layer's events hand to the driver and to the result: the record of an
event (:class:`EventRecord`, in ``res.events``), a located event that acts (:class:`Cut`,
from :meth:`mbcomp.hybrid.events.Events.check`) and what its action did (:class:`Outcome`,
from :meth:`~mbcomp.hybrid.events.Events.act`). Immutable hand-offs, no behaviour.

Examples
--------
>>> import numpy as np
>>> from mbcomp.hybrid.outcomes import EventRecord, Outcome
>>> EventRecord(0.5, "hinge", "lo", "impact").kind, Outcome(0.5, np.zeros(2)).ends
('impact', True)
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["EventRecord", "Cut", "Outcome"]


@dataclass(frozen=True)
class EventRecord:
    """One event of a run.

    Attributes
    ----------
    time : float
        s.
    component : str
        The component's path, or ``"user"``.
    name : str
        The event's name (the user function's ``__name__``).
    kind : str
        ``"impact"``, ``"engage"``, ``"release"``, ``"switch"``, ``"end"``, ``"rest"``
        (chattering settled), ``"turn"`` (a plane slip turned its direction) or ``"user"``.
    detail : dict
        The impact's ``speed_before``/``speed_after`` (m/s or rad/s along the row),
        ``energy_loss`` (J), ``restitution``; the new ``mode``.

    Examples
    --------
    >>> EventRecord(0.5, "hinge", "lo", "impact", {"energy_loss": 1.0}).kind
    'impact'
    """

    time: float
    component: str
    name: str
    kind: str
    detail: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Cut:
    """An event that acts, located in the last accepted step (:meth:`Events.check`).

    Attributes
    ----------
    t : float
        The event's time (s); the step is cut there.
    qu : callable
        ``qu(t) -> [q, u]``: the step's dense output (the outputs up to ``t`` come from it).
    key : tuple
        The event function's key: ``("user", index, name)``, ``("joint", joint, event)`` or
        ``("release", joint, row)``.
    state : ndarray
        ``[q, u]`` at ``t`` before the action.
    action : object
        The component's action (:class:`~mbcomp.modeling.events.Impact`, ``Switch`` or
        ``End``), or None for a user's terminal event.
    turn : ndarray or None
        A plane slide's new direction (tangent coordinates) when the event only turned it.
    """

    t: float
    qu: object
    key: tuple
    state: np.ndarray
    action: object = None
    turn: object = None


@dataclass(frozen=True)
class Outcome:
    """What an event did to the run (:meth:`Events.act`): the run ends at ``t`` (``form`` is
    None; ``state`` its last output, ``message`` why), or a new segment starts at ``t`` (s)
    with ``form`` over the new active set from its state ``y0``.

    Examples
    --------
    >>> import numpy as np
    >>> Outcome(0.5, np.zeros(2), message="event ground at t=0.5 s").ends
    True
    """

    t: float
    state: np.ndarray
    form: object = None
    y0: object = None
    message: str = ""

    @property
    def ends(self):
        """Whether the run ends at :attr:`t`."""
        return self.form is None
