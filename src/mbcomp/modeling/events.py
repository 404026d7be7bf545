"""What a component may declare about events: the actions at a zero crossing, and unilateral rows.

A component with discrete behaviour (a joint stop; later a unilateral contact, a stick-slip
friction) has a *mode*, a plain string (``"free"``, ``"lo"``, ``"hi"``, ...) the run carries
for it, declared by one :class:`~mbcomp.modeling.modes.Modes` object (``Joint.modes(p)``). In
each mode it declares event functions of its own state (:meth:`Modes.events
<mbcomp.modeling.modes.Modes.events>`) and, for each event, an *action*
(:meth:`Modes.action <mbcomp.modeling.modes.Modes.action>`):

* :class:`Impact` -- the component's rows of the mode ``engage`` close with an impact:
  the run solves the impulse equations ``M (u+ - u-) = C^T Lambda`` with Newton's restitution
  on the rows' speeds, then engages that mode when the rebound is too slow to leave (or
  ``restitution`` is 0), else stays in its mode and flies on;
* :class:`Switch` -- change to another mode, with no jump in the speeds (a release);
* :class:`End` -- end the run (status ``"success"``, the reason in the message).

A mode holds rows (:meth:`Modes.rows <mbcomp.modeling.modes.Modes.rows>`): :class:`AxisRow` is a unilateral row on a 1-DOF joint's own coordinate,
``sign (s - at) = 0`` while engaged (``sign (s - at) >= 0`` is the allowed side), whose
multiplier the run watches: it releases (the action at the event ``"release"``) when the row
would have to pull.

Examples
--------
>>> from mbcomp.modeling.events import AxisRow, Impact, Switch
>>> Impact(0.5, engage="lo"), Switch("free")
(Impact(restitution=0.5, engage='lo'), Switch(mode='free'))
>>> AxisRow("lo", 1.0, -0.2).value(0.1)      # 0.3 rad into the allowed side
0.30000000000000004
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

__all__ = ["Impact", "Switch", "End", "AxisRow", "ContactRow", "StickRow", "SlipSpeed", "EventRow", "ACTIONS"]


@dataclass(frozen=True)
class Impact:
    """An impact closing the rows of mode ``engage`` with Newton's restitution.

    Parameters
    ----------
    restitution : float
        Newton's coefficient ``e`` in [0, 1]: the rows' speed after is ``-e`` times before.
    engage : str
        The mode whose rows the impact acts on, entered when the body comes to rest there.

    Examples
    --------
    >>> Impact(0.8, engage="hi").restitution
    0.8
    """

    restitution: float
    engage: str


@dataclass(frozen=True)
class Switch:
    """Change to ``mode`` (speeds continuous; positions and speeds made consistent with the
    new mode's rows).

    Examples
    --------
    >>> Switch("free").mode
    'free'
    """

    mode: str


@dataclass(frozen=True)
class End:
    """End the run here (status ``"success"``), saying ``reason``.

    (``Stop``, its former name, is still importable from this module, with a
    ``DeprecationWarning``: "stop" now means only a joint's mechanical end stop.)

    Examples
    --------
    >>> End("the door latched").reason
    'the door latched'
    """

    reason: str


@dataclass(frozen=True)
class AxisRow:
    """A unilateral row on a 1-DOF joint's coordinate ``s`` (rad or m): ``sign (s - at)``,
    zero while engaged, positive on the allowed side.

    Parameters
    ----------
    name : str
        Row name (the result and messages call it ``<joint>.<name>``).
    sign : float
        +1 for a lower limit (``s >= at``), -1 for an upper one (``s <= at``).
    at : float
        The limit (rad or m).

    Examples
    --------
    >>> AxisRow("hi", -1.0, 1.0).value(1.25)   # 0.25 beyond the upper limit
    -0.25
    """

    name: str
    sign: float
    at: float

    def value(self, s):
        """``sign (s - at)`` (rad or m)."""
        return self.sign * (s - self.at)


@dataclass(frozen=True)
class EventRow:
    """An event function affine in one of the joint's own coordinates or speeds:
    ``sign (x[index] - at)``, ``x`` the joint's coordinates (``of="q"``) or speeds
    (``of="u"``). A :class:`~mbcomp.modeling.modes.Modes` that declares ``linear_events``
    gives its events as these rows (:meth:`~mbcomp.modeling.modes.Modes.event_rows`); the
    run then watches them inside the C integrator's loop, where the Python functions cannot
    be called.

    Parameters
    ----------
    name : str
        The event's name (as in :meth:`~mbcomp.modeling.modes.Modes.events`).
    of : {"q", "u"}
        Coordinates or speeds of the joint.
    index : int
        Which of them (0 for a 1-DOF joint).
    sign : float
        +1 or -1.
    at : float
        The value where the event fires (rad, m, rad/s or m/s).
    direction : int
        scipy's convention: -1 fires when the value falls through zero, +1 when it rises, 0 either.

    Examples
    --------
    >>> EventRow("hi", "q", 0, -1.0, 0.5, -1).value([0.2], [1.0])   # 0.3 rad below the upper stop
    0.3
    """

    name: str
    of: str
    index: int
    sign: float
    at: float
    direction: int

    def __post_init__(self):
        if self.of not in ("q", "u"):
            raise ValueError(f"EventRow {self.name!r}: of={self.of!r} -> fix: 'q' (the joint's coordinates) or 'u' "
                             "(its speeds)")
        if self.direction not in (-1, 0, 1):
            raise ValueError(f"EventRow {self.name!r}: direction={self.direction!r} -> fix: -1, 0 or +1")

    def value(self, q, u):
        """``sign (x[index] - at)`` of the joint's coordinates ``q`` / speeds ``u``."""
        x = q if self.of == "q" else u
        return self.sign * (float(x[self.index]) - self.at)


@dataclass(frozen=True)
class ContactRow:
    """A row of a contact's own holonomic constraints (a cut joint's ``constraints``, by
    ``name``; its value m, positive on the open side): held in a mode (``Modes.rows``: the
    framework watches its push and fires ``"release"`` when it would pull), or the value of an
    event (``Modes.events`` returns ``(event, ContactRow(row), direction)``: the framework
    evaluates the row, the gap while the contact is open). A unilateral contact's rows
    (holonomic and velocity rows) are in the system only in the modes where :meth:`Modes.holds_rows
    <mbcomp.modeling.modes.Modes.holds_rows>` is true.

    With ``mu_s`` (a contact with Coulomb friction, held rolling) the framework also watches
    the friction cone: ``mu_s N - |F_t|`` (N; ``N`` the row's push, ``F_t`` the force of the
    contact's rolling rows, the velocity rows along orthonormal tangents) falling through zero
    is the contact's event ``"slide"``.

    Examples
    --------
    >>> ContactRow("normal").name, ContactRow("normal", mu_s=0.4).mu_s
    ('normal', 0.4)
    """

    name: str
    mu_s: float = None


@dataclass(frozen=True)
class SlipSpeed:
    """The value of a sliding contact's event: its slip speed (m/s) along the direction it
    slid when its slide began (or last turned), ``v_t . d``. ``Modes.events`` returns
    ``(event, SlipSpeed(), -1)``: the framework fires the event where the slip comes to rest
    (``|v_t|`` at the root is ~0: the contact may roll again) -- or, in a plane slip whose
    direction turned by 90 degrees, where ``|v_t|`` is not ~0: the framework then takes the
    new direction and slides on (a ``"turn"``, no action of the component's).

    Examples
    --------
    >>> SlipSpeed()
    SlipSpeed()
    """


@dataclass(frozen=True)
class StickRow(AxisRow):
    """An :class:`AxisRow` holding a 1-DOF joint's coordinate where it stands while a
    Coulomb friction sticks (its rate held at zero: the row's value is 0, its Jacobian
    ``sign`` along the axis), bilateral up to a push of ``limit`` either way.

    Instead of a ``"release"`` event the run watches ``limit + push`` (event ``"break+"``
    falling through zero: the load drives the axis forward harder than the friction holds)
    and ``limit - push`` (``"break-"``), ``push`` (N or N m) being the row's force on the
    axis (minus its multiplier, ``sign`` = +1); the component's ``Modes.action`` says where
    it slips to.

    Parameters
    ----------
    name : str
        Row name.
    sign, at : float
        As :class:`AxisRow` (``sign`` +1; ``at`` unused: the row holds the rate).
    limit : float
        The largest push the row holds (N or N m: the break-away force or torque).

    Examples
    --------
    >>> row = StickRow("stick", 1.0, 0.0, limit=2.5)
    >>> row.value(0.3), row.limit                # held by its rate only
    (0.0, 2.5)
    """

    limit: float = float("inf")

    def value(self, s):
        """0 (the row holds the rate, not a position)."""
        return 0.0 * s


#: the actions a component may return from ``Modes.action``
ACTIONS = (Impact, Switch, End)


def __getattr__(name):
    """``Stop``, the former name of :class:`End`, with a ``DeprecationWarning``."""
    if name == "Stop":
        warnings.warn("mbcomp.modeling.events.Stop is now End (a run's end; 'stop' is a joint's end stop)",
                      DeprecationWarning, stacklevel=2)
        return End
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
