"""What a component declares about its modes: one capability object, :class:`Modes`.

A joint with discrete behaviour (a rigid stop, a one-sided contact, a stick-slip friction)
has a *mode*, a plain string (``"free"``, ``"lo"``, ``"closed"``, ``"slip+"``, ...) the run
carries for it. The joint declares it by returning a :class:`Modes` from
:meth:`Joint.modes(p) <mbcomp.modeling.roles.Joint.modes>` (``None``: no modes, the default);
the run (:mod:`mbcomp.hybrid`) asks that object, and nothing else, about:

* the *start* mode (:attr:`Modes.start`);
* the *events* of a mode: zero crossings of functions of the joint's own coordinates and
  speeds (:meth:`Modes.events`);
* the *action* at an event: what the component does there, an
  :class:`~mbcomp.modeling.events.Impact`, :class:`~mbcomp.modeling.events.Switch` or
  :class:`~mbcomp.modeling.events.End` (:meth:`Modes.action`);
* the unilateral *rows* a mode holds (:meth:`Modes.rows`: ``AxisRow``, ``StickRow``,
  ``ContactRow``), whether the joint's own constraint rows are in the system in a mode
  (:meth:`Modes.holds_rows`), and the mode to *rest* in when an event chatters
  (:meth:`Modes.rest`);
* declared capabilities, plain attributes set by the component, never inferred:
  :attr:`Modes.has_force` (the joint applies a force on its own speed in some mode:
  :meth:`Modes.force`), :attr:`Modes.slips` (a contact that slides with Coulomb friction
  in some mode: :meth:`Modes.slip_friction`) and :attr:`Modes.linear_events` (every event
  is an :class:`~mbcomp.modeling.events.EventRow`, affine in one coordinate or speed:
  :meth:`Modes.event_rows`; the C integrators then watch them in their loop).

The parameters are bound when the object is made (``modes(p)``), so none of its methods
takes them.
"""
from __future__ import annotations

__all__ = ["Modes"]


class Modes:
    """The modes of one component with its parameters: start mode, events, actions, rows.

    Subclass it and override what the component has; the defaults are those of a mode with
    no events, no rows of its own, the joint's own rows held, no force and no slip.

    Parameters
    ----------
    start : str
        The mode the component starts in.

    Attributes
    ----------
    start : str
        The start mode.
    has_force : bool
        Class attribute, declared: True when :meth:`force` may be nonzero in some mode (the
        run adds it to the joint's speed and books its work). Default False: never asked.
    slips : bool
        Class attribute, declared: True when :meth:`slip_friction` gives a coefficient in some
        mode (a contact sliding with Coulomb friction). Default False: never asked.
    linear_events : bool
        Class attribute, declared: True when every event of every mode is an
        :class:`~mbcomp.modeling.events.EventRow` (:meth:`event_rows`), and :meth:`events`
        gives exactly their values. Default False: the run calls :meth:`events` (in Python).

    Examples
    --------
    A latch that ends the run where a hinge's angle rises through 1 rad:

    >>> from mbcomp.modeling.events import End
    >>> from mbcomp.modeling.modes import Modes
    >>> class Latch(Modes):
    ...     def events(self, q, u, mode):
    ...         return [("latched", 1.0 - q[0], -1)]       # falls through zero at q = 1 rad
    ...     def action(self, name, mode):
    ...         return End("the door latched")
    >>> m = Latch("open")
    >>> m.start, m.events([0.25], [2.0], "open"), m.action("latched", "open")
    ('open', [('latched', 0.75, -1)], End(reason='the door latched'))
    >>> m.rows("open"), m.holds_rows("open"), m.has_force, m.slips, m.linear_events
    ([], True, False, False, False)

    A joint declares it from its parameters; the run then ends there:

    >>> import numpy as np, mbcomp
    >>> from mbcomp.library import World, Revolute, PointMass, FixedTranslation
    >>> class Door(Revolute):
    ...     def modes(self, p):
    ...         return Latch("open")
    >>> mdl = mbcomp.Model(); w = mdl.add("world", World(g=(0, 0, 0)))
    >>> j = mdl.add("hinge", Door(n=(0, 0, 1), phi0=0.0, w0=2.0))
    >>> rod = mdl.add("rod", FixedTranslation(r=(1.0, 0, 0))); bob = mdl.add("bob", PointMass(m=1.0))
    >>> mdl.connect(w.frame_b, j.frame_a); mdl.connect(j.frame_b, rod.frame_a); mdl.connect(rod.frame_b, bob.frame_a)
    >>> res = mbcomp.simulate(mdl, t_end=2.0, rtol=1e-10, atol=1e-12)
    >>> res.status, round(float(res.time[-1]), 9)          # 1 rad at 2 rad/s
    ('success', 0.5)
    >>> res.message.startswith("hinge: the door latched")
    True
    """

    has_force = False
    slips = False
    linear_events = False

    def __init__(self, start):
        if not isinstance(start, str):
            raise TypeError(f"Modes(start={start!r}): a start mode is the mode's name, a string -> fix: "
                            f"return {type(self).__name__}('free') (or the name of the mode the joint starts in) "
                            "from the joint's modes(p)")
        self.start = start

    def events(self, q, u, mode):
        """Event functions of the joint's own coordinates ``q`` and speeds ``u`` in ``mode``.

        Parameters
        ----------
        q, u : ndarray
            The joint's coordinates (rad or m) and speeds (rad/s or m/s).
        mode : str
            The current mode.

        Returns
        -------
        list of (str, value, int)
            ``(event, value, direction)``: ``value`` a float (its unit the function's), or a
            :class:`~mbcomp.modeling.events.ContactRow` / :class:`~mbcomp.modeling.events.SlipSpeed`
            the run evaluates; ``direction`` scipy's convention (-1 fires when the value falls
            through zero, +1 when it rises, 0 either way). Default: none.
        """
        return []

    def event_rows(self, mode):
        """The events of ``mode`` as :class:`~mbcomp.modeling.events.EventRow` (asked only
        when :attr:`linear_events`; :meth:`events` must give their values). Default: none."""
        return []

    def action(self, name, mode):
        """The action at event ``name`` in ``mode``: an :class:`~mbcomp.modeling.events.Impact`,
        :class:`~mbcomp.modeling.events.Switch` or :class:`~mbcomp.modeling.events.End`, or
        ``None`` (nothing happens). ``name`` is ``"release"`` when a row of the mode would have
        to pull, ``"break+"``/``"break-"`` when a :class:`~mbcomp.modeling.events.StickRow`'s
        push passes its limit, ``"slide"`` when a ``ContactRow``'s friction cone is left."""
        return None

    def rows(self, mode):
        """The unilateral rows held in ``mode``: ``[AxisRow | StickRow | ContactRow]``
        (:mod:`mbcomp.modeling.events`); default none."""
        return []

    def rest(self, name, mode):
        """The mode to settle in when event ``name`` chatters in ``mode`` (impacts ever closer
        in time), or ``None`` (default): the run then fails naming the joint."""
        return None

    def holds_rows(self, mode):
        """Whether the joint's own rows (a cut joint's ``constraints`` and its
        ``velocity_constraints``) are in the system in ``mode``: default True; an open
        one-sided contact: False (the body flies)."""
        return True

    def force(self, mode):
        """The generalized force (N or N m) the joint applies on its own speed in ``mode``
        (kinetic friction while slipping); 0 by default. Asked only when :attr:`has_force`."""
        return 0.0

    def slip_friction(self, mode):
        """The kinetic friction coefficient ``mu_k`` (1) of a contact sliding in ``mode``, or
        ``None`` where it does not slide (default). A sliding contact's rolling rows (its
        ``velocity_constraints``, along orthonormal tangents) are out of the system and the run
        applies ``-mu_k N`` against the slip velocity, ``N`` the push of its ``normal`` row
        (:mod:`mbcomp.hybrid.slip`). Asked only when :attr:`slips`."""
        return None

    def __repr__(self):
        return f"{type(self).__name__}(start={self.start!r})"
